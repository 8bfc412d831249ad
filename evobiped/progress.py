"""Progress lines for long work: fraction done, time elapsed and an estimate of the time left.

Every command that can run longer than a few seconds reports through one
:class:`Progress`, in one shape::

    taga:  45% (9 of 20 s simulated)  elapsed 0:00:18  left ~0:00:22
    evolve:   4% (6 of 150 generations; best 21.01 (up), this generation's 6.06 (fell), ...)  elapsed 0:01:02  left ~0:12:40

a line on stderr at most every :data:`INTERVAL` seconds (and one at the end),
nothing with ``quiet``.  By default the time left assumes the rest goes at the
rate so far (elapsed / fraction done); work whose pieces grow, such as
generations whose episodes lengthen as walkers learn to stay up, gives its own
estimate from the simulated seconds still to go (:func:`time_left`).
"""

from __future__ import annotations

import math
import sys
import time
from typing import Callable, Sequence, TextIO

#: seconds between two progress lines
INTERVAL = 5.0


def hms(seconds: float) -> str:
    """``3725`` -> ``"1:02:05"``; ``"?"`` for an unknown (non-finite) time."""
    if not (seconds == seconds and abs(seconds) != float("inf")):
        return "?"
    s = int(round(seconds))
    return f"{s // 3600}:{s // 60 % 60:02d}:{s % 60:02d}"


def time_left(wall: Sequence[float], clock: Sequence[float], steps_left: int, *, ahead: float | None = None,
              window: int = 3) -> float:
    """Wall seconds for ``steps_left`` more steps (generations), from the simulated seconds still to go at the
    current rate.

    ``wall[i]`` is step i's wall-clock time (s) and ``clock[i]`` its simulated clock (s): the longest episode
    of a generation, which its batches wait for.  The rate (wall s per simulated s) is that of the last
    ``window`` steps.  Each remaining step is assumed to simulate ``ahead`` s (an evolution of walkers: the
    episode length T, since episodes lengthen as walkers learn to stay up), by default at least as much as
    the latest step and the window's mean (episodes as short as now).  NaN before the first step."""
    if not len(wall) or not len(clock):
        return math.nan
    w, s = float(sum(wall[-window:])), float(sum(clock[-window:]))
    if s <= 0:  # nothing simulated: each step costs what the last ones did
        return w / len(wall[-window:]) * steps_left
    per_step = max(float(clock[-1]), s / len(clock[-window:])) if ahead is None else float(ahead)
    return w / s * per_step * steps_left


class Progress:
    """Reports ``done`` of ``total`` (in ``unit``) for the work called ``what``; ``emit`` (optional) takes
    each line instead of ``stream`` (default stderr)."""

    def __init__(self, what: str, total: float, unit: str = "", *, quiet: bool = False, stream: TextIO | None = None,
                 emit: Callable[[str], None] | None = None):
        self.what, self.total, self.unit = what, float(total), unit
        self.quiet = quiet
        self.stream = stream
        self.emit = emit
        self.t0 = time.perf_counter()
        self.last = self.t0
        self.done = 0.0

    def restart(self, total: float, unit: str | None = None) -> None:
        """The work is ``total`` (in ``unit``, default unchanged) and begins now (its clock restarts)."""
        self.total = float(total)
        self.unit = self.unit if unit is None else unit
        self.t0 = self.last = time.perf_counter()
        self.done = 0.0

    def say(self, message: str) -> None:
        """One free-form line (unless quiet)."""
        if self.quiet:
            return
        line = f"{self.what}: {message}"
        if self.emit is not None:
            self.emit(line)
        else:
            print(line, file=self.stream or sys.stderr, flush=True)

    def update(self, done: float, note: str = "") -> None:
        """``done`` units of ``total`` are finished; prints a line when :data:`INTERVAL` s have passed."""
        self.done = float(done)
        now = time.perf_counter()
        if now - self.last >= INTERVAL:
            self.last = now
            self._line(now, note)

    def report(self, done: float, note: str = "", left: float | None = None) -> None:
        """A line now, whatever the interval: ``done`` units finished, ``left`` s to go (None: at the rate so far)."""
        self.done = float(done)
        self.last = time.perf_counter()
        self._line(self.last, note, left)

    def finish(self, note: str = "") -> None:
        """The last line (if the work took long enough to have shown progress)."""
        now = time.perf_counter()
        if self.last > self.t0 or now - self.t0 >= INTERVAL:
            self.done = self.total
            self._line(now, note)

    def _line(self, now: float, note: str, left: float | None = None) -> None:
        elapsed = now - self.t0
        frac = self.done / self.total if self.total > 0 else 1.0
        if left is None:
            left = elapsed * (1 - frac) / frac if frac > 0 else float("nan")
        unit = f" {self.unit}" if self.unit else ""
        amount = f"{self.done:.4g} of {self.total:.4g}{unit}"
        self.say(f"{100 * frac:3.0f}% ({amount}{'; ' + note if note else ''})  elapsed {hms(elapsed)}  left ~{hms(left)}")

    def listener(self, offset: float = 0.0, rows: bool = False, bound: float = 0.0):
        """An episode listener (:class:`evobiped.episode.Listener`) reporting ``offset`` + simulated seconds;
        ``rows``: + the simulated seconds of every row still running (trial-seconds), and at the episode's end
        ``offset`` + ``bound`` (the trial-seconds the batch would take if no row stopped early)."""
        return _EpisodeProgress(self, offset, rows, bound)


class _EpisodeProgress:
    def __init__(self, progress: Progress, offset: float, rows: bool, bound: float):
        self.progress, self.offset, self.rows, self.bound = progress, offset, rows, bound
        self.done = offset

    def start(self, episode, sims):
        self.dt = episode.control_dt

    def tick(self, t, sims, ids, neurons, action, task_state):
        self.done = self.done + self.dt * len(ids) if self.rows else self.offset + t
        self.progress.update(round(self.done, 3))

    def end(self, result):  # the caller ends the progress (Progress.finish) when all its episodes are done
        if self.rows:
            self.progress.done = self.offset + self.bound
