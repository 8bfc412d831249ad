"""A speed knob: the walking elite nearest a commanded speed, and a speed schedule followed by switching elites on the
fly.

Each stretch of the schedule holds one commanded speed v (m/s) for ``hold`` s.  Every ``step`` s the knob
chooses the speed it wants and moves towards it by at most ``ramp`` m/s per s when speeding up and
``ramp_down`` when slowing down (0: at once; slowing is the safer change, so it may be quicker), and the
controller's parameters become those of the walking elite for the knob's speed: the one most like the current
elite in its genome among those within 5 % of that speed (else the nearest in speed and turning), while the
body and the controller's state go on: gaits switched without stopping.

The speed it wants closes the loop on the distance walked (``correction`` > 0): after tau s of the stretch
the walker should have covered v tau m; a deficit of d m asks for v + d / correction, held within
``overshoot`` (a fraction) of v.  An elite's archive speed is its mean from a standing start, so on the
move it walks a little faster or slower than that; the loop takes up the difference and the time a change
of speed takes, so the stretch's mean comes out at the command.  ``correction`` = 0 is the open loop: the
knob wants v.  Ramping through similar genomes keeps the walker up over modest changes; a jump of 3x at
once, or an overshoot into the archive's fastest gaits, fells it (docs/repertoire.md).  A stretch's measured
speed is the walk task's mean forward speed over it (the path along the facing, m, per s).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from .elites import Repertoire


@dataclass(frozen=True)
class Stretch:
    """One stretch of a schedule: the commanded speed (m/s), the elite (archive row) and the elite's own measured
    speed, what the walker did (m/s) and whether it was up at the stretch's end."""

    commanded: float
    elite: int  # the elite at the stretch's end
    archive_speed: float
    measured: float
    up: bool

    @property
    def error(self) -> float:
        """|measured - commanded| / commanded."""
        return abs(self.measured - self.commanded) / self.commanded


#: s: the default time the knob's loop takes to make up a distance deficit
CORRECTION = 3.0
#: the most the knob's speed may differ from the command (a fraction of it)
OVERSHOOT = 0.2


#: m/s per s: the default most the knob speeds up and slows down in a second
RAMP, RAMP_DOWN = 0.1, 0.2


def follow(rep: Repertoire, speeds: list[float], hold: float, turning: float = 0.0, *, ramp: float = RAMP,
           ramp_down: float = RAMP_DOWN, step: float = 1.0, correction: float = CORRECTION,
           overshoot: float = OVERSHOOT) -> list[Stretch]:
    """Walk the schedule ``speeds`` (m/s, ``hold`` s each) switching elites on the fly every ``step`` s.  The knob moves
    by at most ``ramp`` m/s per s up and ``ramp_down`` down (0: at once) towards the speed the distance loop asks for
    (``correction`` s to make up a deficit, 0: no loop; within ``overshoot`` of the command).  Every commanded speed
    is checked against the archive's range (UserError) before anything is simulated."""
    for v in speeds:
        rep.nearest(v, turning)
    walking = rep.measure("speed")[rep.walking()]
    slowest, fastest = float(walking.min()), float(walking.max())
    episode = dataclasses.replace(rep.episode.nominal(), seconds=hold * len(speeds))
    ep = episode.build()
    genome = rep.archive.genome
    knob, elite = speeds[0], rep.nearest(speeds[0], turning)
    state = ep.start(genome[elite][None])

    def path() -> float:  # the walk task's speed term is the path along the facing over the time up: times it back to m
        return float(ep.task.terms(state.task)["speed"][0] * state.end_time[0])

    ticks = max(1, int(round(hold / step)))
    dt = hold / ticks  # s between switches
    out = []
    for v in speeds:
        start = path()
        for k in range(ticks):
            want = v
            if correction:
                deficit = v * k * dt - (path() - start)  # m behind the command so far in this stretch
                want = float(np.clip(v + deficit / correction, v * (1 - overshoot), v * (1 + overshoot)))
                want = float(np.clip(want, slowest, fastest))
            knob = float(np.clip(want, knob - ramp_down * dt if ramp_down else -np.inf, knob + ramp * dt if ramp
                                 else np.inf))
            elite = rep.nearest(knob, turning, like=elite)
            state.params = ep.controller.decode(genome[elite][None])
            ep.advance(state, dt)
        out.append(Stretch(v, elite, float(rep.measure("speed")[elite]), (path() - start) / hold, bool(state.alive[0])))
    return out


def tracking(stretches: list[Stretch]) -> tuple[float, int]:
    """The mean relative tracking error over the stretches and the number of stretches that ended down."""
    return float(np.mean([s.error for s in stretches])), sum(not s.up for s in stretches)


def hysteresis(stretches: list[Stretch]) -> list[tuple[float, Stretch, Stretch]]:
    """The commanded speeds held both while the schedule rises to its highest speed and while it falls from it, as
    Taga measured his walker's gait against a rising and a falling drive: (speed, the stretch on the way up, the
    stretch on the way down), slowest first.  A gait that depends on the way the knob came shows as different
    elites or measured speeds at the same command."""
    peak = int(np.argmax([s.commanded for s in stretches]))
    up = {s.commanded: s for s in stretches[:peak]}
    down = {s.commanded: s for s in stretches[peak + 1:]}
    return [(v, up[v], down[v]) for v in sorted(up) if v in down]
