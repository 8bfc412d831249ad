"""The one process pool: spawned workers that leave Ctrl-C to the parent, and a stop that ends them now.

The evaluation backend (one Episode per worker, genomes in batches) and a study
(one whole evolutionary run per task) both use it.
"""

from __future__ import annotations

import multiprocessing as mp
import signal
from concurrent.futures import ProcessPoolExecutor
from typing import Callable


def _start(initializer: Callable | None, initargs: tuple) -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the parent's to handle
    if initializer is not None:
        initializer(*initargs)


def spawn_pool(workers: int, initializer: Callable | None = None, initargs: tuple = ()) -> ProcessPoolExecutor:
    """``workers`` fresh (spawned, not forked) processes that ignore SIGINT; each runs ``initializer(*initargs)`` first."""
    return ProcessPoolExecutor(workers, mp_context=mp.get_context("spawn"), initializer=_start, initargs=(initializer, initargs))


def stop_pool(pool: ProcessPoolExecutor) -> None:
    """Stop ``pool`` now: cancel queued tasks, end running ones, wait for the processes to exit."""
    procs = list((getattr(pool, "_processes", None) or {}).values())
    pool.shutdown(wait=False, cancel_futures=True)
    for p in procs:
        if p.is_alive():
            p.terminate()
    for p in procs:
        p.join()
