"""The evaluation backends by name (:data:`BACKENDS`) and the one way to make one (:func:`make_evaluator`)."""

from __future__ import annotations

import os
from typing import Callable

from ..core.errors import ConfigError
from ..episode import EpisodeConfig
from .base import Evaluator
from .faults import FaultHook
from .limits import check_worker_count
from .processes import ProcessPoolEvaluator
from .ray_backend import RayEvaluator
from .serial import SerialEvaluator
from .threads import ThreadEvaluator

BACKENDS = ("serial", "process", "thread", "ray")


def make_evaluator(episode: EpisodeConfig, backend: str = "process", workers: int | None = None,
                   address: str | None = None,
                   on_retry: Callable[[int, int], None] | None = None, fault: FaultHook | None = None) -> Evaluator:
    """The evaluator for a backend name; ``workers`` defaults to all cores; ``on_retry(n, limit)``: a batch of the
    process pool or of the threads is evaluated again after its worker died; ``fault``: the workers' testing hook
    (:mod:`.faults`; None: the one the environment names)."""
    if backend not in BACKENDS:
        raise ConfigError(f"unknown backend {backend!r} (choose from {', '.join(BACKENDS)})")
    if workers is not None and workers < 1:
        raise ConfigError(f"workers must be >= 1, got {workers}")
    check_worker_count(backend, workers, address)
    episode.check()  # here, once, whatever the backend: a worker never meets a bad value
    if backend == "serial":
        return SerialEvaluator(episode)
    if backend == "ray":
        return RayEvaluator(episode, workers, address, fault=fault)
    if backend == "thread":
        return ThreadEvaluator(episode, workers or os.cpu_count() or 1, on_retry=on_retry, fault=fault)
    return ProcessPoolEvaluator(episode, workers or os.cpu_count() or 1, on_retry=on_retry, fault=fault)
