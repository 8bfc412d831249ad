"""The Ray backend: actors holding an Episode each, on a local Ray or a cluster (:func:`make_evaluator`'s ``ray``)."""

from __future__ import annotations

import os
import signal
import threading

import numpy as np

from ..episode import EpisodeConfig
from ..core.errors import STOP_SIGNALS, UserError
from ..core.net import connect_error
from .base import MAX_RETRIES, Evaluator, chunks, concat, evaluate_batch
from .faults import FaultHook
from .pool import silenced_stderr

#: seconds between checks, while a generation waits for Ray actors, that their nodes are alive
NODE_CHECK_PERIOD = 5.0


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
            hint = (" (a cluster with token authentication, the default since Ray 2.59, needs RAY_AUTH_MODE=token and "
                    "its token: see `ray get-auth-token`)")
        raise UserError(f"cannot start or reach a Ray cluster{where}: "
                        f"{str(exc).splitlines()[0] if str(exc) else type(exc).__name__}{hint}") from None
    if threading.current_thread() is threading.main_thread():
        for s, h in handlers.items():  # ray.init puts its own in place (SIGTERM: exit status 15, no checkpoint line)
            if h is not None:
                signal.signal(s, h)
    return ray, True


#: the watcher of a local Ray's processes: while this process lives it notes every descendant of the Ray node's
#: processes (argv: this pid, the node's pids); when this process ends it SIGKILLs them at once, so the dashboard and
#: runtime-env agents, which outlive a killed raylet by a minute (their error report waits on the dead GCS), go too
_WATCH = """
import os, signal, sys, time
parent, roots = int(sys.argv[1]), {int(p) for p in sys.argv[2:]}
def tree():
    kids = {}
    for d in filter(str.isdigit, os.listdir("/proc")):
        try:
            ppid = int(open(f"/proc/{d}/stat").read().rsplit(")", 1)[1].split()[1])
        except (OSError, ValueError, IndexError):
            continue
        kids.setdefault(ppid, []).append(int(d))
    found, todo = set(), list(roots)
    while todo:
        p = todo.pop()
        if p not in found:
            found.add(p)
            todo += kids.get(p, [])
    return found
seen = set()
while os.getppid() == parent:
    seen |= tree()
    time.sleep(1.0)
for p in seen:
    try:
        if b"ray" in open(f"/proc/{p}/cmdline", "rb").read():
            os.kill(p, signal.SIGKILL)
    except OSError:
        pass
"""


def _watch_local_ray(ray):
    """Start the watcher of a local Ray's processes (:data:`_WATCH`; Linux, where /proc lists them), or None."""
    import subprocess
    import sys

    try:
        node = ray._private.worker._global_node
        pids = [str(info.process.pid) for infos in node.all_processes.values() for info in infos]
    except AttributeError:  # another Ray's internals
        return None
    if not pids or not os.path.isdir("/proc"):
        return None
    return subprocess.Popen([sys.executable, "-c", _WATCH, str(os.getpid()), *pids], stdin=subprocess.DEVNULL,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)


class RayEvaluator(Evaluator):
    """Ray actors (one per CPU of the cluster, or ``workers``), each holding an Episode.

    An actor that dies is restarted and its batch sent again, at most :data:`MAX_RETRIES` times.  One lost for
    good, or one whose node died (checked every :data:`NODE_CHECK_PERIOD` s while a generation waits: Ray would
    wait forever for room to restart it), stops the generation with a UserError, the run's last checkpoint intact.
    ``fault``: the actors' testing hook (:class:`~.faults.FaultHook`; None: the one the environment names).
    """

    def __init__(self, episode: EpisodeConfig, workers: int | None = None, address: str | None = None,
                 chunk: int | None = None, fault: FaultHook | None = None):
        super().__init__(episode)
        fault = FaultHook.from_environment() if fault is None else fault
        ray, self._owns = init_ray(address, workers)
        self.ray = ray
        self._watch = _watch_local_ray(ray) if self._owns and address is None else None
        self.chunk = chunk
        cpus = int(ray.cluster_resources().get("CPU", 1))
        if workers is not None and workers > cpus:  # an actor takes a CPU: the rest would wait for one forever
            self.actors = []
            self.close()
            raise UserError(f"--workers {workers}: the Ray cluster has {cpus} CPUs (one per worker)")
        n = workers or cpus

        # a worker that dies is restarted and its batch sent again (same result: fates depend on genomes alone)
        @ray.remote(num_cpus=1, max_restarts=MAX_RETRIES, max_task_retries=MAX_RETRIES)
        class _Worker:
            def __init__(self, config, fault):
                self.episode, self.fault = config.build(), fault

            def evaluate(self, genomes, key, context):
                self.fault.kill_process()
                return evaluate_batch(self.episode, genomes, key, context)

            def node(self):
                return ray.get_runtime_context().get_node_id()

        self.actors = [_Worker.remote(episode, fault) for _ in range(max(1, n))]
        self.nodes = set(ray.get([a.node.remote() for a in self.actors]))  # where they run

    def _check_nodes(self) -> None:
        """UserError if a node that runs one of the actors has died."""
        alive = {n["NodeID"] for n in self.ray.nodes() if n["Alive"]}
        if not self.nodes <= alive:
            raise UserError(f"a Ray node running this run's workers died ({len(self.nodes - alive)} of "
                            f"{len(self.nodes)} nodes lost); the last checkpoint is kept: resume the run with evobiped "
                            "evolve --resume")

    def evaluate(self, genomes, key=None, context=None):
        genomes = np.asarray(genomes, float)
        pieces = [genomes[s] for s in chunks(len(genomes), self.chunk, len(self.actors))]
        pool = self.ray.util.ActorPool(self.actors)
        for g in pieces:
            pool.submit(lambda a, g: a.evaluate.remote(g, key, context), g)
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
            raise UserError(f"Ray lost a worker ({type(exc).__name__}: a node died, or a worker died {MAX_RETRIES + 1} "
                            "times); the last checkpoint is kept: resume the run with evobiped evolve "
                            "--resume") from None

    def close(self):
        for a in self.actors:
            self.ray.kill(a)
        self.actors = []
        if self._owns:
            self.ray.shutdown()
        if getattr(self, "_watch", None) is not None:  # Ray's processes ended with it: nothing left to watch
            self._watch.kill()
            self._watch.wait()
            self._watch = None
