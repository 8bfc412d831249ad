"""The one process pool: spawned workers that leave Ctrl-C to the parent, die with it, and a stop that ends them now.

The evaluation backend (one Episode per worker, genomes in batches) and a study
(one whole evolutionary run per task) both use it.

A worker never outlives the process that started it, however that one ends
(SIGKILL by the out-of-memory killer included): on Linux the kernel kills it
the moment its parent ends (``prctl(PR_SET_PDEATHSIG)``), and on every system
a watch thread ends it within :data:`WATCH_PERIOD` s of finding itself
re-parented.  The pool must therefore be fed from a thread that lives as long
as the pool (the main thread here): Linux counts the death of the thread that
started a worker as its parent's.  With the workers gone, multiprocessing's
resource tracker, whose pipe they held, ends too.  The tracker writes to
/dev/null: what it would print after an abnormal end (leaked-semaphore
warnings, or ``KeyError`` tracebacks from a tracker relaunched after it was
killed) is noise to a user whose run already said what happened.
"""

from __future__ import annotations

import contextlib
import ctypes
import multiprocessing as mp
import os
import signal
import sys
import threading
import time
from concurrent.futures import ProcessPoolExecutor
from multiprocessing import resource_tracker
from typing import Callable

from ..core.errors import signals_deferred

#: seconds between a worker's checks that its parent still lives (where the kernel does not kill it at once)
WATCH_PERIOD = 0.5
_PR_SET_PDEATHSIG = 1


@contextlib.contextmanager
def silenced_stderr():
    """Send file descriptor 2 (C/C++ libraries' logs, and processes started meanwhile) to /dev/null for a while."""
    sys.stderr.flush()
    saved = os.dup(2)
    try:
        with open(os.devnull, "w") as null:
            os.dup2(null.fileno(), 2)
        yield
    finally:
        try:
            sys.stderr.flush()
        # a stop signal raised in the flush must not leave fd 2 on /dev/null (the "interrupted" line would vanish)
        finally:
            os.dup2(saved, 2)
            os.close(saved)


def _die_with(parent: int) -> None:
    """End this process when process ``parent`` ends, however it ends."""
    if sys.platform.startswith("linux"):
        try:
            ctypes.CDLL(None, use_errno=True).prctl(_PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0)
        except (OSError, AttributeError):
            pass  # no prctl: the watch thread below still ends us

    def watch() -> None:
        while os.getppid() == parent:
            time.sleep(WATCH_PERIOD)
        os._exit(1)

    if os.getppid() != parent:  # it ended before we got here
        os._exit(1)
    threading.Thread(target=watch, name="evobiped-parent-watch", daemon=True).start()


#: the signals a worker leaves to its parent (Ctrl-C and a closed terminal): blocked from its start (its imports)
#: until it ignores them
PARENTS_SIGNALS = {signal.SIGINT, signal.SIGHUP}


#: below this address space (bytes, ``ulimit -v``) a worker may die loading or compiling NumPy's, MuJoCo's and numba's
#: code: it dies quietly (LLVM's own "Unable to allocate section memory!" included) and the parent names the limit
FEW_BYTES = 2 * 2**30


def _little_address_space() -> bool:
    import resource

    soft = resource.getrlimit(resource.RLIMIT_AS)[0]
    return soft != resource.RLIM_INFINITY and soft < FEW_BYTES


def _start(parent: int, initializer: Callable | None, initargs: tuple) -> None:
    _die_with(parent)
    if _little_address_space():  # its libraries' own abort messages would interleave with the parent's lines
        quiet = os.open(os.devnull, os.O_WRONLY)
        os.dup2(quiet, 2)
        os.close(quiet)
    for sig in PARENTS_SIGNALS:  # Ctrl-C and a closed terminal are the parent's to handle
        signal.signal(sig, signal.SIG_IGN)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, PARENTS_SIGNALS)  # one that came while it started is dropped now
    if initializer is not None:
        try:
            initializer(*initargs)
        except (ImportError, OSError, MemoryError):  # a library that cannot load under a low ulimit -v: die quietly,
            if not _little_address_space():  # the parent names the limit when the pool breaks
                raise
            os._exit(1)


def _quiet_resource_tracker() -> None:
    """Start multiprocessing's resource tracker now with its stderr on /dev/null, and have every relaunch
    (after the tracker was killed) do the same, so that neither its warnings nor its tracebacks reach the user."""
    tracker = resource_tracker._resource_tracker
    if not getattr(tracker, "_evobiped_quiet", False):
        launch = tracker.ensure_running

        def ensure_running() -> None:
            if getattr(tracker, "_fd", None) is not None and tracker._check_alive():
                return
            with silenced_stderr():
                launch()

        tracker.ensure_running = ensure_running  # what register, unregister and getfd call
        tracker._evobiped_quiet = True
    tracker.ensure_running()


class _Pool(ProcessPoolExecutor):
    """A process pool whose workers start with :data:`PARENTS_SIGNALS` blocked (a mask survives the spawn), so a
    Ctrl-C to the process group while a worker imports is not a KeyboardInterrupt traceback."""

    def _spawn_process(self):
        old = signal.pthread_sigmask(signal.SIG_BLOCK, PARENTS_SIGNALS)
        try:
            with signals_deferred():  # nor is the parent stopped while it hands the worker its start (EOFError there)
                super()._spawn_process()
        finally:
            signal.pthread_sigmask(signal.SIG_SETMASK, old)


def spawn_pool(workers: int, initializer: Callable | None = None, initargs: tuple = ()) -> ProcessPoolExecutor:
    """``workers`` fresh (spawned, not forked) processes that ignore SIGINT and SIGHUP (from their start) and die
    with this process; each runs ``initializer(*initargs)`` first."""
    _quiet_resource_tracker()
    return _Pool(workers, mp_context=mp.get_context("spawn"), initializer=_start,
                               initargs=(os.getpid(), initializer, initargs))


def stop_pool(pool: ProcessPoolExecutor) -> None:
    """Stop ``pool`` now: cancel queued tasks, end running ones, wait for the processes to exit."""
    procs = list((getattr(pool, "_processes", None) or {}).values())
    manager = getattr(pool, "_executor_manager_thread", None)  # shutdown forgets it
    pool.shutdown(wait=False, cancel_futures=True)
    for p in procs:
        if p.is_alive():
            p.terminate()
    for p in procs:
        p.join()
    # (a Ctrl-C while the pool started its manager can leave it made but never started: nothing to join then)
    if manager is not None and manager is not threading.current_thread() and manager.ident is not None:
        manager.join(timeout=5)  # its wakeup pipe closed now, not while the interpreter's exit wakes it (Python 3.11:
        # a write to the pipe it closes meanwhile, "Exception ignored ... Bad file descriptor")
