"""Progress lines for long work: fraction done, time elapsed and an estimate of the time left.

Every command that can run longer than a few seconds reports through one
:class:`Progress`, in one shape::

    taga:  45% (9 of 20 s simulated)  elapsed 0:00:18  left ~0:00:22
    evolve:   4% (6 of 150 generations; best 21.01 (up), this generation's 6.06 (fell), ...)  elapsed 0:01:02  left
    ~0:12:40

a line on stderr at most every :data:`INTERVAL` seconds (and one at the end),
nothing with ``quiet``.  By default the time left assumes the rest goes at the
rate so far (elapsed / fraction done); work whose pieces grow, such as
generations whose episodes lengthen as walkers learn to stay up, gives its own
estimate: an evolution models every walker's episode (:class:`GenerationClock`).
"""

from __future__ import annotations

import math
import sys
import time
from typing import Callable, Sequence, TextIO

import numpy as np

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
    """Wall seconds for ``steps_left`` more steps at the wall seconds per simulated second of the last ``window``
    steps (``wall[i]``: step i's wall-clock time, ``clock[i]``: its simulated seconds), each remaining step
    simulating ``ahead`` s (default: as many as the latest step and at least the window's mean).  NaN before
    the first step.  An evolution's generations use :class:`GenerationClock`, which models every walker."""
    if not len(wall) or not len(clock):
        return math.nan
    w, s = float(sum(wall[-window:])), float(sum(clock[-window:]))
    if s <= 0:  # nothing simulated: each step costs what the last ones did
        return w / len(wall[-window:]) * steps_left
    per_step = max(float(clock[-1]), s / len(clock[-window:])) if ahead is None else float(ahead)
    return w / s * per_step * steps_left


class GenerationClock:
    """The time left of an evolution, from every walker's episode length.

    A generation's wall time is modelled as ``a * S + b * L``: ``S`` the simulated seconds of all its episodes
    (every walker and presentation until it fell or reached T: the physics), ``L`` its longest episode (the
    batches wait for their longest row: the per-tick work shared by a batch); ``a`` and ``b`` are fitted (least
    squares, not negative) to the last :attr:`window` generations, so they follow the machine's current speed.
    The remaining generations are forecast walker by walker: each episode lasts on average halfway between the
    fraction ``u`` of T that this window's walkers lasted (episodes as short as now: the least the rest can take)
    and the whole episode (every walker up: the most), ``(1 + u) / 2`` of T, and the longest lasts T.  Measured
    on two quick starts and a 30-generation run (tests/quickstart_clock.json; docs/usage.md)."""

    def __init__(self, generations: int, seconds: float, window: int = 10):
        self.generations, self.seconds, self.window = int(generations), float(seconds), int(window)
        self.rows: list[int] = []  # episodes (walkers x presentations) per generation
        self.simulated: list[float] = []  # S
        self.longest: list[float] = []  # L
        self.wall: list[float] = []
        self._pending: tuple[int, float, float] = (0, 0.0, 0.0)

    def episodes(self, end_times) -> None:
        """The end time (s) of every episode of the generation being evaluated (may be called for several batches)."""
        n, s, longest = self._pending
        e = [float(x) for x in end_times]
        self._pending = (n + len(e), s + sum(e), max([longest, *e]))

    def generation(self, wall: float) -> None:
        """The generation whose episodes were given took ``wall`` s."""
        n, s, longest = self._pending
        self._pending = (0, 0.0, 0.0)
        self.rows.append(n)
        self.simulated.append(s)
        self.longest.append(longest)
        self.wall.append(float(wall))

    def cost(self) -> tuple[float, float]:
        """``(a, b)``: wall s per simulated episode-second and per second of the longest episode, this window."""
        k = self.window
        S, L, W = (np.array(x[-k:], float) for x in (self.simulated, self.longest, self.wall))
        if S.sum() <= 0:
            return 0.0, 0.0
        (a, b), *_ = np.linalg.lstsq(np.stack([S, L], 1), W, rcond=None)
        if not (np.isfinite(a) and np.isfinite(b)) or a < 0 or b < 0:  # one term alone, the one that explains it
            return (float(W.sum() / S.sum()), 0.0) if a >= b or L.sum() <= 0 else (0.0, float(W.sum() / L.sum()))
        return float(a), float(b)

    def left(self, done: int) -> float:
        """Wall seconds for the generations after the first ``done``; NaN before any generation."""
        if not self.wall:
            return math.nan
        remaining = self.generations - int(done)
        if remaining <= 0:
            return 0.0
        k = self.window
        rows = float(np.mean(self.rows[-k:]))
        if sum(self.simulated[-k:]) <= 0:  # nothing simulated (every individual kept): what the last ones cost
            return float(np.mean(self.wall[-k:])) * remaining
        u = float(np.mean(self.simulated[-k:])) / (rows * self.seconds) if rows else 1.0
        u = (1.0 + u) / 2  # halfway between episodes as short as now and every walker up
        a, b = self.cost()
        return (a * rows * self.seconds * u + b * self.seconds) * remaining


def line_text(what: str | None, done: float, total: float, unit: str, note: str, *, elapsed: float, left: float,
              at_most: bool = False) -> str:
    """One progress line: ``what: 41% (62 of 150 generations; note)  elapsed 0:04:12  left ~0:06:20`` (without
    ``what: `` when ``what`` is None); ``at_most``: the work may end before its total (a run with a stopping rule),
    so the time left is a bound: ``left at most 0:06:20``."""
    frac = done / total if total > 0 else 1.0
    amount = f"{done:.4g} of {total:.4g}{' ' + unit if unit else ''}"
    line = (f"{100 * frac:3.0f}% ({amount}{'; ' + note if note else ''})  elapsed {hms(elapsed)}  left "
            f"{'at most ' if at_most else '~'}{hms(left)}")
    return line if what is None else f"{what}: {line}"


def generation_note(*, best: float, best_fell: bool, this: float, this_fell: bool, mean: float, worst: float,
                    evals_per_second: float, simulated: float, longest: float) -> str:
    """The details of evolve's line for one generation: the run's best so far, this generation's best, mean and
    worst, the evaluation rate, the simulated seconds and the longest episode."""
    up = lambda fell: "(fell)" if fell else "(up)"  # noqa: E731
    return (f"best {best:.3f} {up(best_fell)}, this generation's {this:.3f} {up(this_fell)}, mean {mean:.3f}, "
            f"worst {worst:.3f}; {evals_per_second:.1f} eval/s, {simulated:.0f} s simulated, longest episode "
            f"{longest:.1f} s")


class Progress:
    """Reports ``done`` of ``total`` (in ``unit``) for the work called ``what``; ``emit`` (optional) takes
    each line instead of ``stream`` (default stderr)."""

    def __init__(self, what: str, total: float, unit: str = "", *, quiet: bool = False, stream: TextIO | None = None,
                 emit: Callable[[str], None] | None = None, at_most: bool = False):
        """``at_most``: the work may stop before ``total`` (its time left is an upper bound, and says so)."""
        self.what, self.total, self.unit = what, float(total), unit
        self.at_most = at_most
        self.quiet = quiet
        self.stream = stream
        self.emit = emit
        self.t0 = time.perf_counter()
        self.last = self.t0
        self.done = 0.0
        #: episode listeners' work: when the first batch began (None: not yet) and the row-seconds since, ticks included
        self.work_start: float | None = None
        self.work = 0.0

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

    def update(self, done: float, note: str = "", left: Callable[[], float] | None = None) -> None:
        """``done`` units of ``total`` are finished; prints a line when :data:`INTERVAL` s have passed (``left``:
        what gives the seconds to go then; default: at the rate so far)."""
        self.done = float(done)
        now = time.perf_counter()
        if now - self.last >= INTERVAL:
            self.last = now
            self._line(now, note, None if left is None else left())

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

    @property
    def elapsed(self) -> float:
        """Wall seconds since the work began (as the lines say it)."""
        return time.perf_counter() - self.t0

    def _line(self, now: float, note: str, left: float | None = None) -> None:
        elapsed = now - self.t0
        frac = self.done / self.total if self.total > 0 else 1.0
        if left is None:
            left = elapsed * (1 - frac) / frac if frac > 0 else float("nan")
        self.say(line_text(None, self.done, self.total, self.unit, note, elapsed=elapsed, left=left,
                           at_most=self.at_most and self.done < self.total))

    def listener(self, offset: float = 0.0, rows: bool = False, bound: float = 0.0,
                 later: Sequence[tuple[int, float]] = ()):
        """An episode listener (:class:`evobiped.episode.Listener`) reporting ``offset`` + simulated seconds;
        ``rows``: + the simulated seconds of every row still running (trial-seconds), and at the episode's end
        ``offset`` + ``bound`` (the trial-seconds the batch would take if no row stopped early).  With ``rows`` the
        time left is that of the rows still running, each to the end of the batch, and of the batches still to come
        (``later``: ``(rows, seconds)`` each), at the wall time per tick the work since the first batch's first tick
        took (a tick costs as much as its running rows and :data:`TICK_ROWS` more)."""
        return _EpisodeProgress(self, offset, rows, bound, later)


#: the work of one control tick of a batch beside its rows' own, in rows (measured: a batch of one row steps a second
#: of simulated time about three times slower per row than a batch of 164)
TICK_ROWS = 2.0


class _EpisodeProgress:
    def __init__(self, progress: Progress, offset: float, rows: bool, bound: float, later: Sequence[tuple[int, float]]):
        self.progress, self.offset, self.rows, self.bound = progress, offset, rows, bound
        self.later = sum((n + TICK_ROWS) * s for n, s in later)  # the batches to come, in row-seconds of work
        self.done = offset

    def start(self, episode, sims):
        self.dt = episode.control_dt
        self.seconds = self.bound / max(sims.n, 1)  # the batch's episode length
        if self.progress.work_start is None:  # the first batch begins: the rate is reckoned from here
            self.progress.work_start = time.perf_counter()

    def tick(self, t, sims, ids, neurons, action, task_state):
        self.done = self.done + self.dt * len(ids) if self.rows else self.offset + t
        self.progress.work += self.dt * (len(ids) + TICK_ROWS)
        self.progress.update(round(self.done, 3), left=self._left(t, len(ids)) if self.rows else None)

    def _left(self, t: float, running: int):
        def left() -> float:
            wall, work = time.perf_counter() - self.progress.work_start, self.progress.work
            to_go = (running + TICK_ROWS) * max(self.seconds - t, 0.0) + self.later
            return wall / work * to_go if work > 0 else math.nan

        return left

    def end(self, result):  # the caller ends the progress (Progress.finish) when all its episodes are done
        if self.rows:
            self.progress.done = self.offset + self.bound
