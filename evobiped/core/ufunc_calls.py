"""NumPy's own float64 inner loops called from compiled code (:func:`evobiped.core.kernel.ufunc_loop` finds them):
importing this module imports numba, so only a compiled kernel does."""

from __future__ import annotations

import numpy as np
from llvmlite import ir
from numba import njit, types
from numba.extending import intrinsic


@intrinsic
def _call_loop(typingctx, address, args, dimensions, steps):
    """``((void (*)(char **, npy_intp *, npy_intp *, void *)) address)(args, dimensions, steps, NULL)``: a ufunc inner
    loop at a run-time address (all four integers), so a function that calls it is cached like any other."""
    def codegen(context, builder, signature, values):
        ptr = ir.IntType(8).as_pointer()
        fn = builder.inttoptr(values[0], ir.FunctionType(ir.VoidType(), [ptr] * 4).as_pointer())
        builder.call(fn, [builder.inttoptr(v, ptr) for v in values[1:]] + [ir.Constant(ptr, None)])
        return context.get_dummy_value()

    return types.void(types.intp, types.intp, types.intp, types.intp), codegen


@intrinsic
def call_scalar2(typingctx, address, x, y):
    """``((double (*)(double, double)) address)(x, y)``: the C function behind a generic binary loop
    (:func:`evobiped.core.kernel.ufunc_scalar2`), at a run-time address."""
    def codegen(context, builder, signature, values):
        d = ir.DoubleType()
        fn = builder.inttoptr(values[0], ir.FunctionType(d, [d, d]).as_pointer())
        return builder.call(fn, values[1:])

    return types.float64(types.intp, types.float64, types.float64), codegen


@njit(cache=True, nogil=True)
def apply_loop(loop: int, x: np.ndarray, out: np.ndarray) -> None:
    """``out[:] = f(x)`` by NumPy's inner loop at address ``loop`` of a unary float64 ufunc f: ``x`` and ``out``
    contiguous float64 arrays of the same size (any shape; ``out`` may be ``x``); the same bits as ``f(x)`` in NumPy."""
    io = np.empty(5, np.intp)  # args (2 pointers), dimensions (1), steps (2): what a ufunc loop is handed
    io[0], io[1], io[2], io[3], io[4] = x.ctypes.data, out.ctypes.data, x.size, 8, 8
    _call_loop(loop, io.ctypes.data, io[2:].ctypes.data, io[3:].ctypes.data)


@njit(cache=True, nogil=True)
def apply_loop2(loop: int, x: np.ndarray, y: np.ndarray, out: np.ndarray) -> None:
    """``out[:] = f(x, y)`` by NumPy's inner loop at address ``loop`` of a binary float64 ufunc f (``np.arctan2``,
    ``np.hypot``): contiguous float64 arrays of one size (``out`` may be either); the same bits as ``f(x, y)``."""
    io = np.empty(7, np.intp)  # args (3 pointers), dimensions (1), steps (3)
    io[0], io[1], io[2], io[3] = x.ctypes.data, y.ctypes.data, out.ctypes.data, x.size
    io[4], io[5], io[6] = 8, 8, 8
    _call_loop(loop, io.ctypes.data, io[3:].ctypes.data, io[4:].ctypes.data)
