"""Evaluation backends behind one interface: serial, a process pool, threads, Ray (:mod:`.ray_backend`).

Every backend builds the episode (and so the MuJoCo model) once per worker and
keeps its workers across generations.  A genome's result depends on that genome
alone (episodes are deterministic and batch-independent), so a run's history
does not depend on the backend or on the number of workers.
"""

from __future__ import annotations

import os
import queue
import signal
from abc import ABC, abstractmethod
from concurrent.futures import ThreadPoolExecutor
from concurrent.futures.process import BrokenProcessPool
import dataclasses

import numpy as np

from ..episode import Context, Episode, EpisodeConfig
from ..episode.result import EpisodeResult
from ..core.errors import ConfigError, UserError
from .pool import spawn_pool, stop_pool

BACKENDS = ("serial", "process", "thread", "ray")

#: memory one local worker takes at most, in bytes (a process or Ray actor: Python, MuJoCo, an episode; a thread: an episode)
WORKER_BYTES = {"process": 256 * 2**20, "ray": 512 * 2**20, "thread": 64 * 2**20}
#: local workers per core beyond which more only cost memory (they share the cores)
WORKERS_PER_CORE = 8


def worker_limit(backend: str) -> int:
    """The most local workers of ``backend`` this machine is given: :data:`WORKERS_PER_CORE` per core, and as many
    as fit in half its memory at :data:`WORKER_BYTES` each."""
    memory = os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    return max(1, min(WORKERS_PER_CORE * (os.cpu_count() or 1), int(memory / 2 // WORKER_BYTES.get(backend, WORKER_BYTES["ray"]))))


def check_worker_count(backend: str, workers: int | None, address: str | None = None, name: str = "workers") -> None:
    """ConfigError (one line) when ``workers`` local workers of ``backend`` exceed :func:`worker_limit`, before any
    starts (a cluster's, ``address`` given, are the cluster's to count: :class:`~.ray_backend.RayEvaluator`)."""
    if workers is None or backend == "serial" or address is not None:
        return
    limit = worker_limit(backend)
    if workers > limit:
        memory = os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
        raise ConfigError(f"{name} {workers}: this machine ({os.cpu_count() or 1} cores, {memory / 2**30:.3g} GiB) runs at most "
                          f"{limit} {backend} workers")


def _evaluate(episode: Episode, genomes: np.ndarray, key: tuple[int, int] | None = None,
              context: Context | None = None) -> EpisodeResult:
    """Run ``genomes`` under the perturbed presentations of ``key`` = (run seed, generation), or nominally (None),
    in the run's ``context`` for this generation (normaliser, collected senses, fitness weights)."""
    return episode.run(genomes, trials=episode.trials_for(key), context=context)


def concat(parts: list[EpisodeResult]) -> EpisodeResult:
    """The results of consecutive batches as one, every field joined along its first axis (genomes, or simulation rows)."""
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
    return EpisodeResult(**{f.name: join([getattr(p, f.name) for p in parts]) for f in dataclasses.fields(EpisodeResult)})


def chunks(n: int, size: int | None, workers: int = 1) -> list[slice]:
    """Slices of at most ``size`` genomes; ``size=None``: about two batches per worker.

    Bigger batches share the per-tick Python work among more simulations;
    several per worker still balance the load when walkers fall early.
    """
    if size is None:
        size = max(1, -(-n // (2 * workers)))
    return [slice(i, min(i + size, n)) for i in range(0, n, size)]


class Evaluator(ABC):
    """Evaluates genomes ``(N, G)``; use as a context manager to release workers."""

    def __init__(self, episode: EpisodeConfig):
        self.config = episode

    @abstractmethod
    def evaluate(self, genomes: np.ndarray, key: tuple[int, int] | None = None, context: Context | None = None) -> EpisodeResult:
        """The episode results of ``genomes`` (fitness and outcome, ``(N,)`` each); ``key`` = (run seed, generation)
        draws the episode's perturbations; ``context``: what the run sets for this generation."""

    def close(self) -> None:
        pass

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


class SerialEvaluator(Evaluator):
    """All genomes in one batch in this process."""

    def __init__(self, episode: EpisodeConfig):
        super().__init__(episode)
        self.episode = episode.build()

    def evaluate(self, genomes, key=None, context=None):
        return _evaluate(self.episode, genomes, key, context)


# ---- process pool: one Episode per worker process, built by the initializer
_worker_episode: Episode | None = None

#: times a generation's lost batches are sent again after worker deaths before the run gives up
MAX_RETRIES = 3


def _init_worker(config: EpisodeConfig) -> None:
    global _worker_episode
    _worker_episode = config.build()


def _fault_marker_taken() -> bool:
    """Testing hook: with ``EVOBIPED_FAULT_KILL_WORKER=FILE``, True for the first caller to find FILE (it deletes it)."""
    marker = os.environ.get("EVOBIPED_FAULT_KILL_WORKER")
    if not marker:
        return False
    try:
        os.unlink(marker)
    except FileNotFoundError:
        return False
    return True


def _fault_point() -> None:
    """Testing hook of the process pool and Ray: the worker that takes the marker SIGKILLs itself."""
    if _fault_marker_taken():
        os.kill(os.getpid(), signal.SIGKILL)


def _thread_fault_point() -> None:
    """Testing hook of the thread backend: the batch that takes the marker dies as a thread's batch can (MemoryError)."""
    if _fault_marker_taken():
        raise MemoryError("testing hook")


def _work(job: tuple) -> EpisodeResult:
    _fault_point()
    return _evaluate(_worker_episode, *job)


class ProcessPoolEvaluator(Evaluator):
    """A persistent pool of ``workers`` processes; genomes go out in small batches.

    Batches of ``chunk`` genomes (default: about two per worker) balance the load (walkers that fall early cost
    little, stable walkers the full episode).  A worker that dies (killed, out of memory) breaks the pool: a
    fresh pool evaluates the batches it lost again, at most :data:`MAX_RETRIES` times per generation, and
    ``on_retry(n, MAX_RETRIES)`` is told each time.  The results are those of an undisturbed run, since a
    genome's fate depends on that genome alone.
    """

    backend = "process"

    def __init__(self, episode: EpisodeConfig, workers: int, chunk: int | None = None, on_retry=None):
        super().__init__(episode)
        if workers < 1:
            raise ConfigError(f"workers must be >= 1, got {workers}")
        check_worker_count(self.backend, workers)
        self.workers, self.chunk, self.on_retry = int(workers), chunk, on_retry
        self.pool = self._new_pool()

    def _new_pool(self):
        return spawn_pool(self.workers, _init_worker, (self.config,))

    def evaluate(self, genomes, key=None, context=None):
        genomes = np.asarray(genomes, float)
        jobs = [(genomes[s], key, context) for s in chunks(len(genomes), self.chunk, self.workers)]
        parts: list[EpisodeResult | None] = [None] * len(jobs)
        deaths = 0
        while True:
            futures = {}
            try:  # a worker may die at any moment: while batches are fed (submit), collected, or between generations
                for i in (i for i, p in enumerate(parts) if p is None):
                    futures[i] = self._submit(jobs[i])
                for i, f in futures.items():
                    parts[i] = f.result()
                return concat(parts)
            except BrokenProcessPool:
                for i, f in futures.items():  # keep what finished before the death
                    if parts[i] is None and f.done() and not f.cancelled() and f.exception() is None:
                        parts[i] = f.result()
                deaths += 1
                self._replace_pool()
                if deaths > MAX_RETRIES:
                    raise UserError(f"evaluation workers died {deaths} times in one generation (out of memory? killed?); "
                                    "the last checkpoint is kept: resume the run with evobiped evolve --resume") from None
                if self.on_retry is not None:
                    self.on_retry(deaths, MAX_RETRIES)

    def _submit(self, job):
        """Send one batch; a pool that breaks while it starts its workers (one killed as the next is spawned: the
        pipe they share is closed under it) is a broken pool like any other."""
        try:
            return self.pool.submit(_work, job)
        except (OSError, ValueError) as exc:
            raise BrokenProcessPool(f"the pool broke while starting its workers ({exc})") from None

    def _replace_pool(self) -> None:
        """Stop the broken pool (its survivors included) and start a fresh one (its workers start at the next submit)."""
        stop_pool(self.pool)
        self.pool = self._new_pool()

    def close(self):
        stop_pool(self.pool)


class ThreadEvaluator(Evaluator):
    """``workers`` threads in this process, each with its own Episode (and MuJoCo batch).

    MuJoCo steps a batch with the GIL released, so one thread's physics runs while
    another does its per-tick Python work: no process start, no pickling.  Batches as
    in the process pool (``chunk``: default about two per worker).  A batch whose thread runs out of memory is
    evaluated again, at most :data:`MAX_RETRIES` times per generation (``on_retry`` as in the process pool).
    """

    backend = "thread"

    def __init__(self, episode: EpisodeConfig, workers: int, chunk: int | None = None, on_retry=None):
        super().__init__(episode)
        if workers < 1:
            raise ConfigError(f"workers must be >= 1, got {workers}")
        check_worker_count(self.backend, workers)
        self.workers, self.chunk, self.on_retry = int(workers), chunk, on_retry
        self._episodes: queue.SimpleQueue[Episode] = queue.SimpleQueue()
        for _ in range(self.workers):
            self._episodes.put(episode.build())
        self.pool = ThreadPoolExecutor(self.workers, thread_name_prefix="evobiped-eval")

    def _work(self, genomes: np.ndarray, key, context) -> EpisodeResult:
        _thread_fault_point()
        episode = self._episodes.get()  # a free one: no two threads share an Episode
        try:
            return _evaluate(episode, genomes, key, context)
        finally:
            self._episodes.put(episode)

    def evaluate(self, genomes, key=None, context=None):
        genomes = np.asarray(genomes, float)
        pieces = [genomes[s] for s in chunks(len(genomes), self.chunk, self.workers)]
        parts: list[EpisodeResult | None] = [None] * len(pieces)
        deaths = 0
        while True:
            futures = {i: self.pool.submit(self._work, pieces[i], key, context) for i, p in enumerate(parts) if p is None}
            lost = False
            for i, f in futures.items():
                try:
                    parts[i] = f.result()
                except MemoryError:  # the one way a thread's batch dies alone: the others' results stand
                    lost = True
            if not lost:
                return concat(parts)
            deaths += 1
            if deaths > MAX_RETRIES:
                raise UserError(f"evaluation threads ran out of memory {deaths} times in one generation; "
                                "the last checkpoint is kept: resume the run with evobiped evolve --resume")
            if self.on_retry is not None:
                self.on_retry(deaths, MAX_RETRIES)

    def close(self):
        self.pool.shutdown(wait=True)


def make_evaluator(episode: EpisodeConfig, backend: str = "process", workers: int | None = None, address: str | None = None,
                   on_retry=None) -> Evaluator:
    """The evaluator for a backend name; ``workers`` defaults to all cores; ``on_retry(n, limit)``: a batch of the
    process pool or of the threads is evaluated again after its worker died."""
    if backend not in BACKENDS:
        raise ConfigError(f"unknown backend {backend!r} (choose from {', '.join(BACKENDS)})")
    if workers is not None and workers < 1:
        raise ConfigError(f"workers must be >= 1, got {workers}")
    check_worker_count(backend, workers, address)
    episode.check()  # here, once, whatever the backend: a worker never meets a bad value
    if backend == "serial":
        return SerialEvaluator(episode)
    if backend == "ray":
        from .ray_backend import RayEvaluator

        return RayEvaluator(episode, workers, address)
    if backend == "thread":
        return ThreadEvaluator(episode, workers or os.cpu_count() or 1, on_retry=on_retry)
    return ProcessPoolEvaluator(episode, workers or os.cpu_count() or 1, on_retry=on_retry)
