"""Worker death at every point of a pool's life: while batches are fed, while they are collected, between
generations; on the process and thread backends.  The retries give an undisturbed run's results; past the
limit, one line and the last checkpoint kept.  The release campaign (tests/fault_campaign.py) repeats the random
moments many times; here a few of each run in seconds."""

import os
import signal
import time
from pathlib import Path

import numpy as np
import pytest

from evobiped.episode import EpisodeConfig
from evobiped.core.errors import UserError
from evobiped.evaluation import MAX_RETRIES, ProcessPoolEvaluator, SerialEvaluator, ThreadEvaluator

CFG = EpisodeConfig(seconds=0.2)


def genomes(n=6):
    return CFG.layout().sample(np.random.default_rng(1), n)


def same(a, b) -> bool:
    return np.array_equal(a.fitness, b.fitness) and np.array_equal(a.end_time,
                                                                   b.end_time) and np.array_equal(a.fell, b.fell)


def dead(pid: int) -> bool:
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] == "Z"
    except OSError:
        return True


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="reads the process table from /proc")
@pytest.mark.parametrize("how", ["one", "all"])
def test_workers_killed_between_generations_cost_one_retry(how):
    """A pool broken while idle (its workers killed between two generations) refuses the next batch at once;
    that costs a retry, not the run."""
    g = genomes()
    want = SerialEvaluator(CFG).evaluate(g)
    retries = []
    with ProcessPoolEvaluator(CFG, 2, on_retry=lambda n, limit: retries.append((n, limit))) as ev:
        assert same(ev.evaluate(g), want)
        procs = list(ev.pool._processes.values())
        for p in procs[:1] if how == "one" else procs:
            os.kill(p.pid, signal.SIGKILL)
        deadline = time.time() + 10
        while not all(dead(p.pid) for p in procs[:1]) and time.time() < deadline:
            time.sleep(0.01)
        time.sleep(0.2)  # the pool's manager thread finds the death
        assert same(ev.evaluate(g), want)
    assert retries == [(1, MAX_RETRIES)]


def test_a_pool_that_breaks_at_every_submit_stops_after_the_last_retry(monkeypatch):
    """Every fresh pool refuses its batches (as one whose workers died at once): MAX_RETRIES retries, then one
    UserError."""
    from concurrent.futures.process import BrokenProcessPool

    class Broken:
        def submit(self, *a, **k):
            raise BrokenProcessPool("a child process terminated abruptly")

        def shutdown(self, *a, **k):
            pass

    monkeypatch.setattr(ProcessPoolEvaluator, "_new_pool", lambda self: Broken())
    retries = []
    ev = ProcessPoolEvaluator(CFG, 2, on_retry=lambda n, limit: retries.append(n))
    with pytest.raises(UserError, match=f"workers died {MAX_RETRIES + 1} times in one generation"):
        ev.evaluate(genomes())
    assert retries == list(range(1, MAX_RETRIES + 1))


def test_a_thread_batch_that_runs_out_of_memory_is_evaluated_again(tmp_path, monkeypatch):
    marker = tmp_path / "kill-one-worker"
    marker.touch()
    monkeypatch.setenv("EVOBIPED_FAULT_KILL_WORKER", str(marker))
    g = genomes()
    want = SerialEvaluator(CFG).evaluate(g)
    retries = []
    with ThreadEvaluator(CFG, 2, on_retry=lambda n, limit: retries.append((n, limit))) as ev:
        assert same(ev.evaluate(g), want)
    assert not marker.exists() and retries == [(1, MAX_RETRIES)]


def test_thread_batches_that_keep_dying_stop_after_the_last_retry(tmp_path, monkeypatch):
    marker = tmp_path / "kill-one-worker"
    marker.touch()
    monkeypatch.setenv("EVOBIPED_FAULT_KILL_WORKER", str(marker))
    with ThreadEvaluator(CFG, 1, on_retry=lambda n, limit: marker.touch()) as ev:
        with pytest.raises(UserError, match="ran out of memory 4 times"):
            ev.evaluate(genomes(2))


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="reads the process table from /proc")
def test_workers_killed_at_random_moments(tmp_path):
    """The release campaign's random-moment classes, once each: every run completes equal to an undisturbed one."""
    import random

    from .fault_campaign import FAILURES, campaign

    kept = random.getstate()
    random.seed(7)
    try:
        results, notes = campaign(tmp_path / "c", ["worker-sigkill", "worker-storm", "late-signal"], repeat=1)
    finally:
        random.setstate(kept)
    assert {name: sum(c.values()) for name, c in results.items()} == {"worker-sigkill": 1, "worker-storm": 1,
                                                                      "late-signal": 1}
    assert not notes and not any(c[f] for c in results.values() for f in FAILURES), (dict(results), notes)


def test_a_pool_that_breaks_while_it_starts_its_workers_costs_a_retry(monkeypatch):
    """A worker killed while the next is spawned: the shared pipe is closed under the spawn (OSError, not
    BrokenProcessPool); a retry like any other death."""
    g = genomes()
    want = SerialEvaluator(CFG).evaluate(g)
    retries = []
    with ProcessPoolEvaluator(CFG, 2, on_retry=lambda n, limit: retries.append(n)) as ev:
        broken = ev.pool

        def closed(*a, **k):
            raise OSError("handle is closed")

        monkeypatch.setattr(broken, "submit", closed)
        assert same(ev.evaluate(g), want)
    assert retries == [1]


def test_a_stopped_pool_leaves_no_manager_thread_for_the_interpreters_exit_to_wake():
    """Python 3.11's exit wakes every pool's manager thread through a pipe the thread closes as it ends: a pool
    whose workers died and that was stopped has its thread ended first, or the exit may write to the closed pipe
    ("Exception ignored ... Bad file descriptor" after the command's last line)."""
    from evobiped.evaluation.pool import spawn_pool, stop_pool

    for _ in range(3):
        pool = spawn_pool(1)
        pool.submit(time.sleep, 0).result()
        for p in list(pool._processes.values()):
            os.kill(p.pid, signal.SIGKILL)
        manager = pool._executor_manager_thread
        stop_pool(pool)
        assert not manager.is_alive()


def test_stopping_a_pool_whose_manager_thread_never_started_is_quiet():
    """A Ctrl-C while a pool starts its manager thread leaves the thread made but not started: stopping the pool then
    joins nothing (joining an unstarted thread raises)."""
    import threading
    from concurrent.futures import ProcessPoolExecutor

    from evobiped.evaluation.pool import stop_pool

    pool = ProcessPoolExecutor(1)
    pool._executor_manager_thread = threading.Thread(target=lambda: None)
    stop_pool(pool)  # no RuntimeError
