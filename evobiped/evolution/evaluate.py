"""Evaluation backends behind one interface: serial, a process pool, threads, Ray.

Every backend builds the episode (and so the MuJoCo model) once per worker and
keeps its workers across generations.  A genome's result depends on that genome
alone (episodes are deterministic and batch-independent), so a run's history
does not depend on the backend or on the number of workers.
"""

from __future__ import annotations

import os
import queue
import signal
import threading
from abc import ABC, abstractmethod
from concurrent.futures import ThreadPoolExecutor
from concurrent.futures.process import BrokenProcessPool
import dataclasses

import numpy as np

from ..episode import Episode, EpisodeConfig
from ..episode_result import EpisodeResult
from ..errors import STOP_SIGNALS, ConfigError, UserError
from ..net import connect_error
from .pool import silenced_stderr, spawn_pool, stop_pool

BACKENDS = ("serial", "process", "thread", "ray")


def _evaluate(episode: Episode, genomes: np.ndarray, key: tuple[int, int] | None = None) -> EpisodeResult:
    """Run ``genomes`` under the perturbed presentations of ``key`` = (run seed, generation), or nominally (None)."""
    return episode.run(genomes, trials=episode.trials_for(key))


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
    def evaluate(self, genomes: np.ndarray, key: tuple[int, int] | None = None) -> EpisodeResult:
        """The episode results of ``genomes`` (fitness and outcome, ``(N,)`` each); ``key`` = (run seed, generation)
        draws the episode's perturbations."""

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

    def evaluate(self, genomes, key=None):
        return _evaluate(self.episode, genomes, key)


# ---- process pool: one Episode per worker process, built by the initializer
_worker_episode: Episode | None = None

#: times a generation's lost batches are sent again after worker deaths before the run gives up
MAX_RETRIES = 3
#: seconds between checks, while a generation waits for Ray actors, that their nodes are alive
NODE_CHECK_PERIOD = 5.0


def _init_worker(config: EpisodeConfig) -> None:
    global _worker_episode
    _worker_episode = config.build()


def _fault_point() -> None:
    """Testing hook: with ``EVOBIPED_FAULT_KILL_WORKER=FILE`` the first worker to find FILE deletes it and SIGKILLs itself."""
    marker = os.environ.get("EVOBIPED_FAULT_KILL_WORKER")
    if marker:
        try:
            os.unlink(marker)
        except FileNotFoundError:
            return
        os.kill(os.getpid(), signal.SIGKILL)


def _thread_fault_point() -> None:
    """Testing hook of the thread backend: with ``EVOBIPED_FAULT_KILL_WORKER=FILE`` the first batch to find FILE deletes
    it and dies as a thread's batch can (MemoryError)."""
    marker = os.environ.get("EVOBIPED_FAULT_KILL_WORKER")
    if marker:
        try:
            os.unlink(marker)
        except FileNotFoundError:
            return
        raise MemoryError("testing hook")


def _work(job: tuple[np.ndarray, tuple[int, int] | None]) -> EpisodeResult:
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

    def __init__(self, episode: EpisodeConfig, workers: int, chunk: int | None = None, on_retry=None):
        super().__init__(episode)
        if workers < 1:
            raise ConfigError(f"workers must be >= 1, got {workers}")
        self.workers, self.chunk, self.on_retry = int(workers), chunk, on_retry
        self.pool = self._new_pool()

    def _new_pool(self):
        return spawn_pool(self.workers, _init_worker, (self.config,))

    def evaluate(self, genomes, key=None):
        genomes = np.asarray(genomes, float)
        jobs = [(genomes[s], key) for s in chunks(len(genomes), self.chunk, self.workers)]
        parts: list[EpisodeResult | None] = [None] * len(jobs)
        deaths = 0
        while True:
            futures = {}
            try:  # a worker may die at any moment: while batches are fed (submit), collected, or between generations
                for i in (i for i, p in enumerate(parts) if p is None):
                    futures[i] = self.pool.submit(_work, jobs[i])
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

    def __init__(self, episode: EpisodeConfig, workers: int, chunk: int | None = None, on_retry=None):
        super().__init__(episode)
        if workers < 1:
            raise ConfigError(f"workers must be >= 1, got {workers}")
        self.workers, self.chunk, self.on_retry = int(workers), chunk, on_retry
        self._episodes: queue.SimpleQueue[Episode] = queue.SimpleQueue()
        for _ in range(self.workers):
            self._episodes.put(episode.build())
        self.pool = ThreadPoolExecutor(self.workers, thread_name_prefix="evobiped-eval")

    def _work(self, genomes: np.ndarray, key) -> EpisodeResult:
        _thread_fault_point()
        episode = self._episodes.get()  # a free one: no two threads share an Episode
        try:
            return _evaluate(episode, genomes, key)
        finally:
            self._episodes.put(episode)

    def evaluate(self, genomes, key=None):
        genomes = np.asarray(genomes, float)
        pieces = [genomes[s] for s in chunks(len(genomes), self.chunk, self.workers)]
        parts: list[EpisodeResult | None] = [None] * len(pieces)
        deaths = 0
        while True:
            futures = {i: self.pool.submit(self._work, pieces[i], key) for i, p in enumerate(parts) if p is None}
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


def check_reachable(address: str, timeout: float = 5.0) -> None:
    """UserError unless ``host:port`` (or ``ray://host:port``) accepts a TCP connection.

    ``ray.init`` retries an unreachable address for a long time; this answers in
    at most ``timeout`` s.  ``auto`` and ``local`` are left to Ray.
    """
    if address in ("auto", "local"):
        return
    hostport = address.split("://", 1)[-1]
    host, _, port = hostport.rpartition(":")
    if not host or not port.isdigit():
        raise UserError(f"bad Ray address {address!r} (expected HOST:PORT, ray://HOST:PORT or auto)")
    why = connect_error(host, int(port), timeout)
    if why is not None:
        raise UserError(f"cannot reach a Ray cluster at {address}: {why}")


def init_ray(address: str | None, workers: int | None):
    """Connect to the cluster at ``address`` or start a local Ray on ``workers`` CPUs.

    Returns ``(ray module, True if we started it and must shut it down)``;
    UserError (one line) when Ray is missing or the cluster cannot be reached.
    """
    try:
        import ray
    except ImportError:
        raise UserError("the ray backend needs Ray: pip install 'evobiped[ray]'") from None
    if ray.is_initialized():
        return ray, False
    if address:
        check_reachable(address)
    handlers = {s: signal.getsignal(s) for s in (signal.SIGINT, *STOP_SIGNALS)}
    try:
        # no address: a fresh local instance, even where a cluster started by `ray start` is running
        kw = {"address": address} if address else {"address": "local", "num_cpus": workers or os.cpu_count()}
        with silenced_stderr():  # Ray's C++ client logs a warning per connection retry
            ray.init(include_dashboard=False, log_to_driver=False, logging_level="ERROR", **kw)
    except Exception as exc:  # ConnectionError, ValueError, RuntimeError, ...
        where = f" at {address}" if address else ""
        hint = ""
        if address and os.environ.get("RAY_AUTH_MODE") != "token":
            hint = " (a cluster with token authentication, the default since Ray 2.59, needs RAY_AUTH_MODE=token and its token: see `ray get-auth-token`)"
        raise UserError(f"cannot start or reach a Ray cluster{where}: {str(exc).splitlines()[0] if str(exc) else type(exc).__name__}{hint}") from None
    if threading.current_thread() is threading.main_thread():
        for s, h in handlers.items():  # ray.init puts its own in place (SIGTERM: exit status 15, no checkpoint line)
            if h is not None:
                signal.signal(s, h)
    return ray, True


class RayEvaluator(Evaluator):
    """Ray actors (one per CPU of the cluster, or ``workers``), each holding an Episode.

    An actor that dies is restarted and its batch sent again, at most :data:`MAX_RETRIES` times.  One lost for
    good, or one whose node died (checked every :data:`NODE_CHECK_PERIOD` s while a generation waits: Ray would
    wait forever for room to restart it), stops the generation with a UserError, the run's last checkpoint intact.
    """

    def __init__(self, episode: EpisodeConfig, workers: int | None = None, address: str | None = None, chunk: int | None = None):
        super().__init__(episode)
        ray, self._owns = init_ray(address, workers)
        self.ray = ray
        self.chunk = chunk
        n = workers or int(ray.cluster_resources().get("CPU", 1))

        # a worker that dies is restarted and its batch sent again (same result: fates depend on genomes alone)
        @ray.remote(num_cpus=1, max_restarts=MAX_RETRIES, max_task_retries=MAX_RETRIES)
        class _Worker:
            def __init__(self, config):
                self.episode = config.build()

            def evaluate(self, genomes, key):
                _fault_point()
                return _evaluate(self.episode, genomes, key)

            def node(self):
                return ray.get_runtime_context().get_node_id()

        self.actors = [_Worker.remote(episode) for _ in range(max(1, n))]
        self.nodes = set(ray.get([a.node.remote() for a in self.actors]))  # where they run

    def _check_nodes(self) -> None:
        """UserError if a node that runs one of the actors has died."""
        alive = {n["NodeID"] for n in self.ray.nodes() if n["Alive"]}
        if not self.nodes <= alive:
            raise UserError(f"a Ray node running this run's workers died ({len(self.nodes - alive)} of {len(self.nodes)} nodes lost); "
                            "the last checkpoint is kept: resume the run with evobiped evolve --resume")

    def evaluate(self, genomes, key=None):
        genomes = np.asarray(genomes, float)
        pieces = [genomes[s] for s in chunks(len(genomes), self.chunk, len(self.actors))]
        pool = self.ray.util.ActorPool(self.actors)
        for g in pieces:
            pool.submit(lambda a, g: a.evaluate.remote(g, key), g)
        parts = []
        try:
            while pool.has_next():
                try:
                    parts.append(pool.get_next(timeout=NODE_CHECK_PERIOD))
                except TimeoutError:
                    self._check_nodes()
            return concat(parts)
        except self.ray.exceptions.RayError as exc:
            if isinstance(exc, self.ray.exceptions.RayTaskError):
                raise  # an error in evobiped's own code, not a lost worker
            # a worker beyond its restarts, or one on a node that died: the generation is lost, not the run
            raise UserError(f"Ray lost a worker ({type(exc).__name__}: a node died, or a worker died {MAX_RETRIES + 1} times); "
                            "the last checkpoint is kept: resume the run with evobiped evolve --resume") from None

    def close(self):
        for a in self.actors:
            self.ray.kill(a)
        self.actors = []
        if self._owns:
            self.ray.shutdown()


def make_evaluator(episode: EpisodeConfig, backend: str = "process", workers: int | None = None, address: str | None = None,
                   on_retry=None) -> Evaluator:
    """The evaluator for a backend name; ``workers`` defaults to all cores; ``on_retry(n, limit)``: a batch of the
    process pool or of the threads is evaluated again after its worker died."""
    if backend not in BACKENDS:
        raise ConfigError(f"unknown backend {backend!r} (choose from {', '.join(BACKENDS)})")
    if workers is not None and workers < 1:
        raise ConfigError(f"workers must be >= 1, got {workers}")
    episode.check()  # here, once, whatever the backend: a worker never meets a bad value
    if backend == "serial":
        return SerialEvaluator(episode)
    if backend == "ray":
        return RayEvaluator(episode, workers, address)
    if backend == "thread":
        return ThreadEvaluator(episode, workers or os.cpu_count() or 1, on_retry=on_retry)
    return ProcessPoolEvaluator(episode, workers or os.cpu_count() or 1, on_retry=on_retry)
