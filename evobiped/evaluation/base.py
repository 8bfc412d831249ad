"""The one interface of the evaluation backends (:class:`Evaluator`) and what they share: a batch evaluated in an
episode (:func:`evaluate_batch`), genomes cut into batches (:func:`chunks`) and their results joined (:func:`concat`),
and the one retry loop of the local backends whose batches can be lost (:class:`RetryingEvaluator`).

Every backend builds the episode (and so the MuJoCo model) once per worker and
keeps its workers across generations.  A genome's result depends on that genome
alone (episodes are deterministic and batch-independent), so a run's history
does not depend on the backend or on the number of workers.
"""

from __future__ import annotations

import dataclasses
from abc import ABC, abstractmethod
from typing import Callable, ClassVar

import numpy as np

from ..core.errors import ConfigError, UserError
from ..episode import Context, Episode, EpisodeConfig
from ..episode.result import EpisodeResult
from .faults import FaultHook
from .limits import check_worker_count

#: times a generation's lost batches are sent again after worker deaths before the run gives up
MAX_RETRIES = 3


def evaluate_batch(episode: Episode, genomes: np.ndarray, key: tuple[int, int] | None = None,
                   context: Context | None = None) -> EpisodeResult:
    """Run ``genomes`` ``(n, G)`` under the perturbed presentations of ``key`` = (run seed, generation), or nominally
    (None), in the run's ``context`` for this generation (normaliser, collected senses, fitness weights)."""
    return episode.run(genomes, trials=episode.trials_for(key), context=context)


def concat(parts: list[EpisodeResult]) -> EpisodeResult:
    """The results of consecutive batches as one, every field joined along its first axis (genomes, or simulation
    rows)."""
    def join(values: list):
        first = values[0]
        if first is None:
            return None
        if isinstance(first, EpisodeResult):
            return concat(values)
        if isinstance(first, dict):
            return {k: join([v[k] for v in values]) for k in first}
        return np.concatenate(values)

    if len(parts) == 1:
        return parts[0]
    return EpisodeResult(**{f.name: join([getattr(p, f.name) for p in parts])
                            for f in dataclasses.fields(EpisodeResult)})


def chunks(n: int, size: int | None, workers: int = 1) -> list[slice]:
    """Slices of at most ``size`` genomes; ``size=None``: one batch per worker, as even as can be.

    An episode's Python work per control tick costs about the same for 15 simulations as for 60, so the fewer the
    batches, the less of it each simulated second pays; a worker whose batch ends early (its walkers fell) waits for
    the others (docs/performance.md measures both).
    """
    if size is None:
        size = max(1, -(-n // workers))
    return [slice(i, min(i + size, n)) for i in range(0, n, size)]


class Evaluator(ABC):
    """Evaluates genomes ``(N, G)``; use as a context manager to release workers."""

    def __init__(self, episode: EpisodeConfig):
        self.config = episode

    @abstractmethod
    def evaluate(self, genomes: np.ndarray, key: tuple[int, int] | None = None,
                 context: Context | None = None) -> EpisodeResult:
        """The episode results of ``genomes`` (fitness and outcome, ``(N,)`` each); ``key`` = (run seed, generation)
        draws the episode's perturbations; ``context``: what the run sets for this generation."""

    def close(self) -> None:
        pass

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


#: a batch's job: its genomes ``(n, G)``, the generation's key and context
Job = tuple


class RetryingEvaluator(Evaluator):
    """``workers`` local workers (processes or threads) of ``backend``; genomes go out in batches of ``chunk`` (default:
    about two per worker, :func:`chunks`), which balance the load (walkers that fall early cost little, stable
    walkers the full episode).  A batch whose worker is lost is evaluated again, at most :data:`MAX_RETRIES` times
    per generation, and ``on_retry(n, MAX_RETRIES)`` is told each time; the results are those of an undisturbed run,
    since a genome's fate depends on that genome alone.  ``fault``: the testing hook the workers take
    (:class:`~.faults.FaultHook`; None: the one the environment names, read once, here)."""

    #: the backend's name (:data:`~.backends.BACKENDS`)
    backend: ClassVar[str] = ""
    #: the UserError's words when batches are lost more than :data:`MAX_RETRIES` times (``{n}``: how many)
    lost: ClassVar[str] = ""

    def __init__(self, episode: EpisodeConfig, workers: int, chunk: int | None = None,
                 on_retry: Callable[[int, int], None] | None = None, fault: FaultHook | None = None):
        super().__init__(episode)
        if workers < 1:
            raise ConfigError(f"workers must be >= 1, got {workers}")
        check_worker_count(self.backend, workers)
        self.workers, self.chunk, self.on_retry = int(workers), chunk, on_retry
        self.fault = FaultHook.from_environment() if fault is None else fault

    def evaluate(self, genomes, key=None, context=None):
        genomes = np.asarray(genomes, float)
        jobs = [(genomes[s], key, context) for s in chunks(len(genomes), self.chunk, self.workers)]
        parts: list[EpisodeResult | None] = [None] * len(jobs)
        losses = 0
        while not self._run(jobs, parts):
            losses += 1
            self._recover()
            if losses > MAX_RETRIES:
                raise UserError(self.lost.format(n=losses) + "; the last checkpoint is kept: resume the run with "
                                                             "evobiped evolve --resume")
            if self.on_retry is not None:
                self.on_retry(losses, MAX_RETRIES)
        return concat(parts)

    @abstractmethod
    def _run(self, jobs: list[Job], parts: list[EpisodeResult | None]) -> bool:
        """Evaluate every job whose part is None into ``parts``; False when a worker was lost (the parts of the
        batches that finished are kept, the others stay None)."""

    def _recover(self) -> None:
        """Make the workers whole again after a loss (default: nothing to do)."""
