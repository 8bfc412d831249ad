"""The thread backend: threads in this process, each with its own Episode (and MuJoCo batch)."""

from __future__ import annotations

import queue
from concurrent.futures import ThreadPoolExecutor

from ..episode import Episode, EpisodeConfig
from ..episode.result import EpisodeResult
from .base import RetryingEvaluator, evaluate_batch
from .faults import FaultHook


class ThreadEvaluator(RetryingEvaluator):
    """``workers`` threads in this process, each with its own Episode (and MuJoCo batch).

    MuJoCo steps a batch with the GIL released, so one thread's physics runs while
    another does its per-tick Python work: no process start, no pickling.  Batches and retries as in
    :class:`~.base.RetryingEvaluator`: a batch whose thread runs out of memory is evaluated again.
    """

    backend = "thread"
    lost = "evaluation threads ran out of memory {n} times in one generation"

    def __init__(self, episode: EpisodeConfig, workers: int, chunk: int | None = None, on_retry=None,
                 fault: FaultHook | None = None):
        super().__init__(episode, workers, chunk, on_retry, fault)
        self._episodes: queue.SimpleQueue[Episode] = queue.SimpleQueue()
        for _ in range(self.workers):
            self._episodes.put(episode.build())
        self.pool = ThreadPoolExecutor(self.workers, thread_name_prefix="evobiped-eval")

    def _work(self, genomes, key, context) -> EpisodeResult:
        self.fault.fail_batch()
        episode = self._episodes.get()  # a free one: no two threads share an Episode
        try:
            return evaluate_batch(episode, genomes, key, context)
        finally:
            self._episodes.put(episode)

    def _run(self, jobs, parts) -> bool:
        futures = {i: self.pool.submit(self._work, *jobs[i]) for i, p in enumerate(parts) if p is None}
        lost = False
        for i, f in futures.items():
            try:
                parts[i] = f.result()
            except MemoryError:  # the one way a thread's batch dies alone: the others' results stand
                lost = True
        return not lost

    def close(self):
        self.pool.shutdown(wait=True)
