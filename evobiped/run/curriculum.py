"""A curriculum of fitness phases: the task's term weights change when the walkers are ready.

A policy on point feet must learn to step before it can walk: a first phase
pays staying up and stepping, a later one distance forward.  ``phases`` is a
list of weight tables (term -> weight) for a task whose fitness weighs its
terms (the walk task's ``fitness = "weighted"``); the run starts in phase 0 and
moves to the next phase once the **evaluation walkers** (the optimizer's
evaluation rows: ES's theta, else the generation's fittest genome) have met the
condition ``advance_for`` generations running:

* ``advance = "up"``: every evaluation walker stayed up its whole episode, in
  every presentation;
* ``advance = TERM``: the evaluation walkers' mean of that term is at least
  ``advance_above``;

and, with either, the evaluation walkers' mean of each term of ``advance_at_most`` at most its bound and of
``advance_at_least`` at least its bound (e.g. ``advance_at_most = {airborne = 0.1}``: a walker that stays up by
hopping does not move on).

The phase and the run of generations meeting the condition are part of the
checkpoint and of history.csv (``phase``), so a resume continues exactly; the
generation files and best.json carry the weights their walker was scored with.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..episode.result import EpisodeResult
from ..core.errors import ConfigError, UserError
from ..core.options import check_fields, option


def _phases(v) -> None:
    ok = isinstance(v, list) and all(
        isinstance(t, dict) and t and all(isinstance(k, str) and isinstance(w, (int, float)) and not isinstance(w, bool)
                                          and np.isfinite(w) for k, w in t.items()) for t in v)
    if not ok:
        raise ConfigError(f"must be a list of tables of finite weights by term name, got {v!r}")


def _bounds(v) -> None:
    if not (isinstance(v, dict) and all(isinstance(k, str) and isinstance(x, (int, float)) and not isinstance(x, bool)
                                        and np.isfinite(x) for k, x in v.items())):
        raise ConfigError(f"must be a table of finite bounds by term name, got {v!r}")


def _lengths(v) -> None:
    if not (isinstance(v, list) and all(isinstance(x, (int, float)) and not isinstance(x, bool) and 0 < x <= 1e5
                                        for x in v)):
        raise ConfigError(f"must be a list of episode lengths in s, each > 0, got {v!r}")


@dataclass(frozen=True, kw_only=True)
class CurriculumOptions:
    """Fitness phases (``[curriculum]`` in a config; none by default)."""

    phases: list = option([], "the fitness weights of each phase, e.g. [{time_up = 2, steps = 0.5}, {forward = 10, "
                              "time_up = 5}]", check=_phases)
    advance: str = option("up", "when to move on: `up` (every evaluation walker up its whole episode) or a term's name")
    advance_above: float = option(0.0, "with a term: the evaluation walkers' mean it must reach")
    advance_for: int = option(2, "generations running the condition must hold", low=1, integer=True)
    advance_at_most: dict = option({}, "and the evaluation walkers' mean of each of these terms at most its bound, "
                                   "e.g. {airborne = 0.1}", check=_bounds)
    advance_at_least: dict = option({}, "and of each of these terms at least its bound, e.g. {duty_min = 0.3}",
                                    check=_bounds)
    seconds: list = option([], "the episode length of each phase (empty: the episode's)", unit="s", check=_lengths)

    def __post_init__(self):
        check_fields(self, "curriculum")
        if self.seconds and len(self.seconds) != len(self.phases):
            raise ConfigError(f"seconds: one length per phase ({len(self.phases)}), got {len(self.seconds)}")


@dataclass
class Curriculum:
    """The curriculum's state: the ``phase`` and how many generations running met its condition (``streak``)."""

    options: CurriculumOptions = field(default_factory=CurriculumOptions)
    phase: int = 0
    streak: int = 0

    def check(self, task) -> None:
        """ConfigError (one line) when the task cannot take the phases' weights or the condition names no term of it."""
        o = self.options
        if not o.phases:
            return
        if not getattr(task, "weighs_terms", False):
            raise ConfigError(f"curriculum.phases: need a task whose fitness weighs its terms (the walk task with "
                              f"fitness = 'weighted'); task {task.name!r} has none")
        terms = tuple(task.term_names)
        for i, t in enumerate(o.phases):
            unknown = [k for k in t if k not in terms]
            if unknown:
                raise ConfigError(f"curriculum.phases[{i}]: names no term of the {task.name} task: "
                                  f"{', '.join(unknown)} (terms: {', '.join(terms)})")
        if o.advance != "up" and o.advance not in terms:
            raise ConfigError(f"curriculum.advance: {o.advance!r} is neither 'up' nor a term of the {task.name} task "
                              f"({', '.join(terms)})")
        for name in ("advance_at_most", "advance_at_least"):
            if unknown := [k for k in getattr(o, name) if k not in terms]:
                raise ConfigError(f"curriculum.{name}: names no term of the {task.name} task: {', '.join(unknown)} "
                                  f"(terms: {', '.join(terms)})")

    @property
    def active(self) -> bool:
        return bool(self.options.phases)

    def weights(self) -> dict | None:
        """The current phase's weights (None: no curriculum)."""
        return dict(self.options.phases[self.phase]) if self.active else None

    def seconds(self) -> float | None:
        """The current phase's episode length (None: the episode's)."""
        return float(self.options.seconds[self.phase]) if self.active and self.options.seconds else None

    def met(self, result: EpisodeResult, rows: np.ndarray) -> bool:
        """Whether the evaluation walkers (genomes ``rows`` of ``result``) meet the condition."""
        o = self.options
        mean = lambda k: float(np.mean(np.asarray(result.terms[k])[rows]))  # noqa: E731
        bounded = (all(mean(k) <= b for k, b in o.advance_at_most.items())
                   and all(mean(k) >= b for k, b in o.advance_at_least.items()))
        if o.advance == "up":
            return bool(not result.fell[rows].any()) and bounded
        return mean(o.advance) >= o.advance_above and bounded

    def after(self, result: EpisodeResult, rows: np.ndarray) -> None:
        """Count this generation; move to the next phase when the condition held ``advance_for`` generations running."""
        if not self.active or self.phase == len(self.options.phases) - 1:
            return
        self.streak = self.streak + 1 if self.met(result, rows) else 0
        if self.streak >= self.options.advance_for:
            self.phase, self.streak = self.phase + 1, 0

    def to_dict(self) -> dict:
        return {"phase": self.phase, "streak": self.streak}

    def restore(self, table) -> None:
        """Read :meth:`to_dict` back (UserError, one line, when it does not fit these phases)."""
        ok = isinstance(table, dict) and all(isinstance(table.get(k), int) and not isinstance(table.get(k), bool)
                                             and table[k] >= 0
                                             for k in ("phase", "streak"))
        if not ok or table["phase"] >= max(len(self.options.phases), 1):
            raise UserError(f"checkpoint: curriculum must be {{phase, streak}} with a phase below "
                            f"{len(self.options.phases)}, got {table!r}")
        self.phase, self.streak = table["phase"], table["streak"]
