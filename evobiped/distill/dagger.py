"""DAgger's loop (:func:`distill`): roll out, label, refit, iteration after iteration; then the best student
(:func:`select`)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..episode import EpisodeConfig
from ..analysis.selection import best_candidate, try_candidates
from .fit import Fitter
from .settings import DistillOptions
from .rollouts import Rollouts, collect


@dataclass
class DistillReport:
    """What a distillation did: per iteration the teacher's share, data size (ticks), fit error (rad) and how the
    student alone fared (its 50 s episode: fell, end time s, distance m, heading deg)."""

    genome: np.ndarray
    config: EpisodeConfig
    iterations: list[dict]
    #: the iteration (1-based) whose student :attr:`genome` is
    chosen: int = 0


def distill(teacher_cfg: EpisodeConfig, teacher_genome: np.ndarray, *, student: EpisodeConfig, options: DistillOptions,
            seed: int = 0, progress: Callable[[str], None] | None = None,
            steps_done: Callable[[int], None] | None = None) -> DistillReport:
    """DAgger from ``teacher_genome`` into the ``student`` episode's ctrnn; see the module docstring.  ``progress``
    hears a line at each stage; ``steps_done`` (optional) the fitting steps done so far, of iterations x steps,
    before each line (what a time left is reckoned from)."""
    say = progress or (lambda line: None)
    done = steps_done or (lambda n: None)
    fitter = Fitter(student, options, seed)
    episode = student.build()  # the student alone, each iteration's
    data: list[Rollouts] = []
    rows, students = [], []
    for i in range(options.iterations):
        beta = 1.0 if i == 0 else options.beta0 * 0.5 ** (i - 1)
        data.append(collect(teacher_cfg, teacher_genome, student, fitter.student_genome, beta=beta, options=options,
                            key=(seed, i)))
        ticks = int(sum(d.alive.sum() for d in data))
        rmse = fitter.fit(data, progress=lambda s, e: (done(i * options.steps + s),
                                                       say(f"iteration {i + 1}/{options.iterations}: step "
                                                           f"{s}/{options.steps}, window RMS error {e:.4f} rad")))
        students.append(fitter.student_genome.copy())
        alone = episode.run(students[-1])
        walk = alone.walk()
        row = dict(iteration=i + 1, teacher_share=beta, ticks=ticks, rms_error=round(rmse, 5), fell=bool(alone.fell[0]),
                   end_time=float(alone.end_time[0]), distance=round(walk["distance"], 3),
                   heading_deg=walk["heading_deg"])
        rows.append(row)
        say(f"iteration {i + 1}/{options.iterations}: teacher share {beta:g}, {ticks} ticks, RMS error {rmse:.4f} rad; "
            f"student alone: {'fell at %.1f s' % row['end_time'] if row['fell'] else 'up %g s' % row['end_time']}, "
            f"{row['distance']:.2f} m")
    chosen = select(student, students, rows, options, say)
    return DistillReport(genome=students[chosen], config=student, iterations=rows, chosen=chosen + 1)


def select(student: EpisodeConfig, genomes: list[np.ndarray], rows: list[dict], options: DistillOptions,
           say: Callable[[str], None]) -> int:
    """The index of the best student (:func:`evobiped.analysis.selection.best_candidate` over their runs alone); adds
    ``up_long`` (bool: up through ``select_seconds``) to the row of every student."""
    if options.select_seconds <= 0:
        return len(genomes) - 1
    trials = try_candidates(student, np.array(genomes), options.select_seconds)
    for row, t in zip(rows, trials):
        row["up_long"] = bool(t.get("up_long", False))
    best = best_candidate(trials, options.heading_limit)
    say(f"selected iteration {best + 1}'s student (up {options.select_seconds:g} s: "
        + ", ".join(f"{i + 1}: {'yes' if r['up_long'] else 'no'}" for i, r in enumerate(rows)) + ")")
    return best
