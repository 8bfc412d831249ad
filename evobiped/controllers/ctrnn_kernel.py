"""The CTRNN's control step compiled (the episode's ``kernel``, :mod:`evobiped.core.kernel`): the same numbers as
:meth:`CTRNN.step <evobiped.controllers.ctrnn.CTRNN.step>`'s NumPy calls to the last bit, in one call without the GIL.

What makes it bit for bit: every weighted sum adds its products in NumPy's order (``row_dot``: from 0, i = 0, 1, ...;
a single output column as NumPy's sum does, from the first product), each elementwise expression is written as the
NumPy path writes it (the same operations in the same order, no fused multiply-adds), and every ``exp`` is NumPy's own
loop (:func:`evobiped.core.ufunc_calls.apply_loop`).  Importing this module imports numba.
"""

from __future__ import annotations

import numpy as np

from ..core.kernel import jit, ufunc_loop
from ..core.ufunc_calls import apply_loop


@jit
def _row_dot(x, M, out, rows):
    """``out[p, j] = sum_i x[p, i] M[p, i, j]`` as ``controllers.ctrnn.row_dot`` adds it, for the rows ``p`` where
    ``rows[p]`` (the others are left as they are): ``x`` ``(P, k)``, ``M`` ``(P, k, n)``, ``out`` ``(P, n)``.  Two or
    more columns: from 0, i = 0, 1, ... (einsum's order); one column: from the first product (the products' sum)."""
    P, k, n = M.shape
    for p in range(P):
        if not rows[p]:
            continue
        if n >= 2 or k == 0:
            for j in range(n):
                out[p, j] = 0.0
            first = 0
        else:
            for j in range(n):
                out[p, j] = x[p, 0] * M[p, 0, j]
            first = 1
        for i in range(first, k):  # each sum in the order of i, vectorised over j
            for j in range(n):
                out[p, j] += x[p, i] * M[p, i, j]


@jit
def _sigmoid_into(exp, A, alpha, tmp, O):
    """``O = 1 / (1 + exp(alpha - A))`` (``ctrnn._outputs_quiet``), ``tmp`` scratch, all ``(P, n)`` contiguous."""
    P, n = A.shape
    for p in range(P):
        for j in range(n):
            tmp[p, j] = alpha[p, j] - A[p, j]
    apply_loop(exp, tmp, tmp)
    for p in range(P):
        for j in range(n):
            O[p, j] = 1.0 / (1.0 + tmp[p, j])


@jit
def _step(exp, state, inputs, alpha, W, V, tau, substeps, dt, exponential, after, c, D, n_out):
    """One control period of ``P`` networks of ``n`` neurons: returns ``(A (P, n), motor outputs (P, n_out))``.

    ``state`` ``(P, n)`` activations, ``inputs`` ``(P, k)``, ``alpha`` ``(P, n)`` biases, ``W`` ``(P, n, n)``,
    ``V`` ``(P, k, n)`` input weights, ``tau`` ``(P, n)`` s, ``substeps`` ``(P,)`` (exponential), ``dt`` s;
    ``c`` ``(P, n_out)`` and ``D`` ``(P, k, n_out)``: the direct path (``D.shape[0] == 0``: none)."""
    P, n = state.shape
    k = inputs.shape[1]
    every, active = np.ones(P, np.bool_), np.ones(P, np.bool_)
    external = np.zeros((P, n))
    if k:
        _row_dot(inputs, V, external, every)
    tmp, O, net = np.empty((P, n)), np.empty((P, n)), np.empty((P, n))
    A = state.copy()
    if exponential:
        decay = np.empty((P, n))
        for p in range(P):
            for j in range(n):
                decay[p, j] = -(dt / substeps[p]) / tau[p, j]
        apply_loop(exp, decay, decay)
        for i in range(substeps.max()):
            _sigmoid_into(exp, A, alpha, tmp, O)
            for p in range(P):
                active[p] = i < substeps[p]
            _row_dot(O, W, net, active)
            for p in range(P):
                if active[p]:
                    for j in range(n):
                        s = net[p, j] + external[p, j] if k else net[p, j]
                        A[p, j] = s + (A[p, j] - s) * decay[p, j]
        _sigmoid_into(exp, A if after else state, alpha, tmp, O)
    else:
        _sigmoid_into(exp, state, alpha, tmp, O)
        _row_dot(O, W, net, every)
        for p in range(P):
            for j in range(n):
                s = net[p, j] + external[p, j] if k else net[p, j]
                A[p, j] = state[p, j] + (dt / tau[p, j]) * (s - state[p, j])
        if after:
            _sigmoid_into(exp, A, alpha, tmp, O)
    out = np.empty((P, n_out))
    if D.shape[0]:
        direct = np.zeros((P, n_out))
        _row_dot(inputs, D, direct, every)
        for p in range(P):
            for j in range(n_out):
                out[p, j] = O[p, j] + c[p, j] + direct[p, j]
    else:
        out[:] = O[:, :n_out]
    return A, out


_NO_DIRECT = (np.zeros((0, 0)), np.zeros((0, 0, 0)))


def step(ctrl, params: dict, state: np.ndarray, inputs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:meth:`CTRNN.step` of controller ``ctrl`` compiled: ``(A (P, n), motor outputs (P, n_outputs))``."""
    c, D = (params["c"], params["D"]) if ctrl.direct else _NO_DIRECT
    substeps = params["substeps"] if ctrl.exponential else np.zeros(0, np.int64)
    f = np.ascontiguousarray
    return _step(ufunc_loop(np.exp), f(state, float), f(inputs, float), f(params["alpha"]), f(params["W"]),
                 f(params["V"]), f(params["tau"]), substeps, ctrl.dt, ctrl.exponential, ctrl.outputs_after, f(c), f(D),
                 ctrl.n_outputs)
