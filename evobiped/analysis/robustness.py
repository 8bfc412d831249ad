"""The robustness battery: one fixed set of disturbed trials for any walker whose body declares its foot contacts.

Every trial starts from the nominal initial state and runs ``seconds`` (30 s
by default); a trial is survived when the walker has not fallen at the end.
Joints and contacts are found by role (``Actuator.leg``/``joint``,
``Body.contact_sensor``), never by name or column, and each family runs where it
applies: offsets on bodies of PD targets with hip pitch (and roll) roles,
friction and slope on bodies with a MuJoCo ground, sideways pushes on bodies
that are not sagittal.  On the sagittal Taga body (torques, its own ground) the
battery is the forward and backward pushes and the gene noise (40 trials).

==============  ======  ============================================================
family          trials  disturbance
==============  ======  ============================================================
push 5 N        32      a horizontal push on the pelvis for 0.1 s in one of 8
push 10 N       32      directions (every 45 deg from the initial facing: forward,
push 15 N       32      forward-left, left, ...), at 4 phases of the stride (phase
push 20 N       32      i/4 after the first left touchdown after ``push_after``)
offset 0.05     8       a constant offset on the hip targets for the whole trial: pitch
offset 0.1      8       or roll, +-m on both legs (same sign) or +m / -m (opposite signs)
friction        4       floor sliding friction 0.5, 0.75, 1.25, 1.5 (the model's is 1.0)
slope 3 %       4       a 3 % grade rising ahead (uphill), behind (downhill), to the left
slope 5 %       4       or to the right of the initial facing; the same at 5 %
gene noise 1 %  8       every gene moved by Gaussian noise of 1 % of its range (8 fixed
                        draws, seed 1): the walker's neighbours in genome space
==============  ======  ============================================================

:func:`score` is the fraction of all trials survived, one number to rank walkers by.
The stride is measured on a nominal run of the same walker (left-foot
touchdowns between ``push_after`` and the end; 1 s when the walker does not
step).  Nothing here is random: the battery is the same for every walker.

**Pushes at random phases** (``phase_seed``): the fixed phases i/4 sample the
stride at four points only, and a walker tuned on a battery can be tuned to
them.  With a ``phase_seed`` N, each of the 128 push trials falls instead at
its own phase drawn uniformly from [0, 1) of the stride (``numpy`` generator
seeded with (N, 0x9A5E)); the same N gives the same phases for every walker,
so walkers still compare like with like, and another N is a battery nobody
tuned on.  The label gives the phase to two decimals (``left, phase 0.37``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..interface.contract import index
from ..episode import Episode
from ..core.errors import UserError
from ..physics.trials import Trials
from ..core.progress import Progress

PUSH_FORCES = (5.0, 10.0, 15.0, 20.0)  # N
PUSH_DURATION = 0.1  # s
#: direction name -> angle (rad) from the initial facing towards the left; a push or a slope's rise goes that way
DIRECTIONS = {"forward": 0.0, "forward-left": np.pi / 4, "left": np.pi / 2, "backward-left": 3 * np.pi / 4,
              "backward": np.pi, "backward-right": -3 * np.pi / 4, "right": -np.pi / 2, "forward-right": -np.pi / 4}
PHASES = 4
OFFSETS = (0.05, 0.1)  # rad
FRICTIONS = (0.5, 0.75, 1.25, 1.5)
SLOPES = (0.03, 0.05)  # grade
#: where a battery slope rises -> its label
SLOPE_DIRECTIONS = {"forward": "uphill", "backward": "downhill", "left": "rising to the left",
                    "right": "rising to the right"}
GENE_NOISE = 0.01  # of each gene's range
GENE_NOISE_DRAWS = 8
GENE_NOISE_SEED = 1


def unit(direction: str) -> tuple[float, float]:
    """The unit vector of a named direction in the initial-facing frame (forward = +x, left = +y), exact on the axes."""
    a = DIRECTIONS[direction]
    return tuple(float(round(v)) if abs(v - round(v)) < 1e-12 else float(v) for v in (np.cos(a), np.sin(a)))


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


def push_phases(n: int, phase_seed: int | None) -> np.ndarray:
    """The phases (fractions of the stride) of ``n`` push trials in battery order: the fixed i/4, cycled, when
    ``phase_seed`` is None; else ``n`` uniform draws in [0, 1) from (``phase_seed``, 0x9A5E)."""
    if phase_seed is None:
        return np.arange(n) % PHASES / PHASES
    return np.random.default_rng([int(phase_seed), 0x9A5E]).uniform(0.0, 1.0, n)


def battery(episode: Episode, genome: np.ndarray, *, seconds: float = 30.0, push_after: float = 10.0,
            phase_seed: int | None = None, progress: Progress | None = None) -> list[Trial]:
    """Run every trial of the battery for one genome ``(G,)``; the episode must be nominal (no perturbations).
    ``phase_seed``: pushes at random phases of the stride (module docstring; None: the fixed i/4).
    ``progress`` (optional) hears the simulated seconds of its batches."""
    body = episode.body
    if body.contact_sensor is None or "left" not in body.contact_sensor[1]:
        raise UserError("the robustness battery needs a body that declares its left foot's contact sensor; "
                        f"{body.name!r} does not")
    if episode.task.presentations != 1:
        raise UserError(f"the robustness battery runs one presentation per trial; this {episode.task.name!r} episode "
                        f"has {episode.task.presentations} (give a steering walker one source)")
    if not push_after < seconds:
        raise UserError(f"the battery pushes after {push_after:g} s: trials must be longer (got {seconds:g} s)")
    hips = _hip_columns(episode)
    n_act = len(episode.body.actuator_names)
    layout = episode.controller.layout
    t0, period = stride(episode, genome, seconds, push_after)
    labels: list[tuple[str, str]] = []
    starts, forces, offsets = [], [], []
    if phase_seed is not None and (isinstance(phase_seed, bool) or not isinstance(phase_seed, (int, np.integer))
                                   or phase_seed < 0):
        raise UserError(f"the battery's phase seed must be an integer >= 0, got {phase_seed!r}")
    directions = {d: unit(d) for d in DIRECTIONS if not (body.sagittal and unit(d)[1])}
    phases = iter(push_phases(len(PUSH_FORCES) * len(directions) * PHASES, phase_seed))
    for f in PUSH_FORCES:
        for d, (ux, uy) in directions.items():
            for i in range(PHASES):
                p = next(phases)
                labels.append((f"push {f:g} N", f"{d}, phase {i}/{PHASES}" if phase_seed is None
                               else f"{d}, phase {p:.2f}"))
                starts.append([t0 + period * p])
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
    n_plain = len(labels)
    for i in range(GENE_NOISE_DRAWS):
        labels.append((f"gene noise {100 * GENE_NOISE:g} %", f"draw {i}"))
        starts.append([0.0])
        forces.append([[0.0, 0.0, 0.0]])
        offsets.append(np.zeros(n_act))
    genes = np.zeros((len(labels), layout.size))
    genes[n_plain:] = np.random.default_rng(GENE_NOISE_SEED).normal(0.0, GENE_NOISE, (GENE_NOISE_DRAWS, layout.size))
    main = Trials.nominal(len(labels), n_act, push_start=np.array(starts), push_force=np.array(forces),
                          push_duration=PUSH_DURATION, target_offset=np.array(offsets), gene_noise=genes)
    runs = [(labels, main)]
    if body.floor_geom is not None:
        runs += [([("friction", f"mu = {mu:g}")], Trials.nominal(1, n_act, friction=mu)) for mu in FRICTIONS]
        runs += [([(f"slope {100 * s:g} %", f"{100 * s:g} % {name}")],
                  Trials.nominal(1, n_act, slope=s, slope_direction=DIRECTIONS[d]))
                 for s in SLOPES for d, name in SLOPE_DIRECTIONS.items()]
    out = []
    n_trials = sum(len(names) for names, _ in runs)
    # trial-seconds: each trial's own simulated time, a fallen trial's rest counted at its batch's end
    if progress is not None:
        progress.total, progress.unit = float(seconds * n_trials), f"trial-s of {n_trials} trials of {seconds:g} s"
    offset = 0.0
    for k, (names, trials) in enumerate(runs):
        bound = seconds * len(names)
        later = [(len(n), seconds) for n, _ in runs[k + 1:]]  # the time left counts the batches still to come
        watch = progress.listener(offset=offset, rows=True, bound=bound, later=later) if progress is not None else None
        offset += bound
        r = episode.run(genome, seconds=seconds, trials=trials, listener=watch).rows
        disp = r.end_position - r.start_position
        fwd = disp[:, 0]  # the Reil walker faces +x at the start
        for j, (family, label) in enumerate(names):
            out.append(Trial(family, label, bool(not r.fell[j]), float(r.end_time[j]), float(fwd[j]),
                             float(np.hypot(*disp[j]))))
    return out


def score(trials: list[Trial]) -> float:
    """The robustness score: the fraction of all trials survived (0 to 1)."""
    return sum(t.survived for t in trials) / len(trials)


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
        lines.append(f"{r['family']:<16}{r['survived']:>9}{r['trials']:>5}{100 * r['survival']:>9.0f}%"
                     f"{r['forward_m']:>18.2f}{fall:>36}")
    return "\n".join(lines)
