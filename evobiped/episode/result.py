"""What an episode gives back: each individual's fitness, fall, end time, positions and the task's terms.

:class:`EpisodeResult` is a value (arrays over the population); :func:`walk_summary` is how runs and replays
report one walk.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass
class EpisodeResult:
    """Per-individual outcome, every array ``(P,)`` (positions and facings ``(P, 2)``, or ``(P, S, 2)`` for S
    presentations)."""

    fitness: np.ndarray
    fell: np.ndarray
    unstable: np.ndarray
    end_time: np.ndarray
    start_position: np.ndarray
    end_position: np.ndarray
    #: the direction each walker faced at the start, unit vectors on the ground plane (``Body.heading`` after reset)
    start_facing: np.ndarray
    #: per simulation row (one per genome and presentation) when the task has several presentations
    rows: "EpisodeResult | None" = None
    #: the task's fitness terms by name (``Task.term_names``): ``(P,)`` per simulation row, ``(P, S)`` per genome
    #: of S rows (presentations x trials, as the positions)
    terms: dict[str, np.ndarray] = field(default_factory=dict)
    #: what each individual sensed over its presentations, when collected (``Context.observe``): ``count`` ``(P,)``
    #: control ticks up, ``total`` and ``squares`` ``(P, k)`` sums of its inputs and their squares (None: not collected)
    senses: dict[str, np.ndarray] | None = None

    def displacements(self) -> tuple[np.ndarray, np.ndarray]:
        """Where each walker went in its first presentation: displacement ``(P, 2)`` m and direction ``(P,)``
        degrees (see :func:`evobiped.tasks.walk.displacement_heading`; NaN: it did not move)."""
        from ..tasks.walk import displacement_heading

        rows = self.rows if self.rows is not None else self
        S = len(rows.fitness) // len(self.fitness)
        a, b, f = rows.start_position[::S], rows.end_position[::S], rows.start_facing[::S]
        return b - a, displacement_heading(a, b, f)

    def walk(self, i: int = 0) -> dict:
        """Where walker ``i`` went (its first presentation when there are several), see :func:`walk_summary`."""
        d, h = self.displacements()
        return walk_summary(d[i], h[i])

    def per_genome(self, S: int, combine) -> "EpisodeResult":
        """Rows p * S + j -> one entry per genome: fitness combined by ``combine`` ``(P, S) -> (P,)``,
        fell/unstable if any presentation did, the earliest end; positions become ``(P, S, 2)``."""
        by = lambda a: a.reshape(-1, S, *a.shape[1:])  # noqa: E731
        return EpisodeResult(
            fitness=combine(by(self.fitness)),
            fell=by(self.fell).any(axis=1),
            unstable=by(self.unstable).any(axis=1),
            end_time=by(self.end_time).min(axis=1),
            start_position=by(self.start_position),
            end_position=by(self.end_position),
            start_facing=by(self.start_facing),
            rows=self,
            terms={k: by(v) for k, v in self.terms.items()},
            senses=None if self.senses is None else {k: by(v).sum(axis=1) for k, v in self.senses.items()},
        )


def walk_summary(displacement: np.ndarray, heading_deg: float) -> dict:
    """A walk as runs and replays report it: distance (m), direction (``heading_deg``, None: it did not move)
    and displacement (x, y) in m, from the displacement ``(2,)`` m and direction in degrees."""
    d, h = np.asarray(displacement, float)[None], float(heading_deg)
    return {"distance": float(np.linalg.norm(d, axis=1)[0]), "heading_deg": None if not np.isfinite(h) else round(h, 2),
            "displacement": [round(float(v), 4) for v in d[0]]}
