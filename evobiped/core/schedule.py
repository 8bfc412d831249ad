"""A value that changes over the generations of a run: constant, or a linear ramp from ``start`` to ``end``.

A config gives a scheduled option either as a plain value (constant) or as a table::

    push_force = {start = 2.0, end = 10.0, generations = 60, after = 10}

The value is ``start`` up to generation ``after`` (default 0), then moves linearly
to ``end`` over ``generations`` generations, and stays at ``end`` from
generation ``after + generations`` on.  ``start`` and ``end`` are numbers, or
lists of numbers of one length (a friction range ``[low, high]``), ramped
element by element.  The value at a generation is a function of the generation
alone, so a resumed run and one on any number of workers see the same values.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

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
