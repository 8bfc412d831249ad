"""The numerical environment a result was made in, and whether another one can reproduce it bit for bit.

evobiped is deterministic: the same seed, the same versions and the same numerical environment give the same
result to the last bit, on any number of workers and backends.  The *numerical environment* is what decides the
last bits besides our own code:

- the MuJoCo and numpy versions;
- the SIMD kernels numpy dispatches at run time (``numpy_simd``: numpy picks AVX-512 kernels on a CPU that has
  them and AVX2 kernels elsewhere, and their last bits differ; ``NPY_DISABLE_CPU_FEATURES`` changes the choice);
- the CPU architecture and operating system.

Every run directory (``config.json``) and genome file records :func:`current` under the key ``environment``
(with the evobiped and Python versions, for the record).  :func:`differences` says which of the fields above
differ between a recorded environment and this process's; where none does, a replay must be bit-identical.
"""

from __future__ import annotations

import platform
import sys

from .. import __version__

#: the fields that decide the last bits of a simulation (see the module docstring)
NUMERICAL_FIELDS = ("mujoco", "numpy", "numpy_simd", "machine", "system")


def numpy_simd() -> list[str]:
    """The SIMD targets numpy dispatches to in this process (``np.show_runtime``'s "found"), e.g.
    ``['X86_V3', 'X86_V4', 'AVX512_ICL']`` on an AVX-512 CPU, ``['X86_V3']`` on an AVX2 one."""
    try:
        from numpy._core import _multiarray_umath as umath
    except ImportError:  # numpy < 2
        from numpy.core import _multiarray_umath as umath
    return [name for name in umath.__cpu_dispatch__ if umath.__cpu_features__.get(name)]


def current() -> dict:
    """This process's environment: ``evobiped``, ``python``, ``mujoco``, ``numpy`` (versions), ``numpy_simd``
    (list of str), ``machine`` (e.g. ``x86_64``) and ``system`` (e.g. ``Linux``)."""
    import mujoco
    import numpy

    return {
        "evobiped": __version__,
        "python": platform.python_version(),
        "mujoco": mujoco.__version__,
        "numpy": numpy.__version__,
        "numpy_simd": numpy_simd(),
        "machine": platform.machine(),
        "system": platform.system() or sys.platform,
    }


def differences(recorded: dict | None, now: dict | None = None) -> list[str]:
    """What differs between a ``recorded`` environment and ``now`` (default :func:`current`) among
    :data:`NUMERICAL_FIELDS`, one phrase each (``"numpy SIMD X86_V3 -> X86_V3, X86_V4, AVX512_ICL"``);
    ``["no environment recorded"]`` when ``recorded`` is missing.  Empty: a replay must be bit-identical."""
    if not isinstance(recorded, dict):
        return ["no environment recorded"]
    now = current() if now is None else now
    out = []
    for key in NUMERICAL_FIELDS:
        a, b = recorded.get(key), now.get(key)
        if a != b:
            show = lambda v: "none" if v is None else ", ".join(v) if isinstance(v, list) else str(v)  # noqa: E731
            label = "numpy SIMD" if key == "numpy_simd" else key
            out.append(f"{label} {show(a)} -> {show(b)}")
    return out
