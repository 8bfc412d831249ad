"""The robustness battery: one fixed set of disturbed trials for any walker whose body declares its foot contacts.

Every trial starts from the nominal initial state and runs ``seconds`` (30 s
by default); a trial is survived when the walker has not fallen at the end.
Joints and contacts are found by role (``Actuator.leg``/``joint``,
``Body.contact_sensor``), never by name or column, and each family runs where it
applies: offsets on bodies of PD targets with hip pitch (and roll) roles,
friction and slope on bodies with a MuJoCo ground, sideways pushes on bodies
that are not sagittal.  On the sagittal Taga body (torques, its own ground) the
battery is the forward and backward pushes (48 trials).

============  ======  ==============================================================
family        trials  disturbance
============  ======  ==============================================================
push 5 N      32      a horizontal push on the pelvis for 0.1 s, forward, backward,
push 10 N     32      left or right (of the initial facing), at 8 phases of the stride
push 15 N     32      (phase i/8 after the first left touchdown after ``push_after``)
offset 0.05   8       a constant offset on the hip targets for the whole trial: pitch
offset 0.1    8       or roll, +-m on both legs (same sign) or +m / -m (opposite signs)
friction      3       floor sliding friction 0.5, 0.75, 1.5 (the model's is 1.0)
slope         2       a 3 % grade uphill and downhill along the initial facing
============  ======  ==============================================================

The stride is measured on a nominal run of the same walker (left-foot
touchdowns between ``push_after`` and the end; 1 s when the walker does not
step).  Nothing here is random: the battery is the same for every walker.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .contract import index
from .episode import Episode
from .errors import UserError
from .perturb import Trials
from .progress import Progress

PUSH_FORCES = (5.0, 10.0, 15.0)  # N
PUSH_DURATION = 0.1  # s
#: direction name -> unit vector in the initial-facing frame (forward = +x, left = +y)
DIRECTIONS = {"forward": (1.0, 0.0), "backward": (-1.0, 0.0), "left": (0.0, 1.0), "right": (0.0, -1.0)}
PHASES = 8
OFFSETS = (0.05, 0.1)  # rad
FRICTIONS = (0.5, 0.75, 1.5)
SLOPES = (0.03, -0.03)  # grade


@dataclass
class Trial:
    """One trial's label and outcome."""

    family: str
    label: str
    survived: bool
    end_time: float  # s
    forward: float  # m, displacement along the initial facing
    distance: float  # m, planar displacement


def _hip_columns(episode: Episode) -> dict[str, tuple[int, int]]:
    """Axis (pitch, roll) -> the (left, right) actuator columns of the hips with that role; only axes both legs have,
    and none on a body of torques (the offsets are PD-target angles)."""
    body = episode.body
    if body.action_kind != "position":
        return {}
    roles = {(a.leg, a.joint) for a in body.actuators}
    return {axis: (index(body.actuators, "left", f"hip_{axis}"), index(body.actuators, "right", f"hip_{axis}"))
            for axis in ("pitch", "roll") if {("left", f"hip_{axis}"), ("right", f"hip_{axis}")} <= roles}


class _Touchdowns:
    """Listener: left-foot touchdown times (s) of row 0 (the body's contact sensor, its left leg's column)."""

    def __init__(self):
        self.times: list[float] = []
        self._down = True

    def start(self, episode, sims):
        self.body = episode.body
        self.sensor, legs = self.body.contact_sensor
        self.column = legs.index("left")

    def tick(self, t, sims, ids, neurons, action, task_state):
        down = bool(self.body.sensors(sims)[self.sensor][0, self.column] > 0)
        if down and not self._down:
            self.times.append(t)
        self._down = down

    def end(self, result):
        pass


def stride(episode: Episode, genome: np.ndarray, seconds: float, after: float) -> tuple[float, float]:
    """(first left touchdown after ``after`` s, stride period s) of a nominal run; (after, 1.0) if it does not step."""
    td = _Touchdowns()
    episode.run(genome, seconds=seconds, listener=td)
    t = np.array([x for x in td.times if x >= after])
    if len(t) < 2:
        return after, 1.0
    return float(t[0]), float(np.median(np.diff(t)))


def battery(episode: Episode, genome: np.ndarray, *, seconds: float = 30.0, push_after: float = 10.0,
            progress: Progress | None = None) -> list[Trial]:
    """Run every trial of the battery for one genome ``(G,)``; the episode must be nominal (no perturbations).
    ``progress`` (optional) hears the simulated seconds of its batches."""
    body = episode.body
    if body.contact_sensor is None or "left" not in body.contact_sensor[1]:
        raise UserError(f"the robustness battery needs a body that declares its left foot's contact sensor; {body.name!r} does not")
    if episode.task.presentations != 1:
        raise UserError(f"the robustness battery runs one presentation per trial; this {episode.task.name!r} episode has "
                        f"{episode.task.presentations} (give a steering walker one source)")
    if not push_after < seconds:
        raise UserError(f"the battery pushes after {push_after:g} s: trials must be longer (got {seconds:g} s)")
    hips = _hip_columns(episode)
    n_act = len(episode.body.actuator_names)
    t0, period = stride(episode, genome, seconds, push_after)
    labels: list[tuple[str, str]] = []
    starts, forces, offsets = [], [], []
    directions = {d: u for d, u in DIRECTIONS.items() if not (body.sagittal and u[1])}
    for f in PUSH_FORCES:
        for d, (ux, uy) in directions.items():
            for i in range(PHASES):
                labels.append((f"push {f:g} N", f"{d}, phase {i}/{PHASES}"))
                starts.append([t0 + period * i / PHASES])
                forces.append([[f * ux, f * uy, 0.0]])
                offsets.append(np.zeros(n_act))
    for m in OFFSETS:
        for axis, (left, right) in hips.items():
            for pattern in ("same", "opposite"):
                for sign in (1.0, -1.0):
                    off = np.zeros(n_act)
                    off[left] = sign * m
                    off[right] = sign * m if pattern == "same" else -sign * m
                    labels.append((f"offset {m:g} rad", f"{axis} {pattern} {'+' if sign > 0 else '-'}"))
                    starts.append([0.0])
                    forces.append([[0.0, 0.0, 0.0]])
                    offsets.append(off)
    main = Trials.nominal(len(labels), n_act, push_start=np.array(starts), push_force=np.array(forces),
                          push_duration=PUSH_DURATION, target_offset=np.array(offsets))
    runs = [(labels, main)]
    if body.floor_geom is not None:
        runs += [([("friction", f"mu = {mu:g}")], Trials.nominal(1, n_act, friction=mu)) for mu in FRICTIONS]
        runs += [([("slope", f"{100 * s:+g} % ({'uphill' if s > 0 else 'downhill'})")], Trials.nominal(1, n_act, slope=s))
                 for s in SLOPES]
    out = []
    n_trials = sum(len(names) for names, _ in runs)
    if progress is not None:  # trial-seconds: each trial's own simulated time, a fallen trial's rest counted at its batch's end
        progress.total, progress.unit = float(seconds * n_trials), f"trial-s of {n_trials} trials of {seconds:g} s"
    offset = 0.0
    for names, trials in runs:
        bound = seconds * len(names)
        watch = progress.listener(offset=offset, rows=True, bound=bound) if progress is not None else None
        offset += bound
        r = episode.run(genome, seconds=seconds, trials=trials, listener=watch).rows
        disp = r.end_position - r.start_position
        fwd = disp[:, 0]  # the Reil walker faces +x at the start
        for j, (family, label) in enumerate(names):
            out.append(Trial(family, label, bool(not r.fell[j]), float(r.end_time[j]), float(fwd[j]), float(np.hypot(*disp[j]))))
    return out


def summarise(trials: list[Trial]) -> list[dict]:
    """One row per family: trials, survived (count and fraction), mean forward displacement (m),
    median time to fall of the fallen (s, None if none fell)."""
    rows = []
    for family in dict.fromkeys(t.family for t in trials):
        ts = [t for t in trials if t.family == family]
        fell = [t.end_time for t in ts if not t.survived]
        rows.append({
            "family": family,
            "trials": len(ts),
            "survived": sum(t.survived for t in ts),
            "survival": sum(t.survived for t in ts) / len(ts),
            "forward_m": float(np.mean([t.forward for t in ts])),
            "median_fall_s": float(np.median(fell)) if fell else None,
        })
    return rows


def table(rows: list[dict]) -> str:
    """The summary as an aligned text table, one header per column."""
    head = ("family", "survived", "of", "survival", "mean forward (m)", "median fall time of the fallen (s)")
    lines = [f"{head[0]:<16}{head[1]:>9}{head[2]:>5}{head[3]:>10}{head[4]:>18}{head[5]:>36}"]
    for r in rows:
        fall = "-" if r["median_fall_s"] is None else f"{r['median_fall_s']:.2f}"
        lines.append(f"{r['family']:<16}{r['survived']:>9}{r['trials']:>5}{100 * r['survival']:>9.0f}%{r['forward_m']:>18.2f}{fall:>36}")
    return "\n".join(lines)
