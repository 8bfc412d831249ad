"""Command schedules of the command task: the forward speed (m/s) and turning rate (rad/s, + left) a walker is asked for
at each time of its episode.

* ``constant``: one speed and one turning rate throughout.
* ``piecewise``: ``times`` t_0 < t_1 < ... (s from the episode start, t_0 >= 0) and a speed and a turning rate for
  each; value i holds from t_i until t_{i+1} (the first one also before t_0).  A control tick that begins at time t
  (the tick reads its senses then, and its motion is scored against that command) takes the last value with
  t_i <= t: the switch at t_i falls on the first tick that begins at or after t_i.
* ``drawn``: stretches of ``stretch`` s; stretch i of generation key = (run seed, generation) has a speed uniform in
  [speed_low, speed_high], replaced by 0 (a stop) with probability ``p_stop``, and a turning rate uniform in
  +-turning_max.  Each stretch is drawn from (run seed, generation, i) alone: every genome of a generation meets the
  same commands, in any process, after a resume, and for an episode of any length.
* a nominal episode of a drawn schedule (a replay, the battery: no generation key) follows :func:`nominal_drawn`, a
  fixed tour of the range, one stretch each: (mid, 0), (high, 0), (mid, +turning_max), (mid, -turning_max),
  (low, 0), then (0, 0) when stops were drawn, held to the end (mid = (speed_low + speed_high) / 2).

What a walker was evolved for (:func:`trained_range`): the speeds [speed_low, speed_high] (and 0 when it met stops)
and the turning rates +-turning_max of a drawn schedule; the span of a piecewise schedule's values; a constant
schedule's one command.  :func:`clip_command` puts any command on the nearest value of that range.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..core.errors import ConfigError

#: s: a tick that begins within this of a switching time takes the new value (the simulation clock's rounding)
CLOCK_TOLERANCE = 1e-6
#: the drawn commands' stream tag (beside the run seed, the generation and the stretch)
DRAW_TAG = 0xC0DE


def check_times(times, speed, turning) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A piecewise schedule's ``times`` (s), ``speed`` (m/s) and ``turning`` (rad/s) as arrays; ConfigError (one line)
    for times that are negative or not strictly increasing, lists of unequal lengths, non-finite values."""
    arrays = []
    for name, v in (("times", times), ("speed", speed), ("turning", turning)):
        items = list(v) if isinstance(v, (list, tuple, np.ndarray)) else None
        if not items or any(isinstance(x, bool) or not isinstance(x, (int, float, np.floating, np.integer))
                            for x in items):
            raise ConfigError(f"{name}: a piecewise schedule needs a non-empty list of numbers, got {v!r}")
        a = np.asarray(items, float)
        if not np.isfinite(a).all():
            raise ConfigError(f"{name}: every value must be finite, got {v!r}")
        arrays.append(a)
    t, s, w = arrays
    if len(s) != len(t) or len(w) != len(t):
        raise ConfigError(f"a piecewise schedule needs one speed and one turning rate per time: {len(t)} times, "
                          f"{len(s)} speeds, {len(w)} turning rates")
    if t[0] < 0:
        raise ConfigError(f"times: must be >= 0 s (from the episode start), got {t[0]:g}")
    if len(t) > 1 and not (np.diff(t) > 0).all():
        raise ConfigError(f"times: must be strictly increasing, got {[float(x) for x in t]}")
    return t, s, w


@dataclass(frozen=True)
class CommandSchedule:
    """A piecewise-constant schedule: value i (``speed`` m/s, ``turning`` rad/s) from ``times[i]`` s on."""

    times: np.ndarray
    speed: np.ndarray
    turning: np.ndarray

    @classmethod
    def of(cls, times, speed, turning) -> "CommandSchedule":
        return cls(*check_times(times, speed, turning))

    def at(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The commands ``(speed, turning)``, ``(n,)`` each, of ticks beginning at times ``t`` ``(n,)`` s."""
        i = np.maximum(np.searchsorted(self.times, np.asarray(t, float) + CLOCK_TOLERANCE, side="right") - 1, 0)
        return self.speed[i], self.turning[i]

    def restart(self, ids) -> None:
        """The schedule is the episode's, the same for every row: rows that begin anew keep it."""

    def steps(self, seconds: float) -> "CommandSchedule":
        """Itself (its switching times are already explicit)."""
        return self


@dataclass(frozen=True)
class DrawnCommands:
    """The commands of generation key = (run seed, generation): stretches of ``stretch`` s (module docstring)."""

    seed: int
    generation: int
    stretch: float
    speed_low: float
    speed_high: float
    p_stop: float
    turning_max: float
    _cache: dict = field(default_factory=dict, compare=False, repr=False)

    def stretch_commands(self, i: int) -> tuple[float, float]:
        """Stretch ``i``'s (speed m/s, turning rad/s), from (seed, generation, i) alone."""
        if i not in self._cache:
            rng = np.random.default_rng([self.seed, self.generation, DRAW_TAG, i])
            speed, stop, turning = rng.uniform(self.speed_low, self.speed_high), rng.random(), rng.uniform(-1.0, 1.0)
            self._cache[i] = (0.0 if stop < self.p_stop else float(speed), float(turning * self.turning_max))
        return self._cache[i]

    def at(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        idx = np.floor((np.asarray(t, float) + CLOCK_TOLERANCE) / self.stretch).astype(int)
        speed, turning = np.empty(len(idx)), np.empty(len(idx))
        for i in np.unique(idx):
            speed[idx == i], turning[idx == i] = self.stretch_commands(int(i))
        return speed, turning

    def restart(self, ids) -> None:
        """The draw is the generation's, the same for every row."""

    def steps(self, seconds: float) -> CommandSchedule:
        """The draw over ``seconds`` s as an explicit piecewise schedule."""
        n = max(1, math.ceil(seconds / self.stretch - CLOCK_TOLERANCE))
        values = [self.stretch_commands(i) for i in range(n)]
        return CommandSchedule(np.arange(n) * self.stretch, np.array([v[0] for v in values]),
                               np.array([v[1] for v in values]))


def nominal_drawn(o) -> CommandSchedule:
    """The fixed schedule a nominal episode of a drawn schedule follows (options ``o``; module docstring)."""
    mid = 0.5 * (o.speed_low + o.speed_high)
    values = [(mid, 0.0), (o.speed_high, 0.0), (mid, o.turning_max), (mid, -o.turning_max), (o.speed_low, 0.0)]
    if o.p_stop > 0:
        values.append((0.0, 0.0))
    return CommandSchedule(np.arange(len(values)) * float(o.stretch), np.array([v[0] for v in values], float),
                           np.array([v[1] for v in values], float))


def schedule_of(o):
    """The schedule options ``o`` (:class:`~evobiped.tasks.command.CommandOptions`) give a nominal episode."""
    if o.schedule == "constant":
        return CommandSchedule(np.zeros(1), np.array([float(o.speed)]), np.array([float(o.turning)]))
    if o.schedule == "piecewise":
        return CommandSchedule.of(o.times, o.speed, o.turning)
    return nominal_drawn(o)


def draw_commands(o, key) -> DrawnCommands | None:
    """Generation ``key`` = (run seed, generation, ...)'s drawn commands under options ``o``; None: not drawn."""
    if o.schedule != "drawn" or key is None:
        return None
    return DrawnCommands(int(key[0]), int(key[1]), float(o.stretch), float(o.speed_low), float(o.speed_high),
                         float(o.p_stop), float(o.turning_max))


def trained_range(o) -> tuple[tuple[float, float], bool, tuple[float, float]]:
    """What a walker evolved under options ``o`` met: ((lowest, highest) speed m/s, whether it met stops (speed 0),
    (lowest, highest) turning rad/s)."""
    if o.schedule == "drawn":
        return (o.speed_low, o.speed_high), o.p_stop > 0, (-o.turning_max, o.turning_max)
    s = schedule_of(o)
    return (float(s.speed.min()),
            float(s.speed.max())), bool((s.speed == 0).any()), (float(s.turning.min()), float(s.turning.max()))


def clip_command(o, speed: float, turning: float) -> tuple[float, float]:
    """(speed m/s, turning rad/s) on the nearest command the walker of options ``o`` was evolved for: a speed within
    its range stays, one outside goes to the nearest of its bounds (or to 0 when it met stops and 0 is nearer);
    a turning rate is clipped to its range."""
    (lo, hi), stops, (wlo, whi) = trained_range(o)
    s = float(np.clip(speed, lo, hi))
    if stops and abs(speed) < abs(speed - s):
        s = 0.0
    return s, float(np.clip(turning, wlo, whi))
