"""Straight-line walking: fitness = planar distance from the start (Reil & Husbands eq. 4).

    W = sqrt((x_t - x_0)^2 + (y_t - y_0)^2)

with t the time the evaluation ends (the time limit, or the fall that ends it
early).  The walker's position is its planar position (the pelvis centre for
the Reil body); for a simulation that blew up, the last finite position counts.

Cyclic-activity criterion (Sect. III-A: "an additional fitness criterion that
actively rewarded cyclic activity"; the paper gives no formula, this is ours).
For each motor neuron j, over the ticks the walker was evaluated:

    m_j = mean output;  a cycle = a passage from below m_j - h to above m_j + h
    (h = ``cyclic_band``, 0.05 of the unit output range), counted n_j times;
    c = mean_j min(n_j, N) / N      with N = ``cyclic_cycles`` (25: 0.5 Hz over 50 s)
    fitness = W (1 + ``cyclic_weight`` c)

so c in [0, 1] grows with sustained oscillation of every motor neuron and
vanishes for a network that settles to a fixed point; it multiplies distance,
so oscillating in place earns nothing.  ``cyclic_weight`` = 0 (default) is the
paper's plain eq. 4; ``evobiped evolve --cyclic`` sets it to 1.

Forward progress (``fitness = "forward"``, beyond the paper).  Eq. 4 pays a 2-3 m lunge that falls more than a
shuffle that stays up, and pays walking backwards as much as forwards.  The forward fitness is

    F = (d_fwd + survival_credit) * t_up / T

with d_fwd the displacement (m) along the direction the walker faced at the start (negative when it walks
backwards), t_up the time it stayed up and T the episode length (s).  Staying up is paid first (F grows with t_up
even before the walker moves), then distance forward.

Weighted terms (``fitness = "weighted"``, beyond the paper): F = sum_k w_k term_k over the terms named in
``weights`` (e.g. forward m, time up s, steps), the weights a run's curriculum may change from one phase to the next
(:mod:`evobiped.run.curriculum`).  ``steps`` counts the walker's stance switches (a touchdown of the swing
foot, :mod:`evobiped.physics.gait`): paying for steps teaches a policy on point feet to step, the only way it stays up.

Gait measures (``gait_measures = true``): the terms ``speed``, the mean forward speed (m/s: the pelvis's path
projected each tick on the direction it faces, over the time up, so a walker on a circle walks at its speed along
it), and ``turning``, the mean turning rate (deg/s: the facing's unwrapped change over the time up, + to the left):
what a gait repertoire's cells are measured by.

Heading sense (``heading_sense = true``): the task adds the sensor ``heading_error`` (rad, in (-pi, pi]): the angle
from the direction the walker faced at the start to the direction it faces now, + turned to its left; fed to a
controller it keeps long walks straight.

Pace (under the weighted fitness): the displacement forward, counted up to ``pace_cap`` (m/s) times the time up.

Gait terms (``gait_terms = true``, or weights that name one): the gait lab's measures of each row over its time up
(:mod:`evobiped.physics.gait_lab`: duty factors, time airborne, slip, work, ...), from the body's feet.
"""

from __future__ import annotations

import numpy as np

from dataclasses import dataclass

from ..physics import gait_lab
from ..core.errors import ConfigError
from ..core.options import option
from .base import Task
from .cycles import count_cycles
from .states import WalkState
from .terms import LAB, WALK_TERMS, weighable


def displacement_heading(start_xy: np.ndarray, end_xy: np.ndarray, start_facing: np.ndarray) -> np.ndarray:
    """Direction of walking: the heading of the displacement relative to the initial facing.

    ``start_xy``, ``end_xy`` ``(P, 2)`` m, ``start_facing`` ``(P, 2)`` (any length) -> ``(P,)``
    degrees in (-180, 180]: 0 = straight ahead, +90 = to the walker's left, -90 = to its
    right, +-180 = straight backwards; NaN for a walker that did not move (under 1 mm).
    """
    d = np.asarray(end_xy, float) - np.asarray(start_xy, float)
    f = np.asarray(start_facing, float)
    deg = np.degrees(np.arctan2(f[:, 0] * d[:, 1] - f[:, 1] * d[:, 0], np.einsum("pi,pi->p", f, d)))
    deg = np.where(deg == -180.0, 180.0, deg)
    return np.where(np.linalg.norm(d, axis=1) < 1e-3, np.nan, deg)


def direction_words(heading_deg: float) -> str:
    """``displacement_heading`` of one walker in words, e.g. "-172 deg: backwards"."""
    if not np.isfinite(heading_deg):
        return "did not move"
    a = abs(heading_deg)
    side = "left" if heading_deg > 0 else "right"
    words = ("forwards" if a <= 30 else f"forwards and to the {side}" if a < 60 else f"to the {side}" if a <= 120
             else f"backwards and to the {side}" if a < 150 else "backwards")
    return f"{heading_deg:+.0f} deg from the initial facing: {words}"


#: fitness name -> what it pays (see the module docstring)
FITNESS = {"distance": "eq. 4: planar distance from the start (m)",
           "forward": "(displacement forward + survival_credit) * time up / T",
           "weighted": "sum of weights[term] * term"}
#: the walk task's terms beside the gait lab's, in the order it reports them (:data:`WALK_TERMS`)
TERMS = tuple(name for g in WALK_TERMS if g.terms is not LAB for name in g.all_names)
#: the gait lab's terms (``gait_terms``): the duty factor of each foot, then the measures
LAB_TERMS = gait_lab.terms("physics_step")
#: those a ``gait_sampling = "control_tick"`` meter gives
LAB_TERMS_TICK = gait_lab.terms("control_tick")


def check_weights(v, task: str, also: tuple[str, ...] = ()) -> None:
    """ConfigError unless ``v`` is a table of finite weights whose names are terms ``task`` may weigh (``also``: its
    own, before the walk task's weighable ones of :data:`WALK_TERMS`)."""
    if not (isinstance(v, dict) and v and all(isinstance(k, str) for k in v)
            and all(isinstance(w, (int, float)) and not isinstance(w, bool) and np.isfinite(w) for w in v.values())):
        raise ConfigError(f"must be a table of finite weights by term name, got {v!r}")
    known = also + weighable()
    unknown = [k for k in v if k not in known]
    if unknown:
        plain = ", ".join(k for k in known if k not in LAB_TERMS)
        raise ConfigError(f"names no term of the {task} task: {', '.join(unknown)} (terms: {plain}, "
                          f"and the gait terms {', '.join(LAB_TERMS)})")


def _weights(v) -> None:
    check_weights(v, "walk")


def weighted(terms: dict[str, np.ndarray], weights: dict[str, float]) -> np.ndarray:
    """``sum_k weights[k] * terms[k]``, ``(n,)``; terms in the order the weights name them."""
    out = np.zeros(len(next(iter(terms.values()))))
    for k, w in weights.items():
        out = out + float(w) * terms[k]
    return out


@dataclass(frozen=True, kw_only=True)
class WalkOptions:
    """Options of the walk task."""

    fitness: str = option("distance", "`distance`: eq. 4, the planar distance from the start; `forward`: "
                          "(displacement forward + survival_credit) * time up / T", choices=tuple(FITNESS))
    survival_credit: float = option(5.0, "what staying up earns under the forward fitness", unit="m", low=0)
    cyclic_weight: float = option(0.0, "weight of the cyclic-activity criterion (0: the paper's plain eq. 4)", low=0)
    cyclic_cycles: int = option(25, "cycles per motor neuron that earn the full criterion", low=1, integer=True)
    cyclic_band: float = option(0.05, "hysteresis band of a cycle, in unit motor output", above=0)
    weights: dict = option({"forward": 10.0, "time_up": 5.0, "steps": 0.1},
                           "the weighted fitness's weight of each term "
                           "(forward m, time_up s, steps, distance m)", check=_weights)
    gait_measures: bool = option(False, "add the terms speed (mean forward speed, m/s) and turning (mean turning rate, "
                                 "deg/s, + left)")
    heading_sense: bool = option(False, "add the sensor heading_error: the facing's angle from the initial facing "
                                        "(rad, + left)")
    pace_cap: float = option(0.6, "the weighted fitness's term pace: the displacement forward, counted up to this "
                                  "speed times the time up (a walk is paid, a faster run is not)", unit="m/s", above=0)
    gait_terms: bool = option(False, "add the gait lab's terms (duty factors, airborne, slip, power, ...; also on when "
                              "the weights name one)")
    gait_sampling: str = option("control_tick", gait_lab.SAMPLING_HELP, choices=tuple(gait_lab.SAMPLINGS))

    def __post_init__(self):
        if self.fitness != "distance" and self.cyclic_weight:
            raise ConfigError("the cyclic criterion multiplies eq. 4; use it with fitness = 'distance'")
        gait_lab.check_sampled(self.weights, self.gait_sampling, "weights")


class WalkTask(Task):
    """Walking away from the start (:class:`WalkState`)."""

    name = "walk"
    Options = WalkOptions
    #: ``distance`` eq. 4 (m), ``forward`` displacement along the initial facing (m), ``cyclicity`` c in [0, 1]
    #: (NaN without the cyclic criterion)
    #: ``time_up`` s until the walker fell (the episode's length if it did not), ``steps`` stance switches (both only
    #: under the weighted fitness)
    term_names = TERMS
    sensor_text = {"heading_error": "the facing's angle from the initial facing (rad, + left)"}
    criteria = {
        "plain": {"fitness": "distance", "cyclic_weight": 0.0},
        "cyclic": {"fitness": "distance", "cyclic_weight": 1.0},
        "forward": {"fitness": "forward", "cyclic_weight": 0.0},
    }

    def __init__(self, options=None, **given):
        super().__init__(options, **given)
        o = self.options
        self.fitness_name = o.fitness
        self.survival_credit = float(o.survival_credit)
        self.cyclic_weight = float(o.cyclic_weight)
        self.cyclic_cycles = int(o.cyclic_cycles)
        self.cyclic_band = float(o.cyclic_band)
        self.weights = dict(o.weights)
        self.heading_sense = bool(o.heading_sense)
        self.counts_steps = self.weighs_terms = self.fitness_name == "weighted"
        # time_up and steps only under the weighted fitness: the other fitnesses' files keep their columns
        self.gait_lab = o.gait_terms or (self.fitness_name == "weighted" and any(k in LAB_TERMS for k in self.weights))
        self.sampling = o.gait_sampling
        self.lab_terms = gait_lab.terms(self.sampling) if self.gait_lab else ()
        self.term_groups = tuple(g for g in WALK_TERMS if g.wanted(self))  # the table's, as these options report
        self.term_names = tuple(name for g in self.term_groups for name in g.reported(self))

    def sensor_widths(self):
        return {"heading_error": 1} if self.heading_sense else {}

    def sensor_norms(self):
        return {"heading_error": ((0.0,), (0.3,))} if self.heading_sense else {}

    def sensor_mirror(self):
        return {"heading_error": ((0,), (-1,))} if self.heading_sense else {}

    def sensors(self, body, sims, state):
        if not self.heading_sense:
            return {}
        f0, f = state.facing, body.heading(sims)
        return {"heading_error": np.arctan2(f0[:, 0] * f[:, 1] - f0[:, 1] * f[:, 0],
                                            np.einsum("pi,pi->p", f0, f))[:, None]}

    def start(self, body, sims):
        p0 = body.planar_position(sims).copy()
        state = WalkState(start=p0, position=p0.copy(), facing=body.heading(sims).copy(),
                          n_motor=len(body.actuator_names))
        if self.cyclic_weight:
            state.motor, state.ticks = [], np.zeros(sims.n, int)
        for g in self.term_groups:  # what each group of terms keeps from tick to tick
            if g.start is not None:
                state.kept.update(g.start(self, body, sims, state))
        return state

    def reads_neurons(self):
        return bool(self.cyclic_weight)  # the cyclic criterion counts the motor neurons' cycles

    def reads_feet_steps(self):
        return self.gait_lab and self.sampling == "physics_step"

    def on_tick(self, body, sims, state, ids, healthy, neurons):
        ok = ids[healthy]
        for g in self.term_groups:  # each reads the position of the tick before
            if g.tick is not None:
                g.tick(self, body, sims, state, ok, neurons)
        state.position[ok] = body.planar_position(sims)[ok]

    def distance(self, state) -> np.ndarray:
        """Eq. 4, ``(P,)`` m."""
        return np.linalg.norm(state.position - state.start, axis=1)

    def cyclicity(self, state) -> np.ndarray:
        """c in [0, 1] per individual ``(P,)`` (see the module docstring); counted once per tick count."""
        if not state.motor:
            return np.zeros(len(state.start))
        done = state.cyclicity
        if done is None or done[0] != len(state.motor):
            n = count_cycles(np.stack(state.motor), state.ticks, self.cyclic_band)
            done = state.cyclicity = (len(state.motor),
                                      (np.minimum(n, self.cyclic_cycles) / self.cyclic_cycles).mean(axis=1))
        return done[1]

    def terms(self, state):
        out = {}
        for g in self.term_groups:  # in the table's order, each given those before
            out.update(g.value(self, state, out))
        return out

    def end_position(self, body, sims, state):
        return state.position

    def fitness_label(self):
        if self.fitness_name == "weighted":
            return "fitness: " + " + ".join(f"{w:g} × {k}" for k, w in self.weights.items())
        if self.fitness_name == "forward":
            return f"fitness (m): (forward displacement + {self.survival_credit:g} m for staying up) × time up / T"
        if self.cyclic_weight:
            return "fitness (m): distance × (1 + cyclic activity)"
        return "fitness: distance from the start (m)"

    def forward(self, state) -> np.ndarray:
        """Displacement along the initial facing, ``(P,)`` m (negative: backwards)."""
        return np.einsum("pi,pi->p", state.position - state.start, state.facing)

    def fitness(self, state):
        if self.fitness_name == "weighted":
            return weighted(self.terms(state), self.weights if state.weights is None else state.weights)
        if self.fitness_name == "forward":
            up = state.end_time / state.seconds
            return (self.forward(state) + self.survival_credit) * up
        W = self.distance(state)
        if not self.cyclic_weight:
            return W
        return W * (1.0 + self.cyclic_weight * self.cyclicity(state))
