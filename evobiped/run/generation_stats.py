"""One generation's statistics (a row of history.csv plus what a progress display needs) and the files it leaves to
its commit."""

from __future__ import annotations

from dataclasses import dataclass

from ..files.rundir import HISTORY_COLUMNS


@dataclass
class GenerationStats:
    """One row of history.csv plus what a progress display needs."""

    generation: int
    best: float
    mean: float
    median: float
    worst: float
    evaluations: int
    falls: int
    unstable: int
    wall_seconds: float
    best_fell: bool = False
    evals_per_second: float = 0.0
    generations_total: int = 0
    #: simulated seconds of this generation's evaluations, every presentation's row until it ended (a fall or T)
    simulated_seconds: float = 0.0
    #: the longest of those episodes (s): the batches wait for their longest row
    longest_seconds: float = 0.0

    def row(self) -> list:
        return [getattr(self, c) for c in HISTORY_COLUMNS]


@dataclass(frozen=True)
class GenerationFiles:
    """What an evaluated generation writes at its commit, before checkpoint.json (:func:`.checkpoint.commit`)."""

    generation: int
    #: generations/gen_NNNN.json's text (the generation's best, its context frozen in)
    text: str
    #: individuals.jsonl's tables, one per row of the population (:meth:`.individuals.Individuals.records`)
    individuals: list[dict]
