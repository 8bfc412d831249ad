"""MuJoCo's C entry points called from compiled code: ``mj_step1``, ``mj_step2`` and ``mj_getState`` at addresses
found at run-time in the shared library the Python bindings loaded, so the code that calls them is cached like any
other."""

from __future__ import annotations

import ctypes
import functools
import glob
import os

import mujoco
from llvmlite import ir
from numba import types
from numba.extending import intrinsic

from ...core.kernel import jit

#: mj_getState's spec of the simulated time alone
TIME = int(mujoco.mjtState.mjSTATE_TIME)


@functools.cache
def _mujoco_library() -> ctypes.CDLL:
    """MuJoCo's shared library, the one the Python bindings loaded (its globals, callbacks and error handler)."""
    here = os.path.dirname(mujoco.__file__)
    found = sorted(glob.glob(os.path.join(here, "libmujoco.so*")) + glob.glob(os.path.join(here, "libmujoco*.dylib"))
                   + glob.glob(os.path.join(here, "mujoco.dll")))
    if not found:
        raise ImportError(f"MuJoCo's shared library is not in {here}")
    return ctypes.CDLL(found[0])


@functools.cache
def entry(name: str) -> int:
    """The address of MuJoCo's C function ``name``."""
    return ctypes.cast(getattr(_mujoco_library(), name), ctypes.c_void_p).value


@intrinsic
def call(typingctx, address, model, data):
    """``((void (*)(void *, void *)) address)(model, data)``: ``mj_step1`` and ``mj_step2`` at run-time addresses
    (all three integers), so the code that calls them is cached like any other."""
    def codegen(context, builder, signature, values):
        ptr = ir.IntType(8).as_pointer()
        fn = builder.inttoptr(values[0], ir.FunctionType(ir.VoidType(), [ptr, ptr]).as_pointer())
        builder.call(fn, [builder.inttoptr(v, ptr) for v in values[1:]])
        return context.get_dummy_value()

    return types.void(types.intp, types.intp, types.intp), codegen


@intrinsic
def read_state(typingctx, address, model, data, out, spec):
    """``mj_getState(model, data, out, spec)`` at a run-time address (``out`` an address of mjtNum)."""
    def codegen(context, builder, signature, values):
        ptr = ir.IntType(8).as_pointer()
        fn = builder.inttoptr(values[0], ir.FunctionType(ir.VoidType(), [ptr, ptr, ptr, ir.IntType(32)]).as_pointer())
        builder.call(fn, [builder.inttoptr(v, ptr) for v in values[1:4]] + [builder.trunc(values[4], ir.IntType(32))])
        return context.get_dummy_value()

    return types.void(types.intp, types.intp, types.intp, types.intp, types.intp), codegen


@jit
def time_of(address, model, data, out):
    """An mjData's simulated time (s), read through ``mj_getState`` into ``out`` ``(1,)``."""
    read_state(address, model, data, out.ctypes.data, TIME)
    return out[0]
