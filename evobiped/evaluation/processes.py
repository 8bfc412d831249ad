"""The process-pool backend: a persistent pool of spawned processes, one Episode each, built by the initializer."""

from __future__ import annotations

from concurrent.futures.process import BrokenProcessPool

from ..episode import Episode, EpisodeConfig
from ..episode.result import EpisodeResult
from .base import RetryingEvaluator, evaluate_batch
from .faults import FaultHook
from .pool import FEW_BYTES, spawn_pool, stop_pool

# ---- in a worker process: its Episode and testing hook, set by the initializer
_worker_episode: Episode | None = None
_worker_fault = FaultHook()


def _init_worker(config: EpisodeConfig, fault: FaultHook) -> None:
    global _worker_episode, _worker_fault
    _worker_episode, _worker_fault = config.build(), fault


def _work(job: tuple) -> EpisodeResult:
    _worker_fault.kill_process()
    return evaluate_batch(_worker_episode, *job)


#: below this many file descriptors (``ulimit -n``) a pool's workers may die of too few: said when they do
FEW_DESCRIPTORS = 256


class ProcessPoolEvaluator(RetryingEvaluator):
    """A persistent pool of ``workers`` processes (:class:`~.base.RetryingEvaluator`: batches, retries).  A worker that
    dies (killed, out of memory) breaks the pool: a fresh pool evaluates the batches it lost again."""

    backend = "process"
    @property
    def lost(self) -> str:
        """Why the workers died, as far as this process can tell: a low ``ulimit -n`` (each worker takes pipes and
        semaphores), else memory or a kill."""
        import resource

        soft = resource.getrlimit(resource.RLIMIT_NOFILE)[0]
        low = soft != resource.RLIM_INFINITY and soft < FEW_DESCRIPTORS
        files = (f"too many open files? this process may open {soft} (ulimit -n): raise the limit (ulimit -n 1024) or "
                 "give fewer --workers; ") if low else ""
        space = resource.getrlimit(resource.RLIMIT_AS)[0]
        if space != resource.RLIM_INFINITY and space < FEW_BYTES:
            files += (f"too little address space? each worker may take {space // 1024:,} KiB "
                      f"(ulimit -v {space // 1024}): "
                      "raise the limit (ulimit -v unlimited); ")
        return "evaluation workers died {n} times in one generation (" + files + "out of memory? killed?)"

    def __init__(self, episode: EpisodeConfig, workers: int, chunk: int | None = None, on_retry=None,
                 fault: FaultHook | None = None):
        super().__init__(episode, workers, chunk, on_retry, fault)
        self.pool = self._new_pool()

    def _new_pool(self):
        return spawn_pool(self.workers, _init_worker, (self.config, self.fault))

    def _run(self, jobs, parts) -> bool:
        futures = {}
        try:  # a worker may die at any moment: while batches are fed (submit), collected, or between generations
            for i in (i for i, p in enumerate(parts) if p is None):
                futures[i] = self._submit(jobs[i])
            for i, f in futures.items():
                parts[i] = f.result()
            return True
        except BrokenProcessPool:
            for i, f in futures.items():  # keep what finished before the death
                if parts[i] is None and f.done() and not f.cancelled() and f.exception() is None:
                    parts[i] = f.result()
            return False

    def _submit(self, job):
        """Send one batch; a pool that breaks while it starts its workers (one killed as the next is spawned: the
        pipe they share is closed under it) is a broken pool like any other."""
        try:
            return self.pool.submit(_work, job)
        except (OSError, ValueError) as exc:
            raise BrokenProcessPool(f"the pool broke while starting its workers ({exc})") from None

    def _recover(self) -> None:
        """Stop the broken pool (its survivors included) and start a fresh one (its workers start at the next
        submit)."""
        stop_pool(self.pool)
        self.pool = self._new_pool()

    def close(self):
        stop_pool(self.pool)
