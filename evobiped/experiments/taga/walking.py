"""Taga et al. 1991's walker: the Taga biped driven by its Matsuoka rhythm generator.

A :class:`TagaWalker` is a batch of P walkers (one genome each, u_0 per walker)
that can be advanced in pieces, so an experiment (:mod:`.protocols`) can change u_0, push the body,
change the ground, or continue from a steady state (the u_0 sweeps of Fig. 11).  Every physics
step: sensors -> rhythm generator (eq. 6) -> torques -> Appendix A forces ->
MuJoCo step: one :class:`evobiped.episode.Episode` (walk task, the controller
stepped at the physics step) built by :func:`walker_config`'s :class:`~evobiped.episode.EpisodeConfig` (the
contract checked there) and continued by :meth:`Episode.advance`.
Trajectories are sampled every ``record_every`` steps; :meth:`TagaWalker.metrics`
reduces them with :mod:`evobiped.experiments.taga.stride`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from typing import Callable

import numpy as np

from ...controllers.matsuoka import MatsuokaOptions
from ...core.errors import UserError
from ...episode import EpisodeConfig
from ...core.options import check_value
from ...physics.sim import Sims
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


def walker_config(u0: float, *, feedback: bool = True, timestep: float = 0.0005, **body_options) -> EpisodeConfig:
    """The episode of Taga's walker: the taga body (physics step ``timestep`` s, its other options ``body_options``),
    the matsuoka controller with tonic input ``u0`` (with Taga's feedback, or none) stepped at the physics step, the
    walk task, one physics step long (open-ended: an experiment advances it as long as it needs)."""
    controller = {"u0": float(u0)} if feedback else {"u0": float(u0), "feedback": "none"}
    return EpisodeConfig(body="taga", controller="matsuoka", task="walk", seconds=timestep,
                         body_options={"timestep": timestep, **body_options}, controller_options=controller)


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
        self.config = walker_config(float(u0[0]), feedback=feedback, timestep=timestep, **body_options)
        self.episode = self.config.build()
        body, ctrl, _ = self.config.parts()
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

    def set_ground(self, kg, bg) -> None:
        """From now on walker p's ground has stiffness ``kg[p]`` (N/m) and damping ``bg[p]`` (N s/m)."""
        self.body.set_ground(self.sims, kg, bg)

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
            m: StrideMetrics = analyse_strides(a["t"], a["contact"][:, p], a["ankle"][:, p, :, 0], a["hip"][:, p, 1],
                                               t_start=t_start, t_end=t_end)
            fell = bool(not self.alive[p])
            d = {"u0": float(self.params["u0"][p, 0]), "fell": fell, "fell_at": float(self.fell_at[p]) if fell
                 else None, "unstable": bool(self.unstable[p])}
            d.update(m.as_dict())
            if fell:
                d["gait"] = "fell"
                if t_start is not None and self.fell_at[p] <= t_start:  # down for the whole window
                    d.update({k: float("nan") for k in ("double_support", "flight", "hip_min", "hip_max")})
            out.append(d)
        return out
