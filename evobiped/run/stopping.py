"""When a run is done before its last generation: the stopping rule (``[stop]`` in a run config).

``when = "walking"``: the run's evaluation walkers (ES's theta, else each generation's fittest) met the walking
criteria (:data:`evobiped.analysis.gait_report.WALKING`, from the walk task's gait terms: up the whole episode, at
least 0.3 m/s, each foot standing half the time, no flight, symmetric feet that do not slide) in the curriculum's last
phase for ``generations`` generations running.  ``when = "fitness"``: their mean fitness reached ``above`` as many
generations running.  The record of each generation (met or not) is part of the checkpoint's context, so a resumed run
stops where the uninterrupted one would.  The direction criterion is left to the walker test after the run (the gait
terms hold no heading).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..core.errors import ConfigError
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
                       "mean fitness reaches `above`), or empty (run every generation)", choices=("", "walking", "fitness"))
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
                raise ConfigError(f"stop.when = 'walking' needs the walk task's gait terms (task_options gait_terms = true "
                                  f"and fitness = 'weighted'); task {task.name!r} lacks {', '.join(missing)}")

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
