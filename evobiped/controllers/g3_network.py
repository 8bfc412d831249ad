"""The G3 GO Gait Generator's cell equations (Pribe, Grossberg & Cohen 1997, eqs. 1-4), for any number of channels.

    dx_i/dt = -A x_i + (B - x_i)[f(x_i) + I_i] - (C + x_i) sum_j D_ij h_ij(I) g(y_j)   (1, 5)
    dy_i/dt = E[(1 - y_i)[x_i]^+ - y_i]                                                 (2, 6)
    f(w) = F1 [w]+^2 / (F2 + [w]+^2),   g(w) = G1 [w]+^2 / (G2 + [w]+^2)                  (4)

Our reading of the text: inhibition is D_ij g(y_j) (x_i is inhibited by y_j).
Time is in the model's dimensionless units; :func:`rk4_step` is one
fixed-step RK4 step, vectorised over a batch dimension B.  The G3 controller
(:mod:`evobiped.controllers.g3`) drives bodies with these cells; the paper's
quadruped network (its inhibition matrices, Table 1's modulation, GO lags) and
its published parameter sets are the experiment's
(:mod:`evobiped.experiments.g3.network`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

@dataclass(frozen=True, kw_only=True)
class Shunting:
    """The cell constants A-G2 of eqs. (1)-(4) (dimensionless)."""

    A: float = 1.0
    B: float = 1.1
    C: float = 2.5
    E: float = 1.5
    F1: float = 9.8
    F2: float = 0.5
    G1: float = 3.9
    G2: float = 0.5


def sigmoid_sq(w: np.ndarray, gain: float, half: float) -> np.ndarray:
    """Rectified sigmoid ``gain [w]+^2 / (half + [w]+^2)`` of eq. (4)."""
    wp = np.maximum(w, 0.0)
    w2 = wp * wp
    return gain * w2 / (half + w2)


def derivatives(c: Shunting, x: np.ndarray, y: np.ndarray, I: np.ndarray, D: np.ndarray):
    """Right-hand side of eqs. (1)-(2) (or (5)-(6) with D already modulated).

    x, y, I: ``(B, N)``; D: ``(B, N, N)``, D[b, i, j] inhibits x_i by g(y_j).
    Returns (dx/dt, dy/dt), each ``(B, N)``.
    """
    inh = np.einsum("bij,bj->bi", D, sigmoid_sq(y, c.G1, c.G2))
    dx = -c.A * x + (c.B - x) * (sigmoid_sq(x, c.F1, c.F2) + I) - (c.C + x) * inh
    dy = c.E * ((1.0 - y) * np.maximum(x, 0.0) - y)
    return dx, dy


def rk4_step(c: Shunting, x, y, I, D, h: float):
    """One classical RK4 step of length h with inputs I and D held constant."""
    k1x, k1y = derivatives(c, x, y, I, D)
    k2x, k2y = derivatives(c, x + 0.5 * h * k1x, y + 0.5 * h * k1y, I, D)
    k3x, k3y = derivatives(c, x + 0.5 * h * k2x, y + 0.5 * h * k2y, I, D)
    k4x, k4y = derivatives(c, x + h * k3x, y + h * k3y, I, D)
    return (x + (h / 6.0) * (k1x + 2 * k2x + 2 * k3x + k4x), y + (h / 6.0) * (k1y + 2 * k2y + 2 * k3y + k4y))


#: the cell constants each published parameter set uses, by its name (the G3 controller's ``preset`` option);
#: Figs. 5B, 7 and 8A lower B to 1.05, the others keep eqs. (1)-(4)'s defaults
CELLS: dict[str, Shunting] = {
    "fig4": Shunting(),
    "fig5a": Shunting(),
    "fig5b": Shunting(B=1.05),
    "fig7": Shunting(B=1.05),
    "fig8a": Shunting(B=1.05),
    "human": Shunting(),
    "human-lagged": Shunting(),
}
