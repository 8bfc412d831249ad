"""evobiped: evolve neural controllers for bipedal walkers in MuJoCo.

Data flows one way: genome -> controller params -> episode (body + controller
+ task) -> fitness -> GA.  See README.md for the commands.
"""

import _signal  # the C module: Python's signal module first imports enum, 30 ms
import os as _os
import sys as _sys


def _interrupted_while_starting(signum, frame) -> None:
    """The evobiped command's Ctrl-C before its ``main`` takes over (while Python imports it): one line, exit
    status 130, nothing written yet (``evobiped.cli.main`` puts Python's own handler back)."""
    _os.write(2, b"evobiped: interrupted\n")
    _os._exit(128 + signum)


#: the least address space (bytes, ``ulimit -v`` times 1024) the command starts in: ``evobiped presets`` ran from
#: 240,000 KiB, a 0.5 s ``evobiped episode`` from 450,000-470,000 KiB (below it, failed or aborted by turns: NumPy's
#: OpenBLAS, MuJoCo's library, numba's LLVM and Rerun each stop in their own words); 512 MiB leaves a margin
MIN_ADDRESS_SPACE = 512 * 2**20


def _refuse_little_address_space() -> None:
    """The evobiped command under an address-space limit (``ulimit -v``) below :data:`MIN_ADDRESS_SPACE`: one line,
    exit status 2, before NumPy or MuJoCo is loaded (they would end in their own abort messages)."""
    import resource

    soft = resource.getrlimit(resource.RLIMIT_AS)[0]
    if soft != resource.RLIM_INFINITY and soft < MIN_ADDRESS_SPACE:
        need = MIN_ADDRESS_SPACE // 1024
        _os.write(2, f"evobiped: error: this process may take {soft // 1024:,} KiB of address space (ulimit -v "
                     f"{soft // 1024}), below the {need:,} KiB (512 MiB) evobiped needs to load NumPy and MuJoCo; "
                     f"raise the limit (ulimit -v {need}) or lift it (ulimit -v unlimited)\n".encode())
        _os._exit(2)


# first thing, before any import: in the command's own process (the console script, or `python -m evobiped`)
if _sys.argv[:1] == ["-m"] or _os.path.basename(_sys.argv[0] if _sys.argv else "") == "evobiped":
    if _signal.getsignal(_signal.SIGINT) is _signal.default_int_handler:
        _signal.signal(_signal.SIGINT, _interrupted_while_starting)
    _refuse_little_address_space()

from .core.glbackend import choose as _choose_gl  # noqa: E402

_choose_gl()  # before anything imports mujoco: MuJoCo reads MUJOCO_GL once, at its import

__version__ = "0.1.0"
