"""A walker's gait as a gait lab reports it, and the walking criteria every claimed walker must meet.

:func:`gait_report` runs one genome alone in its nominal episode with a :class:`FootRecorder` listening (any task:
the gait lab needs only the body's feet) and reports the measures of :mod:`evobiped.physics.gait_lab` over its time up,
with its speed and the direction it walked.  :data:`WALKING` holds the criteria a walk meets (a duty factor of at
least 0.5 on each foot, no flight, symmetric feet that do not slide), and :func:`failed_criteria` names those a report
misses: a mover that runs, skips or skates is reported as such, never as a walker.
"""

from __future__ import annotations

import numpy as np

from ..bodies.base import Body
from ..core.errors import UserError
from ..episode import EpisodeConfig
from ..physics.gait_lab import FIELDS, MEASURES, MIN_CONTACT, MIN_GAP, FootSample, measure_one

#: the walking criteria: measure -> (comparison, bound), with what each rules out
WALKING = {
    "speed": (">=", 0.3, "too slow (m/s)"),
    "heading_deg": ("abs<=", 30.0, "off its line (deg)"),
    "duty_min": (">=", 0.5, "a foot stands less than half the time: running or skipping"),
    "airborne": ("<=", 0.02, "both feet in the air: a flight phase"),
    "duty_asymmetry": ("<=", 0.05, "the feet stand for unequal shares: limping or skipping"),
    "slip_share": ("<=", 0.05, "stance feet slide (median slip over the speed): skating"),
    "slide_per_m": ("<=", 0.10, "stance feet slide more than 10 cm per metre walked (the slip's tail): skating"),
}
#: the criteria whose measures only a meter sampling every physics step gives (a run's stopping rule under
#: ``gait_sampling = "control_tick"`` judges without them, as it did when those walkers were evolved)
STEP_CRITERIA = ("slide_per_m",)


def criteria_for(sampling: str) -> dict:
    """The :data:`WALKING` criteria a gait measured under ``sampling`` is judged by."""
    return {k: v for k, v in WALKING.items() if sampling == "physics_step" or k not in STEP_CRITERIA}


class FootRecorder:
    """An episode listener that keeps the body's foot samples of row ``row`` after every physics step (``samples``:
    per step ``(contact, slip, height, knee, power)`` of that row), and the times (s) of its control ticks."""

    #: the episode collects the samples of every physics step for it (:meth:`Body.tick_feet`)
    reads_feet_steps = True

    def __init__(self, row: int = 0):
        self.row = row
        self.samples: dict[str, list[np.ndarray]] = {k: [] for k in FIELDS}
        self.times: list[float] = []
        #: per tick, how many samples were kept up to its end
        self.ends: list[int] = []
        self.body = None

    def start(self, episode, sims) -> None:
        self.body = episode.body
        self.body.feet(sims)  # a body without feet refuses here, before any tick

    def tick(self, t, sims, ids, neurons, action, task_state) -> None:
        if self.row in ids:
            self.take(self.body.tick_feet(sims), t)

    def take(self, feet: FootSample, t: float) -> None:
        """Keep row ``row`` of a tick's samples ``feet`` (fields ``(S, n, ...)``), the tick ending at ``t`` s."""
        for k in self.samples:
            self.samples[k].extend(np.array(getattr(feet, k)[:, self.row]))
        self.times.append(float(t))
        self.ends.append(len(self.samples[FIELDS[0]]))

    def end(self, result) -> None:
        pass

    def between(self, start: float, end: float) -> "FootRecorder":
        """A recorder holding only the samples of the ticks that end in (``start``, ``end``] s (a stretch of an
        episode, measured on its own by :func:`measured`)."""
        t = np.asarray(self.times)
        ticks = np.flatnonzero((t > start + 1e-9) & (t <= end + 1e-9))
        out = FootRecorder(self.row)
        out.body = self.body
        if len(ticks):
            a, b = ([0] + self.ends)[ticks[0]], self.ends[ticks[-1]]
            out.samples = {k: v[a:b] for k, v in self.samples.items()}
            out.times = [self.times[i] for i in ticks]
            out.ends = [e - a for e in self.ends[ticks[0]: ticks[-1] + 1]]
        return out

    def series(self) -> dict[str, np.ndarray]:
        """Each sample stacked over the physics steps, ``(T, F)`` (``power`` ``(T, J)``)."""
        return {k: np.array(v) for k, v in self.samples.items()}


def gait_report(config: EpisodeConfig, genome: np.ndarray, *, seconds: float = 20.0,
                up_for: float | None = None) -> dict:
    """One genome ``(G,)`` alone in ``config``'s nominal episode, its gait measured over the first ``seconds`` s (or
    until it falls), then, with ``up_for``, left to walk on until ``up_for`` s: a dict with
    ``up`` (no fall in ``up_for`` s, else in ``seconds``), ``time_up`` (s, in the measured ``seconds``), ``forward`` (m
    along the initial facing), ``speed`` (m/s), ``heading_deg`` (direction of its displacement from the initial facing;
    None: it did not move), every measure of
    :mod:`evobiped.physics.gait_lab` (``duty_<foot>`` per foot), ``feet``, ``stance`` (per foot the debounced stance
    episodes as ``[start s, end s]``), ``walks`` and ``failed`` (:func:`failed_criteria`)."""
    if not (isinstance(seconds, (int, float)) and np.isfinite(seconds) and seconds > 0):
        raise UserError(f"--seconds must be a finite number above 0, got {seconds!r}")
    episode = config.nominal().build()
    body = episode.body
    if not has_feet(body):
        raise UserError(f"body {body.name!r} declares no feet: its gait cannot be measured")
    recorder = FootRecorder()
    total = max(seconds, up_for or 0.0)
    state = episode.start(np.asarray(genome, float)[None], seconds=total)
    recorder.start(episode, state.sims)
    episode.advance(state, seconds, listener=recorder)
    end = body.planar_position(state.sims)[:1].copy()
    report = measured(recorder, episode, start=state.start_position[:1], end=end, facing=state.start_facing[:1],
                      time_up=min(float(state.end_time[0]), float(seconds)), seconds=seconds,
                      up=not bool(state.fell[0]))
    if up_for is not None and up_for > seconds:
        episode.advance(state, up_for - seconds)
        report["up"], report["up_for"], report["end_time"] = not bool(state.fell[0]), float(up_for), float(
            state.end_time[0])
    report["failed"] = (["up"] if not report["up"] else []) + failed_criteria(report)
    report["walks"] = not report["failed"]
    return report


def measured(recorder: FootRecorder, episode, *, start: np.ndarray, end: np.ndarray, facing: np.ndarray, time_up: float,
             seconds: float, up: bool) -> dict:
    """The report of the walker ``recorder`` listened to (see :func:`gait_report`): it started at ``start`` ``(1, 2)``
    m facing ``facing`` ``(1, 2)``, is at ``end`` ``(1, 2)`` m, stayed up ``time_up`` of ``seconds`` s (``up``: no
    fall)."""
    from ..physics.gait_lab import SHUFFLE, stance_episodes
    from ..tasks.walk import displacement_heading

    body = episode.body
    forward = float(np.einsum("pi,pi->p", end - start, facing)[0])
    heading = float(displacement_heading(start, end, facing)[0])
    mass, leg = body.gait_constants(episode.model)
    feet = tuple(body.contact_sensor[1])
    series = recorder.series()
    dt = episode.control_dt / episode.substeps  # s per sample: one per physics step
    report = {"up": up, "time_up": time_up, "end_time": time_up, "seconds": float(seconds), "forward": forward,
              "speed": forward / time_up if time_up > 0 else 0.0, "heading_deg": heading if np.isfinite(heading)
                  else None,
              "displacement": [float(v) for v in (end - start)[0]], "mass": mass, "leg_length": leg,
              "control_dt": episode.control_dt, "sample_dt": dt, "sampling": "physics_step", "feet": list(feet)}
    report.update(measure_one(series, dt, forward=forward, mass=mass, leg_length=leg, feet=feet, min_gap=MIN_GAP))
    report["stance"] = {f: [[a * dt, b * dt] for a,
                            b in stance_episodes(series["contact"][:, i], dt, MIN_CONTACT, MIN_GAP)]
                        for i, f in enumerate(feet)}
    report["shuffle"] = bool(report["step_similar"] < SHUFFLE)
    report["failed"] = (["up"] if not up else []) + failed_criteria(report)
    report["walks"] = not report["failed"]
    return report


def has_feet(body) -> bool:
    """Whether the gait lab can measure ``body`` (it declares its feet)."""
    return body.contact_sensor is not None and type(body).feet is not Body.feet


def failed_criteria(report: dict, criteria: dict | None = None) -> list[str]:
    """The names of the ``criteria`` (default :data:`WALKING`) that ``report`` misses (a missing or non-finite value
    misses)."""
    out = []
    for name, (how, bound, _) in (WALKING if criteria is None else criteria).items():
        v = report.get(name)
        if v is None or not np.isfinite(v):
            out.append(name)
        elif how == ">=" and not v >= bound or how == "<=" and not v <= bound or how == "abs<=" and not abs(v) <= bound:
            out.append(name)
    return out


def criteria_words(failed: list[str]) -> str:
    """What the failed criteria mean, in words, e.g. ``airborne (both feet in the air: a flight phase)``."""
    words = {"up": "fell", **{k: v[2] for k, v in WALKING.items()}}
    return "; ".join(f"{k} ({words[k]})" for k in failed) if failed else "walks"


def gait_line(report: dict) -> str:
    """One line of the gait: speed, duty factors, flight, steps, slip, power, cost of transport."""
    feet = report["feet"]
    duty = "/".join(f"{report[f'duty_{f}']:.2f}" for f in feet)
    return (f"{report['speed']:.2f} m/s, duty {duty} ({'/'.join(f[0].upper() for f in feet)}), airborne "
            f"{100 * report['airborne']:.1f} %, {report['steps_per_s']:.1f} steps/s of {report['step_length']:.2f} m, "
            f"slip {100 * report['slip_share']:.1f} % of the speed, {report['power']:.0f} W/kg, "
            f"CoT {report['cost_of_transport']:.2f}")


__all__ = ["MEASURES", "WALKING", "STEP_CRITERIA", "criteria_for", "FootRecorder", "gait_report", "failed_criteria",
           "criteria_words", "gait_line"]
