"""The time left of work done in batches of rows (the robustness battery): from the rows still running and the
batches to come, at the rate since the first batch began."""

from __future__ import annotations

import re
from types import SimpleNamespace

import pytest

from evobiped.core import progress


def test_time_before_the_first_batch_does_not_inflate_the_estimate(monkeypatch):
    """The battery first walks the walker once to find its stride, with nothing to report: the issue's first
    estimate was 2 h 27 min for a 49 s job.  Here 20 s pass before the first tick; each tick of a batch costs
    1 ms per running row and per TICK_ROWS; the first line's estimate must match the work left."""
    now = [0.0]
    monkeypatch.setattr(progress.time, "perf_counter", lambda: now[0])
    lines = []
    p = progress.Progress("robustness", 100 * 30.0 + 2 * 30.0, "trial-s", emit=lines.append)
    now[0] = 20.0  # the stride search: no progress
    dt, c = 0.02, 1e-3  # wall s per row and tick
    K = progress.TICK_ROWS
    listener = p.listener(offset=0.0, rows=True, bound=100 * 30.0, later=[(1, 30.0), (1, 30.0)])
    listener.start(SimpleNamespace(control_dt=dt), SimpleNamespace(n=100))
    ticks = int(round(30.0 / dt))
    for k in range(ticks):
        now[0] += c * (100 + K)
        listener.tick((k + 1) * dt, None, range(100), None, None, None)
        if lines:
            break
    assert lines, "a line within the first batch"
    m = re.search(r"left ~(\d+):(\d+):(\d+)", lines[0])
    left = int(m[1]) * 3600 + int(m[2]) * 60 + int(m[3])
    true_left = c * (100 + K) * (ticks - (k + 1)) + 2 * c * (1 + K) * ticks  # this batch's rest, the two to come
    assert left == pytest.approx(true_left, abs=1.0)
    assert left < 200  # not hours: the 20 s before the first batch are not part of the rate


def test_rows_that_stop_make_the_estimate_shrink(monkeypatch):
    now = [0.0]
    monkeypatch.setattr(progress.time, "perf_counter", lambda: now[0])
    lines = []
    p = progress.Progress("battery", 10 * 10.0, "trial-s", emit=lines.append)
    listener = p.listener(offset=0.0, rows=True, bound=100.0)
    listener.start(SimpleNamespace(control_dt=0.1), SimpleNamespace(n=10))
    for k in range(100):
        rows = 10 if k < 20 else 2  # 8 of 10 fall at 2 s
        now[0] += 0.1 * (rows + progress.TICK_ROWS)
        listener.tick((k + 1) * 0.1, None, range(rows), None, None, None)
    estimates = [int(m[1]) * 60 + int(m[2]) for m in (re.search(r"left ~\d+:(\d+):(\d+)", line) for line in lines)]
    assert len(estimates) >= 3 and estimates[-1] < estimates[0]
