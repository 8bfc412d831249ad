"""Progress lines for long work: fraction done, time elapsed and an estimate of the time left.

Every command that can run longer than a few seconds reports through one
:class:`Progress`: a line on stderr at most every :data:`INTERVAL` seconds
(and one at the end), nothing with ``quiet``.  Example::

    taga: 45% (9.0 of 20 s simulated)  elapsed 0:00:18  left ~0:00:22
"""

from __future__ import annotations

import sys
import time
from typing import TextIO

#: seconds between two progress lines
INTERVAL = 5.0


def hms(seconds: float) -> str:
    """``3725`` -> ``"1:02:05"``; ``"?"`` for an unknown (non-finite) time."""
    if not (seconds == seconds and abs(seconds) != float("inf")):
        return "?"
    s = int(round(seconds))
    return f"{s // 3600}:{s // 60 % 60:02d}:{s % 60:02d}"


class Progress:
    """Reports ``done`` of ``total`` (in ``unit``) for the work called ``what``."""

    def __init__(self, what: str, total: float, unit: str = "", *, quiet: bool = False, stream: TextIO | None = None):
        self.what, self.total, self.unit = what, float(total), unit
        self.quiet = quiet
        self.stream = stream
        self.t0 = time.perf_counter()
        self.last = self.t0
        self.done = 0.0

    def say(self, message: str) -> None:
        """One free-form line (unless quiet)."""
        if not self.quiet:
            print(f"{self.what}: {message}", file=self.stream or sys.stderr, flush=True)

    def update(self, done: float, note: str = "") -> None:
        """``done`` units of ``total`` are finished; prints a line when :data:`INTERVAL` s have passed."""
        self.done = float(done)
        now = time.perf_counter()
        if now - self.last >= INTERVAL:
            self.last = now
            self._line(now, note)

    def finish(self, note: str = "") -> None:
        """The last line (if the work took long enough to have shown progress)."""
        now = time.perf_counter()
        if self.last > self.t0 or now - self.t0 >= INTERVAL:
            self.done = self.total
            self._line(now, note)

    def _line(self, now: float, note: str) -> None:
        elapsed = now - self.t0
        frac = self.done / self.total if self.total > 0 else 1.0
        left = elapsed * (1 - frac) / frac if frac > 0 else float("nan")
        unit = f" {self.unit}" if self.unit else ""
        amount = f"{self.done:g} of {self.total:g}{unit}"
        self.say(f"{100 * frac:3.0f}% ({amount}{'; ' + note if note else ''})  elapsed {hms(elapsed)}  left ~{hms(left)}")

    def listener(self, offset: float = 0.0):
        """An episode listener (:class:`evobiped.episode.Listener`) reporting ``offset`` + simulated seconds."""
        return _EpisodeProgress(self, offset)


class _EpisodeProgress:
    def __init__(self, progress: Progress, offset: float):
        self.progress, self.offset = progress, offset

    def start(self, episode, sims):
        pass

    def tick(self, t, sims, ids, neurons, action, task_state):
        self.progress.update(round(self.offset + t, 3))

    def end(self, result):  # the caller ends the progress (Progress.finish) when all its episodes are done
        pass
