"""Taga et al. 1991 experiments: the Taga biped driven by its Matsuoka rhythm generator.

A :class:`TagaWalker` is a batch of P walkers (one genome each, u_0 per walker)
that can be advanced in pieces, so an experiment can change u_0, push the body,
or continue from a steady state (the u_0 sweeps of Fig. 11).  Every physics
step: sensors -> rhythm generator (eq. 6) -> torques -> Appendix A forces ->
MuJoCo step: one :class:`evobiped.episode.Episode` (walk task, the controller
stepped at the physics step) continued by :meth:`Episode.advance`.
Trajectories are sampled every ``record_every`` steps; :meth:`TagaWalker.metrics`
reduces them with :mod:`evobiped.experiments.taga.stride`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from typing import Callable

import numpy as np

from ...bodies.taga import TagaBiped
from ...controllers.matsuoka import FEEDBACK_SENSORS, Matsuoka, MatsuokaOptions
from ...errors import UserError
from ...episode import Episode
from ...options import check_value
from ...sim import Sims
from ...tasks.walk import WalkTask
from .parameters import PRESETS, preset_genome
from .stride import StrideMetrics, analyse_strides


#: where Fig. 7's horizontal pushes act: the hip (its point mass) or a shank's centre
PUSH_TARGETS = ("none", "hip", "right_shank", "left_shank")


def set_push(sims: Sims, ids: np.ndarray, target: str, force: float) -> None:
    """From now on a horizontal force ``force`` (N, forward > 0) on ``target`` of walkers ``ids`` (``"none"``
    stops it): MuJoCo's applied force at the body's centre of mass, which is the hip's point mass and a
    uniform shank's centre."""
    if target not in PUSH_TARGETS:
        raise UserError(f"push target must be one of {PUSH_TARGETS}, got {target!r}")
    for name in PUSH_TARGETS[1:]:
        sims.xfrc_applied[ids, sims.model.body(name).id, :3] = 0.0
    if target != "none":
        sims.xfrc_applied[ids, sims.model.body(target).id, 0] = float(force)


def check_u0(u0: float) -> float:
    """``u0`` as the matsuoka controller's option declares it (ConfigError otherwise)."""
    return float(check_value(MatsuokaOptions, "u0", float(u0), "u0"))


@dataclass
class Trace:
    """Sampled trajectory of P walkers: ``t`` (T,), the rest ``(T, P, ...)``."""

    t: list = field(default_factory=list)
    hip: list = field(default_factory=list)  # (P, 2) x, height above terrain
    contact: list = field(default_factory=list)  # (P, 2) right, left
    ankle: list = field(default_factory=list)  # (P, 2, 2)
    knee: list = field(default_factory=list)  # (P, 2, 2)
    hip_z: list = field(default_factory=list)  # (P,) absolute hip z
    u: list = field(default_factory=list)  # (P, 12) neuron inner states (internal order)

    def arrays(self) -> dict[str, np.ndarray]:
        return {k: np.array(v) for k, v in self.__dict__.items()}


class TagaWalker:
    """P Taga bipeds with their rhythm generators: one :class:`~evobiped.episode.Episode` (walk task)
    continued piece by piece, its trajectory sampled every ``record_every`` physics steps."""

    def __init__(
        self,
        u0,
        *,
        preset: str = "taga",
        feedback: bool = True,
        timestep: float = 0.0005,
        record_every: int = 4,
        progress: Callable[[float], None] | None = None,
        **body_options,
    ):
        """``progress(t)`` (optional) is called with the simulated time (s) every 1000 physics steps."""
        if preset not in PRESETS:
            raise UserError(f"unknown preset {preset!r} (choose from {', '.join(PRESETS)})")
        u0 = np.atleast_1d(np.asarray(u0, float))
        for v in u0:
            check_u0(v)
        body = TagaBiped(timestep=timestep, **body_options)
        inputs = dict(FEEDBACK_SENSORS) if feedback else {}
        ctrl = Matsuoka(n_outputs=6, inputs=inputs, actuators=TagaBiped.actuators, u0=float(u0[0]))
        # open-ended: the episode's planned length (one step) only fills end_time for walkers still up
        self.episode = Episode(body, ctrl, WalkTask(), seconds=timestep, stop_on_fall=True)
        self.body, self.ctrl, self.model, self.P = body, self.episode.controller, self.episode.model, len(u0)
        self.state = self.episode.start(np.tile(preset_genome(ctrl, preset), (self.P, 1)))
        self.sims, self.params = self.state.sims, self.state.params
        self.params["u0"] = u0[:, None].copy()
        self.record_every = int(record_every)
        self.progress = progress
        self.trace = Trace()
        self._record()

    @property
    def time(self) -> float:
        return self.state.time

    @property
    def alive(self) -> np.ndarray:
        return self.state.alive

    @property
    def unstable(self) -> np.ndarray:
        return self.state.unstable

    @property
    def fell_at(self) -> np.ndarray:
        """``(P,)`` s when each walker fell, nan while it is up."""
        return np.where(self.state.fell, self.state.end_time, np.nan)

    def set_u0(self, u0) -> None:
        u0 = np.broadcast_to(np.asarray(u0, float), (self.P,))
        for v in u0:
            check_u0(v)
        self.params["u0"][:, 0] = u0

    def advance(self, seconds: float) -> None:
        """Simulate ``seconds`` more (walkers that fell stay where they fell)."""
        self.episode.advance(self.state, seconds, listener=self)

    def tick(self, t, sims, ids, neurons, action, task_state) -> None:
        """The episode's listener: samples the trace, reports progress."""
        steps = self.state.ticks
        if steps % self.record_every == 0:
            self._record()
        if self.progress is not None and steps % 1000 == 0:
            self.progress(self.time)

    def _record(self) -> None:
        k = self.body.links(self.sims)
        tr = self.trace
        tr.t.append(self.time)
        tr.hip.append(np.stack([k["hip"][:, 0], self.body.hip_height(self.sims)], 1))
        tr.hip_z.append(k["hip"][:, 1].copy())
        tr.contact.append(self.body.sensors(self.sims)["ground_contact"] > 0)
        tr.ankle.append(k["ankle"].copy())
        tr.knee.append(k["knee"].copy())
        tr.u.append(self.state.controller["u"].copy())

    def metrics(self, *, t_start: float | None = None, t_end: float | None = None) -> list[dict]:
        """Per walker: fell/when and :class:`~evobiped.experiments.taga.stride.StrideMetrics` over the window."""
        a = self.trace.arrays()
        out = []
        for p in range(self.P):
            m: StrideMetrics = analyse_strides(a["t"], a["contact"][:, p], a["ankle"][:, p, :, 0], a["hip"][:, p, 1], t_start=t_start, t_end=t_end)
            fell = bool(not self.alive[p])
            d = {"u0": float(self.params["u0"][p, 0]), "fell": fell, "fell_at": float(self.fell_at[p]) if fell else None, "unstable": bool(self.unstable[p])}
            d.update(m.as_dict())
            if fell:
                d["gait"] = "fell"
                if t_start is not None and self.fell_at[p] <= t_start:  # down for the whole window
                    d.update({k: float("nan") for k in ("double_support", "flight", "hip_min", "hip_max")})
            out.append(d)
        return out


def steady(u0, *, seconds: float = 20.0, window: float = 10.0, **options) -> tuple[TagaWalker, list[dict]]:
    """Run from Appendix E's initial condition; metrics over the last ``window`` s."""
    w = TagaWalker(u0, **options)
    w.advance(seconds)
    return w, w.metrics(t_start=seconds - window)


def push(
    target: str,
    force: float,
    delays=(0.05,),
    *,
    u0: float = 5.5,
    before: float = 10.0,
    duration: float = 0.2,
    after: float = 8.0,
    tolerance: float = 0.05,
    **options,
) -> tuple[TagaWalker, list[dict]]:
    """Fig. 7: walk ``before`` s, then push ``target`` forward with ``force`` N for ``duration`` s.

    Walker p is pushed ``delays[p]`` s after the first liftoff of the right
    foot after ``before`` (a right-shank push with a short delay hits the
    swinging shank).  Per walker: push time, fell/when, the median stride
    length and cycle duration of the strides before the push, every stride
    after it, and the strides until all later ones are within ``tolerance``
    (relative) of the pre-push values (None if never).  A walker that fell
    before its push has ``t_push`` None; without strides before the push the
    pre-push values are nan.
    """
    from .stride import per_stride

    delays = np.asarray(delays, float)
    w = TagaWalker(np.full(len(delays), u0), **options)
    w.advance(before)
    step = w.body.timestep
    for _ in range(int(round(2.0 / step))):  # to the right foot's liftoff
        was = w.body.sensors(w.sims)["ground_contact"][0, 0]
        w.advance(step)
        if was > 0 and w.body.sensors(w.sims)["ground_contact"][0, 0] == 0:
            break
    starts = w.time + delays
    t_end = starts.max() + duration + after
    on = np.zeros(len(delays), bool)
    given = np.zeros(len(delays), bool)  # the push acted on the walker for at least one step
    while w.alive.any() and w.time < t_end - step / 2:  # an all-down batch stops its clock
        t = w.time
        want = (t >= starts - step / 2) & (t < starts + duration - step / 2)
        for i in np.flatnonzero(want != on):
            set_push(w.sims, np.array([i]), target if want[i] else "none", force if want[i] else 0.0)
        on = want
        given |= want & w.alive
        w.advance(step)
    a = w.trace.arrays()
    rows = []
    for p in range(w.P):
        s, L, D = per_stride(a["t"], a["contact"][:, p], a["ankle"][:, p, :, 0])
        pre, post = (s < starts[p] - 1.5) & (s > before - 5.0), s > starts[p]
        refL, refD = (float(np.median(L[pre])), float(np.median(D[pre]))) if pre.any() else (np.nan, np.nan)
        ok = (np.abs(L[post] / refL - 1) < tolerance) & (np.abs(D[post] / refD - 1) < tolerance)
        fell = bool(not w.alive[p])
        recovered = None if fell else next((i for i in range(len(ok)) if ok[i:].all() and len(ok) - i >= 3), None)
        rows.append(
            dict(
                target=target,
                force=float(force),
                delay=float(delays[p]),
                t_push=float(starts[p]) if given[p] else None,
                fell=fell,
                fell_at=float(w.fell_at[p]) if fell else None,
                stride_length_before=refL,
                cycle_duration_before=refD,
                strides_after=[(float(x), float(y)) for x, y in zip(L[post], D[post])],
                strides_to_recover=recovered,
            )
        )
    return w, rows


def ground_switch(kg, bg, *, u0: float = 5.5, before: float = 10.0, after: float = 15.0, window: float = 10.0, **options) -> list[dict]:
    """Claim 6, second reading: walk ``before`` s on the nominal ground (Appendix D), then
    switch walker p to ground (kg[p], bg[p]) and walk ``after`` s more; metrics over the last ``window`` s."""
    kg, bg = np.asarray(kg, float), np.asarray(bg, float)
    w = TagaWalker(np.full(len(kg), u0), **options)
    w.advance(before)
    w.body.p["kg"], w.body.p["bg"] = kg, bg
    w.advance(after)
    rows = w.metrics(t_start=w.time - window)
    for r, k, b in zip(rows, kg, bg):
        r.update(kg=float(k), bg=float(b))
    return rows


def u0_sweep(u0_values, *, settle: float = 8.0, window: float = 4.0, first: float = 20.0, **options) -> list[dict]:
    """Fig. 11: step u_0 through ``u0_values``, each step starting from the previous steady state.

    The first value runs ``first`` s from Appendix E's initial condition, every
    later one ``settle`` s; metrics over the last ``window`` s of each.
    A fall ends the sweep (later values are reported as fell).
    """
    w = TagaWalker(u0_values[0], **options)
    rows = []
    for i, u in enumerate(u0_values):
        w.set_u0(u)
        dur = first if i == 0 else settle
        w.advance(dur)
        m = w.metrics(t_start=w.time - window)[0]
        m["u0"] = float(u)
        rows.append(m)
    return rows


def isolated_activity(u0: float = 5.5, *, seconds: float = 10.0, initial_u: float = 0.1, timestep: float = 0.0005) -> tuple[np.ndarray, np.ndarray]:
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
