"""Commanded walking: one network walks at a commanded forward speed and turning rate, and stops at a zero command.

Senses.  The task adds ``command_speed`` (m/s) and ``command_turning`` (rad/s, + left), the commands of the tick's
time under the task's schedule (:mod:`evobiped.tasks.command_schedule`: ``constant``, ``piecewise`` or ``drawn``
per generation), and ``command_stop`` (1 at a zero speed command, else 0: a stop told apart from a slow walk).  Under
the stance frame's left/right mirror the speed keeps its sign and the turning rate changes sign.  With ``heading_sense``
the walk task's ``heading_error`` is the angle of the facing from the *commanded* facing (the initial facing turned by
the integral of the commanded turning rate, + when turned left of it), held within +-pi/2 (:data:`HEADING_LEASH`: a
walker that lags further behind a commanded turn is told "turn left" or "turn right", never the opposite after a wrap);
at a zero turning command it is the walk task's heading error.

Tracking fitness (as legged locomotion scores a velocity command).  Every tick a row is up, with v the pelvis's
forward velocity in its heading frame (m/s: its planar displacement over the tick along the facing at the tick's
end, per s), w its yaw rate (rad/s: the facing's turn over the tick, + left), v* and w* the tick's commands, and
sigma_v = ``sigma_speed``, sigma_w = ``sigma_turning``:

    track_speed   += exp(-(v - v*)^2 / sigma_v^2)
    track_turning += exp(-(w - w*)^2 / sigma_w^2)
    stand         += [v* = 0] * [both feet on the ground] * exp(-|v_xy|^2 / sigma_v^2) * exp(-w^2 / sigma_w^2)

each times the tick's length, divided by the time up (``average = "time_up"``, the default; each term then in
[0, 1]) or by the episode's length (``average = "episode"``: the time lost to a fall scores 0).  So at a zero speed
command standing still on both feet earns ``stand`` (stepping in place earns ``track_speed`` alone); a schedule
without a stop gives every walker ``stand`` = 0.  ``smoothing`` tau > 0 s low-passes v, |v_xy| and w (a first-order
filter of time constant tau) before they are scored, so the stride's own sway is not charged.

The fitness is ``weighted`` over the terms (as the walk task's, whose terms and gait lab's terms stay available:
``time_up``, ``steps``, ``pace``, ``duty_left``, ``airborne``, ``sliding``, ``positive_work``, ...).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..core.errors import ConfigError
from ..core.options import option
from .command_schedule import check_times, draw_commands, schedule_of
from .states import CommandState
from ..physics.gait_lab import SAMPLING_HELP, check_sampled
from .walk import WalkTask, check_weights

#: the terms the command task adds to the walk task's
COMMAND_TERMS = ("track_speed", "track_turning", "stand")
#: rad: the most the heading sense reads
HEADING_LEASH = np.pi / 2
#: the schedules (:mod:`evobiped.tasks.command_schedule`)
SCHEDULES = ("constant", "piecewise", "drawn")


def _weights(v) -> None:
    check_weights(v, "command", COMMAND_TERMS)


def _value(v) -> None:
    items = v if isinstance(v, (list, tuple)) else [v]
    if not items or any(isinstance(x, bool) or not isinstance(x, (int, float)) or not np.isfinite(x) for x in items):
        raise ConfigError(f"must be a finite number (constant) or a list of finite numbers (piecewise), got {v!r}")


def _times(v) -> None:
    if not isinstance(v, (list, tuple)) or any(isinstance(x, bool) or not isinstance(x, (int, float)) for x in v):
        raise ConfigError(f"must be a list of times in s, got {v!r}")


def _wrap(a: np.ndarray) -> np.ndarray:
    """Angles in (-pi, pi]."""
    return np.pi - np.mod(np.pi - a, 2 * np.pi)


@dataclass(frozen=True, kw_only=True)
class CommandOptions:
    """Options of the command task."""

    # the walk task's settings this task fixes (plain class attributes, not options)
    fitness = "weighted"
    survival_credit = 0.0
    cyclic_weight = 0.0
    cyclic_cycles = 25
    cyclic_band = 0.05
    gait_measures = False

    schedule: str = option("constant", "`constant` (speed, turning), `piecewise` (times, and a speed and a turning "
                           "rate per time) or `drawn` anew each generation (stretch, speed_low, speed_high, p_stop, "
                           "turning_max)", choices=SCHEDULES)
    speed: float = option(0.5, "the commanded forward speed: one (constant) or one per time (piecewise)", unit="m/s",
                          check=_value, span="a number, or a list")
    turning: float = option(0.0, "the commanded turning rate, + left: one (constant) or one per time (piecewise)",
                            unit="rad/s", check=_value, span="a number, or a list")
    times: tuple = option((), "piecewise: when each value begins, from the episode start", unit="s", check=_times,
                          span=">= 0, strictly increasing")
    stretch: float = option(5.0, "drawn: how long each drawn command holds", unit="s", above=0)
    speed_low: float = option(0.2, "drawn: the slowest speed drawn", unit="m/s", low=0)
    speed_high: float = option(0.8, "drawn: the fastest speed drawn", unit="m/s", low=0)
    p_stop: float = option(0.2, "drawn: the probability that a stretch is a stop (speed 0)", low=0, high=1)
    turning_max: float = option(0.35, "drawn: turning rates uniform in +-turning_max", unit="rad/s", low=0)
    sigma_speed: float = option(0.25, "sigma_v of the speed tracking term exp(-(v - v*)^2 / sigma_v^2)", unit="m/s",
                                above=0)
    sigma_turning: float = option(0.35, "sigma_w of the turning tracking term exp(-(w - w*)^2 / sigma_w^2)",
                                  unit="rad/s", above=0)
    average: str = option("time_up", "the tracking terms per second of the time up (`time_up`) or of the episode "
                          "(`episode`: time lost to a fall scores 0)", choices=("time_up", "episode"))
    smoothing: float = option(0.0, "time constant of a low-pass on the measured speed and turning rate (0: none)",
                              unit="s", low=0)
    weights: dict = option({"track_speed": 10.0, "track_turning": 5.0, "stand": 5.0, "time_up": 1.0},
                           "the weight of each term (track_speed, track_turning, stand, and the walk task's: time_up "
                           "s, steps, pace m, the gait lab's)", check=_weights)
    heading_sense: bool = option(False, "add the sensor heading_error: the facing's angle from the commanded facing "
                                 "(rad, + left, within +-pi/2)")
    pace_cap: float = option(0.6, "the term pace: the displacement forward, counted up to this speed times the time up",
                             unit="m/s", above=0)
    gait_terms: bool = option(False, "add the gait lab's terms (also on when the weights name one)")
    gait_sampling: str = option("control_tick", SAMPLING_HELP, choices=("physics_step", "control_tick"))

    def __post_init__(self):
        check_sampled(self.weights, self.gait_sampling, "weights")
        if self.schedule == "constant" and (isinstance(self.speed, (list, tuple))
                                            or isinstance(self.turning, (list, tuple))):
            raise ConfigError("a constant schedule takes one speed and one turning rate; lists need schedule = "
                              "'piecewise'")
        if self.schedule == "piecewise":
            check_times(self.times, self.speed if isinstance(self.speed, (list, tuple)) else [self.speed],
                        self.turning if isinstance(self.turning, (list, tuple)) else [self.turning])
        if self.speed_low > self.speed_high:
            raise ConfigError(
                f"speed_low ({self.speed_low:g} m/s) must not exceed speed_high ({self.speed_high:g} m/s)")


class CommandTask(WalkTask):
    """Walking as commanded (:class:`~evobiped.tasks.states.CommandState`)."""

    name = "command"
    sensor_text = {
        "heading_error": "the facing's angle from the commanded facing (rad, + left, within ±π/2)",
        "command_speed": "the command task's commanded forward speed (m/s)",
        "command_turning": "the command task's commanded turning rate (rad/s, + left; its sign changes in the stance "
                           "frame's mirror)",
        "command_stop": "the command task's stop: 1 at a zero speed command, else 0"}
    Options = CommandOptions
    criteria = {}

    def __init__(self, options=None, **given):
        super().__init__(options, **given)
        self.term_names = tuple(self.term_names) + COMMAND_TERMS
        self.nominal = schedule_of(self.options)

    def sensor_widths(self):
        return {**super().sensor_widths(), "command_speed": 1, "command_turning": 1, "command_stop": 1}

    def sensor_norms(self):
        return {**super().sensor_norms(), "command_speed": ((0.0,), (0.5,)), "command_turning": ((0.0,), (0.35,)),
                "command_stop": ((0.0,), (1.0,))}

    def sensor_mirror(self):  # a turn to the left is a turn to the right of the mirrored body; the speed is the same
        return {**super().sensor_mirror(), "command_speed": ((0,), (1,)), "command_turning": ((0,), (-1,)),
                "command_stop": ((0,), (1,))}

    def draw_sources(self, key):
        """This generation's drawn commands (None: the schedule is not drawn); the episode hands them to
        :meth:`take_sources` (the draw mechanism the steer task's random sources use)."""
        return draw_commands(self.options, key)

    def take_sources(self, state, commands) -> None:
        """Follow ``commands`` (a generation's draw) instead of the nominal schedule."""
        state.commands = commands

    def commands(self, state, rows=None) -> tuple[np.ndarray, np.ndarray]:
        """The commands (speed m/s, turning rad/s) of rows ``rows`` (default all) at their clock now."""
        rows = slice(None) if rows is None else rows
        return state.commands.at(state.clock[rows] - state.t0[rows])

    def start(self, body, sims):
        walk = super().start(body, sims)
        if body.contact_sensor is None or len(body.contact_sensor[1]) < 2:
            raise ConfigError(f"the command task scores standing on both feet; body {body.name!r} declares no two feet")
        if body.sagittal and np.any(self.nominal.turning != 0):
            raise ConfigError(f"body {body.name!r} walks in its sagittal plane: it cannot follow a turning command")
        f = body.heading(sims)
        n = sims.n
        return CommandState(**vars(walk), commands=self.nominal, t0=np.array(sims.time, float),
                            clock=np.array(sims.time, float),
                            up=np.zeros(n), last_facing=f.copy(), yaw_cmd=np.arctan2(f[:, 1], f[:, 0]),
                            measured=np.zeros((n, 3)), sums=np.zeros((n, 3)), first=np.ones(n, bool))

    def sensors(self, body, sims, state):
        speed, turning = self.commands(state)
        out = {"command_speed": speed[:, None], "command_turning": turning[:, None],
               "command_stop": (speed == 0).astype(float)[:, None]}
        if self.heading_sense:
            f = body.heading(sims)
            out["heading_error"] = _wrap(np.arctan2(f[:, 1], f[:, 0]) - state.yaw_cmd)[:, None]
        return out

    def on_tick(self, body, sims, state, ids, healthy, neurons):
        ok = ids[healthy]
        o = self.options
        v_cmd, w_cmd = self.commands(state, ok)
        dt = np.maximum(np.asarray(sims.time, float)[ok] - state.clock[ok], 1e-12)
        f0, f1 = state.last_facing[ok], body.heading(sims)[ok]
        step = body.planar_position(sims)[ok] - state.position[ok]
        turn = np.arctan2(f0[:, 0] * f1[:, 1] - f0[:, 1] * f1[:, 0], np.einsum("pi,pi->p", f0, f1))
        now = np.stack([np.einsum("pi,pi->p", step, f1) / dt, np.linalg.norm(step, axis=1) / dt, turn / dt], axis=1)
        if o.smoothing > 0:  # a first-order low-pass, started at the first tick's reading
            a = np.where(state.first[ok], 1.0, 1.0 - np.exp(-dt / o.smoothing))[:, None]
            now = state.measured[ok] + a * (now - state.measured[ok])
        state.measured[ok], state.first[ok] = now, False
        v, speed, w = now.T
        sv2, sw2 = o.sigma_speed ** 2, o.sigma_turning ** 2
        both = body.contacts(sims)[ok].all(axis=1)
        still = (v_cmd == 0) * both * np.exp(-speed ** 2 / sv2) * np.exp(-w ** 2 / sw2)
        state.sums[ok] += dt[:, None] * np.stack([np.exp(-(v - v_cmd) ** 2 / sv2), np.exp(-(w - w_cmd) ** 2 / sw2),
                                                  still], axis=1)
        state.up[ok] += dt
        yaw = np.arctan2(f1[:, 1], f1[:, 0])  # the commanded facing turns on, held within the leash of the facing
        cmd = state.yaw_cmd[ok] + w_cmd * dt
        state.yaw_cmd[ok] = yaw - np.clip(_wrap(yaw - cmd), -HEADING_LEASH, HEADING_LEASH)
        state.last_facing[ok], state.clock[ok] = f1, np.asarray(sims.time, float)[ok]
        super().on_tick(body, sims, state, ids, healthy, neurons)

    def terms(self, state):
        out = super().terms(state)
        per = state.up if self.options.average == "time_up" else np.full(len(state.up), float(state.seconds))
        scored = state.sums / np.maximum(per, 1e-9)[:, None]
        for k, name in enumerate(COMMAND_TERMS):
            out[name] = np.where(per > 0, scored[:, k], 0.0)
        return out

    def fitness_label(self):
        return "fitness: " + " + ".join(f"{w:g} × {k}" for k, w in self.weights.items())
