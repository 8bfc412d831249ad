"""Compiled per-tick code that gives NumPy's numbers to the last bit: the episode's ``kernel`` option.

The control tick's array work (a controller's step, a body's senses) can run as numba-compiled loops
(``@njit(cache=True, nogil=True)``, :func:`jit`) instead of NumPy calls.  Elementwise IEEE operations (+, -, *, /,
sqrt, comparisons) give the same bits in both; sums do when the compiled loop adds in NumPy's order (each kernel's
test holds it to NumPy's); transcendental functions do not in general: NumPy's SIMD ``exp`` and ``arcsin``
(AVX-512 on this machine) differ from the C library's, which numba calls, in the last bit of one value in ten
or twenty.  So a kernel takes those from NumPy itself: :func:`ufunc_loop` finds the float64 inner loop NumPy runs
for ``np.exp(x)`` (the one its CPU dispatch chose at import), and compiled code calls it through
:func:`evobiped.core.ufunc_calls.apply_loop`, so a compiled transcendental is NumPy's on every machine.  The
loop is checked against the ufunc on a probe of values when it is found; where it cannot be found or disagrees, the
compiled kernel is unavailable (``kernel = "numpy"`` then runs, with the same numbers).

Kernels: ``numpy`` (the NumPy calls), ``compiled`` (numba; refused with one line where numba or the loops are
missing), ``auto`` (compiled where available, else numpy: the default, as both give the same numbers).
"""

from __future__ import annotations

import ctypes
import functools
import hashlib
import importlib
from pathlib import Path

import numpy as np

from .errors import ConfigError, signals_deferred

KERNELS = ("auto", "compiled", "numpy")
#: the inner loop's C signature: ``void loop(char **args, npy_intp *dimensions, npy_intp *steps, void *data)``, its
#: pointers passed as integers (the same registers on every 64-bit ABI numba targets)
LOOP = ctypes.CFUNCTYPE(None, ctypes.c_ssize_t, ctypes.c_ssize_t, ctypes.c_ssize_t, ctypes.c_ssize_t)
_NPY_DOUBLE = 12


class _UFunc(ctypes.Structure):
    """The head of NumPy's ``PyUFuncObject`` (numpy/ufuncobject.h), up to its type signatures."""

    _fields_ = [("ob_refcnt", ctypes.c_ssize_t), ("ob_type", ctypes.c_void_p), ("nin", ctypes.c_int),
                ("nout", ctypes.c_int),
                ("nargs", ctypes.c_int), ("identity", ctypes.c_int), ("functions", ctypes.POINTER(ctypes.c_void_p)),
                ("data", ctypes.POINTER(ctypes.c_void_p)), ("ntypes", ctypes.c_int), ("reserved1", ctypes.c_int),
                ("name", ctypes.c_char_p), ("types", ctypes.POINTER(ctypes.c_char))]


def _probe(ufunc: np.ufunc) -> list[np.ndarray]:
    """Arguments that exercise a float64 loop: its SIMD body and tail, edges, infinities, NaN."""
    rng = np.random.default_rng(12345)
    if ufunc is np.arcsin:
        x = np.concatenate([rng.uniform(-1, 1, 4099), [-1.0, 1.0, 0.0, -0.0, 1e-300, 0.5, np.nan]])
    elif ufunc.nin == 2:  # arctan2, hypot: every quadrant, both scales, signed zeros, infinities, NaN
        edge = np.array([0.0, -0.0, 1.0, -1.0, np.inf, -np.inf, np.nan, 1e-300])
        x = np.concatenate([rng.normal(size=4099) * 10.0 ** rng.integers(-3, 4, 4099), np.repeat(edge, len(edge))])
        y = np.concatenate([rng.normal(size=4099) * 10.0 ** rng.integers(-3, 4, 4099), np.tile(edge, len(edge))])
        return [x, y]
    else:
        x = np.concatenate([rng.uniform(-40, 40, 4099), rng.uniform(-800, 800, 1001),
                            [0.0, -0.0, np.inf, -np.inf, np.nan]])
    return [x]


def _float64_entry(ufunc: np.ufunc, nins: tuple[int, ...]) -> tuple[_UFunc, int] | None:
    """``ufunc``'s head and the index of its first all-float64 type signature, where its head is one this reads
    (its name, ``nin`` among ``nins``, one output, its type count); None otherwise."""
    u = _UFunc.from_address(id(ufunc))
    if (u.name != ufunc.__name__.encode() or u.nin not in nins or u.nin != ufunc.nin or u.nout != 1
            or u.ntypes != len(ufunc.types)):
        return None
    for i in range(u.ntypes):
        if all(b == _NPY_DOUBLE for b in u.types[i * u.nargs:(i + 1) * u.nargs]):
            return u, i
    return None


@functools.cache
def ufunc_loop(ufunc: np.ufunc) -> int | None:
    """The address of NumPy's float64 inner loop of ``ufunc``, unary (``np.exp``, ``np.arcsin``) or binary
    (``np.arctan2``, ``np.hypot``): the one ``ufunc(x)`` (``ufunc(x, y)``) runs for contiguous float64 arguments (the
    first float64 loop in its type list), checked to the last bit against ``ufunc`` on a probe; None where NumPy's
    layout or loop is not what this expects.  Compiled code calls it through
    :func:`evobiped.core.ufunc_calls.apply_loop` (:func:`~evobiped.core.ufunc_calls.apply_loop2`)."""
    try:
        found = _float64_entry(ufunc, (1, 2))
        if found is None:
            return None
        u, i = found
        if not u.functions[i] or u.data[i]:  # a loop that needs its data pointer is not one this calls
            return None
        address = int(u.functions[i])
    except (ValueError, TypeError, OverflowError):
        return None
    given = _probe(ufunc)
    out = np.empty_like(given[0])
    pointers = [a.ctypes.data for a in given] + [out.ctypes.data]
    args = np.array(pointers + [len(out)] + [8] * len(pointers), np.intp)
    n = len(pointers)
    with np.errstate(all="ignore"):
        LOOP(address)(args.ctypes.data, args[n:].ctypes.data, args[n + 1:].ctypes.data, 0)
        want = ufunc(*given)
    return address if np.array_equal(out.view(np.int64), want.view(np.int64)) else None


#: ``double f(double, double)``: the scalar function a generic binary loop calls (its data pointer)
SCALAR2 = ctypes.CFUNCTYPE(ctypes.c_double, ctypes.c_double, ctypes.c_double)


@functools.cache
def ufunc_scalar2(ufunc: np.ufunc) -> int | None:
    """For a binary ufunc whose float64 loop is NumPy's generic one over a C function (``np.hypot``: ``npy_hypot``,
    handed to the loop as its data), that function's address, checked to the last bit against ``ufunc`` on a probe;
    None where the loop is another kind (then :func:`ufunc_loop` has it).  Compiled code calls it through
    :func:`evobiped.core.ufunc_calls.call_scalar2`."""
    try:
        found = _float64_entry(ufunc, (2,))
        if found is None or not found[0].data[found[1]]:
            return None
        address = int(found[0].data[found[1]])
    except (ValueError, TypeError, OverflowError):
        return None
    x, y = _probe(ufunc)
    f = SCALAR2(address)
    got = np.array([f(a, b) for a, b in zip(x.tolist(), y.tolist())])
    with np.errstate(all="ignore"):
        want = ufunc(x, y)
    return address if np.array_equal(got.view(np.int64), want.view(np.int64)) else None


@functools.cache
def unavailable() -> str | None:
    """Why the compiled kernel cannot run here (one line), or None where it can."""
    try:
        with signals_deferred():  # a Ctrl-C inside LLVM's start-up can crash the process on its way out: after it
            importlib.import_module("numba")
    except ImportError:
        return "the compiled kernel needs numba (pip install numba, a dependency of evobiped)"
    for f in (np.exp, np.arcsin, np.arctan2, np.remainder):
        if ufunc_loop(f) is None:
            return f"the compiled kernel could not find NumPy {np.__version__}'s own float64 {f.__name__} loop"
    if ufunc_scalar2(np.hypot) is None:
        return f"the compiled kernel could not find the C function behind NumPy {np.__version__}'s float64 hypot"
    return None


#: bytes of address space below which ``auto`` runs NumPy: numba's compiler (LLVM) reserves gigabytes of address
#: space, and under ``ulimit -v 600000`` it spun without end on a cold cache instead of failing
COMPILE_ADDRESS_SPACE = 4 * 2**30


def _address_space_short() -> bool:
    """This process's address space is limited below :data:`COMPILE_ADDRESS_SPACE` (``ulimit -v``)."""
    try:
        import resource
    except ImportError:  # not POSIX: no such limit
        return False
    soft = resource.getrlimit(resource.RLIMIT_AS)[0]
    return soft != resource.RLIM_INFINITY and soft < COMPILE_ADDRESS_SPACE


def compiled(kernel: str, where: str = "episode.kernel") -> bool:
    """Whether ``kernel`` (one of :data:`KERNELS`) runs compiled here; ConfigError (one line) for an unknown one and for
    ``compiled`` where it is unavailable.  ``auto`` runs NumPy (the same numbers) where the address space is limited
    below :data:`COMPILE_ADDRESS_SPACE`."""
    if kernel not in KERNELS:
        raise ConfigError(f"{where}: unknown kernel {kernel!r} (choose from {', '.join(KERNELS)})")
    if kernel == "numpy" or (kernel == "auto" and _address_space_short()):
        return False
    why = unavailable()
    if why is not None and kernel == "compiled":
        raise ConfigError(f"{where}: {why}; kernel 'numpy' gives the same numbers")
    return why is None


def jit(fn):
    """``numba.njit(cache=True, nogil=True)``: compiled once per machine (the cache beside the module), runs without
    the GIL.  The cache is keyed on every source file of the package (:func:`package_stamp`), not only on the
    function's own: compiled code inlines the functions it calls and the constants it reads from other modules, and
    numba's own key would keep a stale copy of them after an edit or an upgrade."""
    with signals_deferred():
        import numba

    dispatcher = numba.njit(nogil=True)(fn)
    cache = _package_keyed_cache()
    if cache is None:  # a numba whose cache classes are not the ones known here: its own key
        dispatcher.enable_caching()
    else:
        dispatcher._cache = cache(fn)
    return dispatcher


@functools.cache
def package_stamp() -> str:
    """A hash of every Python source file of the package (their paths and contents)."""
    root = Path(__file__).resolve().parents[1]
    digest = hashlib.sha256()
    for path in sorted(root.rglob("*.py")):
        digest.update(path.relative_to(root).as_posix().encode() + b"\0" + path.read_bytes())
    return digest.hexdigest()


@functools.cache
def _package_keyed_cache():
    """numba's function cache with :func:`package_stamp` added to each locator's source stamp (None where this
    numba's cache classes differ from the ones known here)."""
    try:
        from numba.core import caching

        bases = (caching.UserProvidedCacheLocator, caching.InTreeCacheLocator, caching.UserWideCacheLocator)
        impl, cache = caching.CompileResultCacheImpl, caching.FunctionCache
    except (ImportError, AttributeError):
        return None

    class Stamped:
        def get_source_stamp(self):
            return super().get_source_stamp(), package_stamp()

    locators = [type(f"Package{b.__name__}", (Stamped, b), {}) for b in bases]
    return type("PackageKeyedCache", (cache,), {"_impl_class": type("PackageKeyedImpl", (impl,),
                                                                       {"_locator_classes": locators})})
