"""A speed knob: the walking elite nearest a commanded speed, and a speed schedule followed by switching elites on the fly.

Each stretch of the schedule holds one commanded speed (m/s) for ``hold`` s; at its start the controller's
parameters become those of the walking elite nearest that speed (and the commanded turning rate), while the
body and the controller's state go on: a gait switch without stopping.  A stretch's measured speed is the
walk task's mean forward speed over it (the path along the facing, m, per s).
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
    elite: int
    archive_speed: float
    measured: float
    up: bool

    @property
    def error(self) -> float:
        """|measured - commanded| / commanded."""
        return abs(self.measured - self.commanded) / self.commanded


def follow(rep: Repertoire, speeds: list[float], hold: float, turning: float = 0.0) -> list[Stretch]:
    """Walk the schedule ``speeds`` (m/s, ``hold`` s each) switching elites on the fly; every commanded speed is checked
    against the archive's range (UserError) before anything is simulated."""
    elites = [rep.nearest(v, turning) for v in speeds]
    episode = dataclasses.replace(rep.episode.nominal(), seconds=hold * len(speeds))
    ep = episode.build()
    genome = rep.archive.genome
    state = ep.start(genome[elites[0]][None])
    out, travelled = [], 0.0
    for v, e in zip(speeds, elites):
        state.params = ep.controller.decode(genome[e][None])
        ep.advance(state, hold)
        # the walk task's speed term is the path along the facing over the time up: times it back to metres
        path = float(ep.task.terms(state.task)["speed"][0] * state.end_time[0])
        out.append(Stretch(v, e, float(rep.measure("speed")[e]), (path - travelled) / hold, bool(state.alive[0])))
        travelled = path
    return out


def tracking(stretches: list[Stretch]) -> tuple[float, int]:
    """The mean relative tracking error over the stretches and the number of stretches that ended down."""
    return float(np.mean([s.error for s in stretches])), sum(not s.up for s in stretches)
