"""How many local workers of a backend this machine runs: checked before any starts."""

from __future__ import annotations

import os

from ..core.errors import ConfigError

# : memory one local worker takes at most, in bytes (a process or Ray actor: Python, MuJoCo, an episode; a thread: an
# episode)
WORKER_BYTES = {"process": 256 * 2**20, "ray": 512 * 2**20, "thread": 64 * 2**20}
#: local workers per core beyond which more only cost memory (they share the cores)
WORKERS_PER_CORE = 8


def worker_limit(backend: str) -> int:
    """The most local workers of ``backend`` this machine is given: :data:`WORKERS_PER_CORE` per core, and as many
    as fit in half its memory at :data:`WORKER_BYTES` each."""
    memory = os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    return max(1, min(WORKERS_PER_CORE * (os.cpu_count() or 1),
                      int(memory / 2 // WORKER_BYTES.get(backend, WORKER_BYTES["ray"]))))


def check_worker_count(backend: str, workers: int | None, address: str | None = None, name: str = "workers") -> None:
    """ConfigError (one line) when ``workers`` local workers of ``backend`` exceed :func:`worker_limit`, before any
    starts (a cluster's, ``address`` given, are the cluster's to count: :class:`~.ray_backend.RayEvaluator`)."""
    if workers is None or backend == "serial" or address is not None:
        return
    limit = worker_limit(backend)
    if workers > limit:
        memory = os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
        raise ConfigError(f"{name} {workers}: this machine ({os.cpu_count() or 1} cores, {memory / 2**30:.3g} GiB) "
                          f"runs at most {limit} {backend} workers")
