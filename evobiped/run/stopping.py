"""When a run is done before its last generation, or lost: the stopping rule (``[stop]`` in a run config) and the
lost-run rule (``[restart]``).

``when = "walking"``: the run's evaluation walkers (ES's theta, else each generation's fittest) met the walking
criteria (:data:`evobiped.analysis.gait_report.WALKING`, from the walk task's gait terms: up the whole episode, at
least 0.3 m/s, each foot standing half the time, no flight, symmetric feet that do not slide) in the curriculum's last
phase for ``generations`` generations running.  ``when = "fitness"``: their mean fitness reached ``above`` as many
generations running.  Neither is met in a generation whose walkers were helped (the pelvis assistance held them, or
less than the model's gravity pulled them: a walker helped does not walk).  The record of each generation (met or
not) is part of the checkpoint's context, so a resumed run stops where the uninterrupted one would.  The direction
criterion is left to the walker test after the run (the gait terms hold no heading).

**A lost run** (``[restart]``): ``patience`` gives each phase of the curriculum (one entry per phase; one entry for a
run without a curriculum) the generations it may take within an attempt: to advance to the next phase, or, in the
last phase, to meet the stopping rule.  A phase that has taken them is lost, and the run says so, then, by
``action``: goes on (``warn``), stops (``stop``), or starts over (``restart``: the optimizer from its start point,
the curriculum from its first phase, the running normaliser from its start; the generation count, the random streams
and the budget go on, so every restart's episodes count), at most ``max_restarts`` times, then stops.  Each lost
phase is recorded (generation, phase, what was done) in the checkpoint and summary.json, so a resumed run restarts
where the uninterrupted one would.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..core.errors import ConfigError, UserError
from ..core.options import check_fields, option

#: the gait terms the walking rule reads
WALKING_TERMS = ("duty_min", "airborne", "duty_asymmetry", "slip_share", "forward", "time_up")
#: and those it reads of a task whose gait terms sample every physics step (``gait_sampling = "physics_step"``)
STEP_TERMS = ("slide_per_m",)


def _sampling(task) -> str:
    """How ``task``'s gait terms sample the feet (``gait_sampling``; ``control_tick`` for a task without the option)."""
    return getattr(task, "sampling", None) or getattr(getattr(task, "options", None), "gait_sampling", "control_tick")


@dataclass(frozen=True, kw_only=True)
class StopOptions:
    """The stopping rule (``[stop]``)."""

    when: str = option("", "stop early: `walking` (the evaluation walkers meet the walking criteria), `fitness` (their "
                       "mean fitness reaches `above`), or empty (run every generation)",
                       choices=("", "walking", "fitness"))
    above: float = option(0.0, "with when = fitness: the fitness to reach")
    generations: int = option(3, "generations running the condition must hold", low=1, high=10**6, integer=True)

    def __post_init__(self):
        check_fields(self, "stop")
        if not np.isfinite(self.above):
            raise ConfigError(f"stop.above: must be finite, got {self.above!r}")

    @property
    def active(self) -> bool:
        return bool(self.when)

    def check(self, task) -> None:
        """ConfigError (one line) when the task cannot tell what the rule asks."""
        if self.when == "walking":
            needed = WALKING_TERMS + (STEP_TERMS if _sampling(task) == "physics_step" else ())
            missing = [t for t in needed if t not in task.term_names]
            if missing:
                raise ConfigError("stop.when = 'walking' needs the walk task's gait terms (task_options gait_terms = "
                                  f"true and fitness = 'weighted'); task {task.name!r} lacks {', '.join(missing)}")

    def met(self, terms: dict, fell: np.ndarray, fitness: np.ndarray) -> bool:
        """Whether the evaluation walkers meet the condition this generation: ``terms`` (each ``(n,)``) and ``fell``
        ``(n,)`` of each of their presentations, ``fitness`` ``(k,)`` of each walker."""
        if not len(fell):
            return False
        if self.when == "fitness":
            return bool(np.mean(fitness) >= self.above)
        from ..analysis.gait_report import criteria_for, failed_criteria

        sampling = "physics_step" if all(t in terms for t in STEP_TERMS) else "control_tick"  # the terms say which
        for i in range(len(fell)):  # every presentation of every evaluation walker
            one = {k: float(terms[k][i]) for k in WALKING_TERMS + (STEP_TERMS if sampling == "physics_step" else ())}
            one["speed"] = one["forward"] / one["time_up"] if one["time_up"] > 0 else 0.0
            one["heading_deg"] = 0.0  # not measured during a run (see the module docstring)
            if fell[i] or failed_criteria(one, criteria_for(sampling)):
                return False
        return True


def streak(record: list[dict]) -> int:
    """Generations running, up to the last, whose record says the rule was met."""
    n = 0
    for entry in reversed(record):
        if not entry.get("stop_met"):  # run_context.STOP_COLUMN
            break
        n += 1
    return n


def _patience(v) -> None:
    if not (isinstance(v, list) and all(isinstance(x, int) and not isinstance(x, bool) and 1 <= x <= 10**6 for x in v)):
        raise ConfigError(f"must be a list of whole numbers of generations in [1, 1e6], one per phase, got {v!r}")


def _fallen(v) -> None:
    if not (isinstance(v, list) and all(isinstance(x, int) and not isinstance(x, bool) and 0 <= x <= 10**6 for x in v)):
        raise ConfigError(f"must be a list of whole numbers of generations in [0, 1e6], one per phase, got {v!r}")


@dataclass(frozen=True, kw_only=True)
class RestartOptions:
    """The lost-run rule (``[restart]``; none by default)."""

    patience: list = option([], "the generations each curriculum phase may take within an attempt (one per phase; one "
                            "without a curriculum; empty: a run is never lost)", check=_patience)
    action: str = option("restart", "what a lost run does: `restart` (start over within the budget), `stop`, or "
                         "`warn` (say so and go on)", choices=("restart", "stop", "warn"))
    max_restarts: int = option(10, "restarts at most; a run lost once more stops", low=0, high=10**4, integer=True)
    fallen_for: list = option([], "per phase (as patience): it is lost sooner when its evaluation walkers fell in this "
                              "many generations running (0: never; empty: never in any phase)", check=_fallen)

    @property
    def active(self) -> bool:
        return bool(self.patience)

    def __post_init__(self):
        check_fields(self, "restart")
        if self.fallen_for and len(self.fallen_for) != len(self.patience):
            raise ConfigError(f"restart.fallen_for: one entry per entry of restart.patience ({len(self.patience)}), "
                              f"got {len(self.fallen_for)}")

    def check(self, phases: int, optimizer) -> None:
        """ConfigError (one line) when ``patience`` does not give each of the ``phases`` (0: no curriculum) its
        entry, or ``optimizer`` (its class) cannot start over."""
        if not self.active:
            return
        wanted = max(phases, 1)
        if len(self.patience) != wanted:
            raise ConfigError(f"restart.patience: one entry per curriculum phase ({wanted}), got {len(self.patience)}")
        if self.action == "restart" and not optimizer.starts_over:
            raise ConfigError(f"restart.action = 'restart': optimizer {optimizer.name!r} cannot start over "
                              "(es and ga can); use action = 'stop' or 'warn'")


@dataclass
class Attempts:
    """The lost-run rule's record: the attempt (0: the first), the generation its current phase began, the generations
    running its evaluation walkers fell (``fallen``), and each lost phase as ``{generation, phase, action, why}``."""

    attempt: int = 0
    phase_since: int = 0
    lost: list = field(default_factory=list)
    fallen: int = 0

    def check(self, options: RestartOptions, generation: int, phase: int, moved_on: bool,
              fell: bool = False) -> str | None:
        """After generation ``generation`` (scored in ``phase``; ``moved_on``: the curriculum advanced after it;
        ``fell``: its evaluation walkers fell): what the rule does now, ``restart``, ``stop``, ``warn`` or None (not
        lost), recorded."""
        self.fallen = self.fallen + 1 if fell else 0
        if moved_on:
            self.phase_since, self.fallen = generation + 1, 0
            return None
        taken = generation + 1 - self.phase_since
        down = bool(options.fallen_for) and self.fallen == options.fallen_for[phase] > 0
        if not options.active or not (taken == options.patience[phase] or down):
            return None
        action = options.action
        if action == "restart" and self.attempt >= options.max_restarts:
            action = "stop"
        self.lost.append({"generation": generation, "phase": phase, "action": action,
                          "why": "fallen" if down and taken != options.patience[phase] else "patience"})
        if action == "restart":
            self.attempt, self.phase_since, self.fallen = self.attempt + 1, generation + 1, 0
        return action

    @property
    def stopped(self) -> bool:
        """The rule stopped the run."""
        return bool(self.lost) and self.lost[-1]["action"] == "stop"

    def to_dict(self) -> dict:
        return {"attempt": self.attempt, "phase_since": self.phase_since, "lost": list(self.lost),
                "fallen": self.fallen}

    @classmethod
    def from_dict(cls, table) -> "Attempts":
        """Read :meth:`to_dict` back (UserError, one line, when malformed)."""
        ok = (isinstance(table, dict) and all(isinstance(table.get(k), int) and not isinstance(table.get(k), bool)
                                               and table[k] >= 0 for k in ("attempt", "phase_since", "fallen"))
              and isinstance(table.get("lost"), list)
              and all(isinstance(e, dict) and e.get("action") in ("restart", "stop", "warn") for e in table["lost"]))
        if not ok:
            raise UserError(f"checkpoint: restarts must be {{attempt, phase_since, lost, fallen}}, got {table!r}")
        return cls(table["attempt"], table["phase_since"], list(table["lost"]), table["fallen"])
