"""A value that changes over the generations of a run (:class:`Schedule`), or over an episode's time
(:func:`timed_levels`).

**Over the generations**: constant, or a linear ramp from ``start`` to ``end``.

A config gives a scheduled option either as a plain value (constant) or as a table::

    push_force = {start = 2.0, end = 10.0, generations = 60, after = 10}

The value is ``start`` up to generation ``after`` (default 0), then moves linearly
to ``end`` over ``generations`` generations, and stays at ``end`` from
generation ``after + generations`` on.  ``start`` and ``end`` are numbers, or
lists of numbers of one length (a friction range ``[low, high]``), ramped
element by element.  The value at a generation is a function of the generation
alone, so a resumed run and one on any number of workers see the same values.

**Over an episode** (a controller's command: the matsuoka controller's tonic input ``u0``, the g3 controller's GO
signal ``go``): a level, or a list of steps ``[[t_s, level], ...]`` in seconds from the episode's start, times
increasing, each level held until the next step's time; the level is 0 before the first step.  Levels and times are
finite and >= 0.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from .errors import ConfigError
from .validate import number

#: the keys of a schedule table
KEYS = ("start", "end", "generations", "after")


@dataclass(frozen=True)
class Schedule:
    """``start`` until generation ``after``, a linear ramp to ``end`` over ``generations`` generations, then ``end``."""

    start: Any
    end: Any
    generations: int = 0
    after: int = 0

    @classmethod
    def constant(cls, value: Any) -> "Schedule":
        return cls(value, value)

    @classmethod
    def of(cls, value: Any, path: str = "", check: Callable[[Any, str], None] | None = None) -> "Schedule":
        """The schedule a config value gives: a table (see the module) or a plain value (constant).
        ``check(v, path)`` checks each of ``start`` and ``end`` (ConfigError naming ``path.start``...);
        a bad table is one ConfigError naming ``path``."""
        if not isinstance(value, dict):
            if check is not None:
                check(value, path)
            return cls.constant(value)
        where = f"{path}: " if path else ""
        unknown = [k for k in value if k not in KEYS]
        if unknown:
            raise ConfigError(f"{where}a schedule takes {', '.join(KEYS)}; unknown key {unknown[0]!r}")
        for k in ("start", "end", "generations"):
            if k not in value:
                raise ConfigError(f"{where}a schedule needs start, end and generations (after is optional); {k} is "
                                  "missing")
        dot = f"{path}." if path else ""
        gens = value["generations"]
        after = value.get("after", 0)
        number(after, f"{dot}after:", integer=True)
        number(gens, f"{dot}generations:", integer=True)
        if after < 0:
            raise ConfigError(f"{dot}after: the ramp cannot begin before generation 0, got {after!r}")
        if gens < 0:
            raise ConfigError(f"{dot}generations: the ramp's end (generation {after + gens}) precedes its start "
                              f"(generation {after}): must be >= 0, got {gens!r}")
        start, end = value["start"], value["end"]
        if isinstance(start, (list, tuple)) != isinstance(end, (list, tuple)) or (
                isinstance(start, (list, tuple)) and len(start) != len(end)):
            raise ConfigError(f"{where}start and end must be alike (two numbers, or two lists of one length), got "
                              f"{start!r} and {end!r}")
        if check is not None:
            check(start, f"{dot}start")
            check(end, f"{dot}end")
        if isinstance(start, (list, tuple)):
            start, end = tuple(start), tuple(end)
        return cls(start, end, int(gens), int(after))

    def at(self, generation: int) -> Any:
        """The value at ``generation`` (a number, or a tuple of numbers when start and end are lists)."""
        if self.start == self.end or generation < self.after:
            return self.start
        if generation >= self.after + self.generations:
            return self.end
        w = (generation - self.after) / self.generations
        if isinstance(self.start, tuple):
            return tuple(a + w * (b - a) for a, b in zip(self.start, self.end))
        return self.start + w * (self.end - self.start)


def timed_levels(value: Any) -> tuple[np.ndarray, np.ndarray]:
    """A level or a schedule over an episode's time (``[[t_s, level], ...]``, see the module) -> ``(times (K,) s,
    levels (K,))``; a plain level is the one step ``[[0, level]]``.  ConfigError (one line, without the option's path:
    the caller's check adds it) for anything else: not numbers, an empty list, a non-finite or negative level or
    time, times that do not increase."""
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        if not np.isfinite(value):
            raise ConfigError(f"must be finite, got {value!r}")
        if value < 0:
            raise ConfigError(f"must be >= 0, got {value!r}")
        return np.array([0.0]), np.array([float(value)])
    try:
        if isinstance(value, (str, bytes, dict, bool)):
            raise TypeError
        pairs = [(float(t), float(v)) for t, v in value]
        if any(isinstance(x, bool) for pair in value for x in pair):
            raise TypeError
    except (TypeError, ValueError):
        raise ConfigError(f"must be a level or a list of [time_s, level] pairs, got {value!r}") from None
    if not pairs:
        raise ConfigError("the schedule is empty: give a level, or at least one [time_s, level] pair")
    t, v = np.array(pairs).T
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(v))) or (v < 0).any() or (t < 0).any():
        raise ConfigError(f"a schedule's levels and times must be finite and >= 0, got {value!r}")
    if np.any(np.diff(t) <= 0):
        raise ConfigError(f"a schedule's times must increase, got {value!r}")
    return t, v


def level_at(times: np.ndarray, levels: np.ndarray, t: Any) -> np.ndarray:
    """The level of the schedule ``(times (K,) s, levels (K,))`` of :func:`timed_levels` at ``t`` s (any shape): the
    level of the last step at or before ``t`` (a step's time reached within 1e-9 s counts), 0 before the first."""
    i = np.searchsorted(times, np.asarray(t) + 1e-9, side="right") - 1
    return np.where(i >= 0, levels[np.maximum(i, 0)], 0.0)
