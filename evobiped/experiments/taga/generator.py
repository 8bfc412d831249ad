"""Taga's rhythm generator alone (Fig. 6B: no feedback, no body) and the periods of its oscillators, alone and
entrained by walking (claim 7)."""

from __future__ import annotations

import numpy as np

from ...controllers.matsuoka import Matsuoka
from .parameters import preset_genome
from .walking import TagaWalker


def isolated_activity(u0: float = 5.5, *, seconds: float = 10.0, initial_u: float = 0.1,
                      timestep: float = 0.0005) -> tuple[np.ndarray, np.ndarray]:
    """Fig. 6B: the rhythm generator alone (Feed = 0): times (T,) s and inner states u (T, 12)."""
    ctrl = Matsuoka(n_outputs=6, u0=u0, feedback="none", initial_u=initial_u).bound(timestep)
    params = ctrl.decode(preset_genome(ctrl)[None])
    state = ctrl.initial_state(params)
    n = int(round(seconds / timestep))
    u = np.empty((n, ctrl.n))
    empty = np.zeros((1, 0))
    for i in range(n):
        state, _ = ctrl.step(params, state, empty)
        u[i] = state["u"][0]
    return np.arange(1, n + 1) * timestep, u


def isolated_period(u0: float = 5.5, *, seconds: float = 10.0, **kw) -> float:
    """Period (s) of the isolated generator's hip oscillator (u_flexor - u_extensor), second half of the run."""
    t, u = isolated_activity(u0, seconds=seconds, **kw)
    return period_of(t, u[:, 0] - u[:, 1], t_start=seconds / 2)


def period_of(t: np.ndarray, x: np.ndarray, *, t_start: float = 0.0) -> float:
    """Median interval (s) between upward zero crossings of ``x`` after ``t_start``; nan if < 2."""
    up = np.flatnonzero((x[1:] > 0) & (x[:-1] <= 0)) + 1
    up = up[t[up] >= t_start]
    return float(np.median(np.diff(t[up]))) if len(up) > 1 else float("nan")


def walking_hip_period(w: TagaWalker, *, t_start: float, p: int = 0) -> float:
    """Period (s) of walker p's right hip oscillator (u_1 - u_2) in its trace."""
    a = w.trace.arrays()
    return period_of(a["t"], a["u"][:, p, 0] - a["u"][:, p, 1], t_start=t_start)
