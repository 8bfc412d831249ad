"""Runs of the G3 network on its own (Pribe, Grossberg & Cohen 1997): GO schedules, integration, GO-level sweeps.

The cell equations are the core's (:mod:`evobiped.controllers.g3_network`, which the G3
controller drives bodies with), the quadruped network and the published presets are in
:mod:`evobiped.experiments.g3.network`; this module integrates a network under a GO schedule, as the paper's
figures do, and sweeps GO levels with the gait analysis of
:mod:`evobiped.experiments.g3.gaits`.

Integration is fixed-step RK4 (default dt = 0.005) on the uniform grid k dt;
a step that contains a change of input (a GO change arriving at some channel)
is split there, so the piecewise-constant inputs are integrated exactly and
the lags, even those far below dt (Fig. 8A: 0.00025), act as published.
Everything is vectorised over a batch dimension B (e.g. many GO levels at once).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...controllers.g3_network import rk4_step
from ...core.errors import ConfigError
from .gaits import analyse_gait
from .network import G3Network, Preset


@dataclass
class OscillatorTrace:
    """Sampled states: t ``(T,)``, x and y ``(B, T, N)``, the command GO level ``(B, T)``."""

    t: np.ndarray
    x: np.ndarray
    y: np.ndarray
    go: np.ndarray


def go_schedule(levels, times=None) -> tuple[np.ndarray, np.ndarray]:
    """A GO schedule: ``levels`` ``(B,)`` or ``(B, K)`` switched on at ``times`` ``(K,)``.

    Level k holds from times[k] to times[k+1]; the GO signal is 0 before times[0].
    Returns (times ``(K,)``, levels ``(B, K)``).  Negative levels -> ConfigError.
    """
    lv = np.asarray(levels, float)
    if lv.ndim == 1:
        lv = lv[:, None]
    tm = np.zeros(1) if times is None else np.asarray(times, float).ravel()
    if lv.ndim != 2 or lv.shape[1] != tm.size or lv.size == 0:
        raise ConfigError("G3: GO schedule needs one level per switching time")
    if not np.all(np.isfinite(lv)) or (lv < 0).any():
        raise ConfigError(f"G3: GO levels must be finite and >= 0, got {lv.min():g}")
    if tm.size > 1 and np.any(np.diff(tm) <= 0):
        raise ConfigError("G3: GO switching times must increase")
    return tm, lv


def simulate(net: G3Network, schedule, t_end: float, *, dt: float = 0.005, sample_dt: float = 0.025,
             state=None) -> OscillatorTrace:
    """Integrate ``net`` from t = 0 to ``t_end`` under a GO ``schedule`` (see :func:`go_schedule`).

    state: optional (x, y) ``(B, N)`` initial state (default zeros: the paper's
    reset).  Samples are taken every ``sample_dt`` (a multiple of dt).
    """
    times, levels = schedule
    if not (dt > 0 and t_end > 0):
        raise ConfigError("G3: dt and t_end must be > 0")
    stride = int(round(sample_dt / dt))
    if stride < 1 or abs(stride * dt - sample_dt) > 1e-9 * sample_dt:
        raise ConfigError(f"G3: sample_dt {sample_dt} must be a multiple of dt {dt}")
    Bn, N = levels.shape[0], net.n
    lags = np.asarray(net.lags, float)
    delta = np.asarray(net.delta, float)
    c = net.cells
    if state is None:
        x, y = np.zeros((Bn, N)), np.zeros((Bn, N))
    else:
        x, y = (np.array(s, float) for s in state)
    # every instant at which some channel's input (or the command level) changes
    events = np.unique(np.concatenate([times, (times[:, None] + lags[None, :]).ravel()]))

    def inputs_at(t: float):
        """Right-continuous inputs on [t, next event): per-channel I (B, N), D (B, N, N), command (B,)."""
        arrived = times[None, :] + lags[:, None] <= t + 1e-12  # (N, K)
        idx = arrived.sum(axis=1) - 1  # latest change seen by each channel
        I = np.where(idx[None, :] >= 0, levels[:, np.maximum(idx, 0)], 0.0)
        I = I + np.where(idx >= 0, delta, 0.0)[None, :]
        kc = int(np.sum(times <= t + 1e-12)) - 1
        cmd = levels[:, kc] if kc >= 0 else np.zeros(Bn)
        return I, net.inhibition(cmd), cmd

    n_steps = int(round(t_end / dt))
    n_samples = n_steps // stride + 1
    check_size(n_steps, Bn * n_samples * (2 * N + 1) * 8, t_end, dt)
    xs = np.empty((Bn, n_samples, N))
    ys = np.empty((Bn, n_samples, N))
    gos = np.empty((Bn, n_samples))
    I, D, cmd = inputs_at(0.0)
    xs[:, 0], ys[:, 0], gos[:, 0] = x, y, cmd
    ev = 0
    while ev < events.size and events[ev] <= 1e-12:
        ev += 1
    for k in range(n_steps):
        t0, t1 = k * dt, (k + 1) * dt
        t = t0
        while ev < events.size and events[ev] < t1 - 1e-12:  # split at input changes
            te = events[ev]
            if te - t > 1e-15:
                x, y = rk4_step(c, x, y, I, D, te - t)
            t = te
            I, D, cmd = inputs_at(t)
            ev += 1
        x, y = rk4_step(c, x, y, I, D, t1 - t)
        if ev < events.size and abs(events[ev] - t1) <= 1e-12:
            I, D, cmd = inputs_at(t1)
            ev += 1
        if (k + 1) % stride == 0:
            s = (k + 1) // stride
            xs[:, s], ys[:, s], gos[:, s] = x, y, cmd
    return OscillatorTrace(t=np.arange(n_samples) * stride * dt, x=xs, y=ys, go=gos)


#: the most RK4 steps one run integrates (the paper's runs: 24,000 to 40,000)
MAX_STEPS = 10**7


def check_size(steps: int, trace_bytes: float, t_end: float, dt: float) -> None:
    """ConfigError before a run of ``steps`` RK4 steps (``t_end`` time units at ``dt``) whose trace takes
    ``trace_bytes`` bytes: at most :data:`MAX_STEPS` steps, in a quarter of this machine's memory."""
    import os

    if steps > MAX_STEPS:
        raise ConfigError(f"G3: a run of {t_end:g} time units at dt {dt:g} takes {steps:.3g} RK4 steps, more than "
                          f"{MAX_STEPS:.0e}: a shorter --t-run or a larger --dt")
    room = os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE") / 4
    if trace_bytes > room:
        raise ConfigError(f"G3: the run's trace would take {trace_bytes / 2**30:.3g} GiB, more than this machine can "
                          "hold "
                          f"({room / 2**30:.3g} GiB): fewer GO levels or a shorter --t-run")


# ------------------------------------------------------------------ sweeps
@dataclass
class GoSweep:
    """GO levels ``(L,)`` with the steady gait at each and the run behind it.

    reset: trajectory row l holds level l (from zero state, or after ``from_go``);
    continue: one row steps through the levels, ``t_run`` each.
    start[l]: when level l was switched on; gaits[l].settle_time is relative to it.
    """

    levels: np.ndarray
    gaits: list
    traj: OscillatorTrace
    rows: np.ndarray
    start: np.ndarray
    end: np.ndarray


def go_sweep(p: Preset, levels, *, mode: str = "reset", t_run: float | None = None, from_go: float | None = None,
          switch_at: float = 30.0, dt: float = 0.005, sample_dt: float = 0.025, window: float = 0.4) -> GoSweep:
    """Run ``p`` at each GO level and analyse the last ``window`` of each level's hold.

    mode "reset": every level from zero initial conditions (a batch); with
    ``from_go`` each row first runs at ``from_go`` until ``switch_at`` (Figs. 8B,
    10).  mode "continue": one run through the levels in order, state kept.
    """
    lv = np.asarray(levels, float).ravel()
    if lv.size == 0:
        raise ConfigError("G3: no GO levels given")
    if mode not in ("reset", "continue"):
        raise ConfigError(f"G3: sweep mode must be 'reset' or 'continue', got {mode!r}")
    if not 0 < window <= 1:
        raise ConfigError("G3: window must be in (0, 1]")
    t_run = float(p.t_run if t_run is None else t_run)
    if mode == "reset":
        if from_go is None:
            sched, t0 = go_schedule(lv), 0.0
        else:
            sched, t0 = go_schedule(np.stack([np.full_like(lv, from_go), lv], 1), [0.0, switch_at]), float(switch_at)
        traj = simulate(p.network, sched, t0 + t_run, dt=dt, sample_dt=sample_dt)
        rows, start = np.arange(lv.size), np.full(lv.size, t0)
    else:
        times = np.arange(lv.size) * t_run
        if from_go is not None:
            times, lv_s = np.concatenate([[0.0], times + switch_at]), np.concatenate([[from_go], lv])
        else:
            lv_s = lv
        traj = simulate(p.network, go_schedule(lv_s[None, :], times), times[-1] + t_run, dt=dt, sample_dt=sample_dt)
        rows, start = np.zeros(lv.size, int), times[-lv.size:]
    end = start + t_run
    out = []
    for r, a, b in zip(rows, start, end):
        m = (traj.t >= a - 1e-9) & (traj.t <= b + 1e-9)
        g = analyse_gait(traj.t[m], traj.x[r][m], t_start=b - window * t_run)
        g.settle_time -= a
        out.append(g)
    return GoSweep(levels=lv, gaits=out, traj=traj, rows=rows, start=start, end=end)
