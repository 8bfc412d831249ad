"""Sound-source steering (Reil & Husbands Sect. IV, Figs. 9-13).

Ears.  Two ears at the ends of the pelvis (sites ``left_ear``, ``right_ear`` of
the body's model).  A source on the ground plane at ``q`` is heard by an ear
at ground position ``e`` with the free-field intensity of a point source,
``I = 1 / |e - q|^2`` (inverse-square law; the loudness scale cancels below).
The preprocessed signal of Fig. 9 is

    s = (a - b) / (a + b),   a = I_left,  b = I_right,

so s > 0 when the source is on the walker's left, s < 0 on its right, s = 0
when it faces the source (or has it straight behind), and |s| grows as the
walker gets nearer: for ears at +-e from the pelvis centre and a source at
distance D and bearing theta (left positive), s = 2 D e sin(theta) / (D^2 + e^2).
s is the task sensor ``sound`` (width 1), fed to every CTRNN neuron through
its own evolved weight (Fig. 10).

Sources are world (x, y) positions in m; the walker starts at the origin
facing +x with its left ear towards +y.  The default sources (10, 3) and
(10, -3) are the paper's (-3, -10) and (3, -10) (Fig. 12): there the walker
walks towards -z in an x-z ground plane and x = -3 is its left.

Presentations.  Each genome is evaluated once per source, every time from the
default start; the episode runs them
side by side in one batch.  Fitness of a presentation = -(planar distance of
the pelvis centre to that source) when it ends (time limit or fall);
a genome's fitness is the mean over its presentations (``fitness =
"distance"``, the paper's, the default).

Arriving standing (``fitness = "arrive"``, beyond the paper).  The paper's
fitness reads the distance when the episode ends, fall or not, so it pays
collapsing on the source as much as standing on it.  The arrive fitness
charges every fall more than any distance can cost.  With S presentations,
d_j the distance (m) to source j when presentation j ends, t_j the time (s)
it stayed up, T the episode length (s), fell_j = 1 when it fell (t_j < T)
and 0 otherwise, R = ``fall_penalty`` (m) and c = ``fall_time_cost`` (m/s):

    F = -(1/S) sum_j min(d_j, R)  -  sum_j fell_j (R + c (T - t_j))

A genome that falls in any presentation scores below -R, one that never
falls at least -R (its distances are capped at R), so a fall anywhere is worse
than any distance; among falls a later one costs less (c per second lost),
which leads evolution from walkers that fall towards walkers that stay up.
Up to the end, only the final distance counts: arriving early and stepping
in place, or circling close to the source, score alike.  Per presentation
(what :meth:`SteerTask.fitness` returns, one value per simulation row) the
fall term is multiplied by S, f_j = -min(d_j, R) - S fell_j (R + c (T - t_j)),
so that the mean over the presentations is F.

Random sources (``random_sources = S``, beyond the paper).  A policy that
must reach any source is trained on new ones every generation: S sources at
distances uniform in ``source_distance`` = [low, high] m and bearings
uniform in ``source_bearing`` = [low, high] degrees from the initial facing
(left positive), drawn from (run seed, generation) only, so every genome of a
generation hears the same S sources (common random numbers; a resume or the
number of workers changes nothing).  ``sources`` stays what a nominal episode
(replay, ``episode``, the battery) presents; it must then hold S sources.
Refused with one line: a nearest source inside the walker's start
(low < 0.5 m), a bearing range wider than +-180 deg, an empty range (low > high).

Lingering at the source (``reach`` m and ``reach_bonus`` m, arrive fitness
only).  A walker that arrives early and stops or circles within ``reach`` of
its source is paid ``reach_bonus`` times the fraction of the episode's control
ticks it spent there, up: per presentation
f_j = -min(d_j, R) + b u_j - S fell_j (R + b + c (T - t_j)), u_j that fraction.
The fall term grows by b, so a fall anywhere still scores below (at most equal
to) any walker that stays up.

``sound_limit`` L < 1 clips the sense to +-L: the side heard is kept, the
loudness of a near source capped (a network's input weights act on it
linearly; near the source s grows towards +-1 and would swamp the gait).
``loudness = true`` adds the distance cue ``loudness`` = min(1, (a + b) / 2 * 1 m^2) ~ min(1, 1 / D^2) (1 within 1 m).
"""

from __future__ import annotations

import numpy as np

from dataclasses import dataclass

from ..core.errors import ConfigError
from ..core.options import option
from ..physics.gait_lab import SAMPLING_HELP, check_sampled, terms
from .base import Task
from .sound import (DEFAULT_SOURCES, MIN_SOURCE_DISTANCE, check_range, draw_sources, ear_signal, ear_sites, intensity,
                    parse_sources)
from .states import SteerState
from .walk import LAB_TERMS

#: fitness name -> what it pays (see the module docstring)
FITNESS = {"distance": "the paper's: minus the distance to the source when the episode ends, fall or not (m)",
           "arrive": "minus the distance to the source at the end, minus fall_penalty + fall_time_cost (T - t) per "
                     "fall (m)"}


def _gait_weights(v) -> None:
    if not isinstance(v, dict) or not all(isinstance(w, (int, float)) and not isinstance(w, bool) and np.isfinite(w)
                                          for w in v.values()):
        raise ConfigError(f"must be a table of finite weights by gait term, got {v!r}")
    unknown = [k for k in v if k not in LAB_TERMS]
    if unknown:
        raise ConfigError(f"names no gait term: {', '.join(unknown)} (terms: {', '.join(LAB_TERMS)})")


@dataclass(frozen=True, kw_only=True)
class SteerOptions:
    """Options of the steer task."""

    sources: tuple = option(DEFAULT_SOURCES, "sound sources on the ground plane, one presentation each", unit="m",
                            check=parse_sources, span="[[x, y], ...], none at the start")
    fitness: str = option("distance", "`distance`: the paper's, minus the distance to the source when the episode "
                                      "ends, fall or not; `arrive`: the same, minus fall_penalty + fall_time_cost (T - "
                                      "t_fall) for every presentation that falls", choices=tuple(FITNESS))
    fall_penalty: float = option(100.0, "under the arrive fitness: what a fall costs, and the cap on each final "
                                 "distance (so any fall scores below any walker that stays up)", unit="m", above=0)
    fall_time_cost: float = option(1.0, "under the arrive fitness: what a fall costs per second of the episode it "
                                   "loses", unit="m/s", low=0)
    sound_limit: float = option(1.0, "the sense sound is s clipped to +-sound_limit (1: as heard); keeps the side "
                                "heard and caps the loudness of a near source", above=0, high=1)
    random_sources: int = option(0, "S sources drawn anew each generation of a run from source_distance and "
                                 "source_bearing (0: the fixed sources); sources must then hold S", low=0, high=64,
                                 integer=True)
    source_distance: tuple = option((), "[low, high]: the distances of random sources", unit="m", check=check_range,
                                    span="[] or [low, high], 0.5 <= low <= high")
    source_bearing: tuple = option((-60.0, 60.0), "[low, high]: the bearings of random sources from the initial "
                                                  "facing, left positive", unit="deg", check=check_range,
                                   span="[low, high] within [-180, 180]")
    reach: float = option(0.0, "under the arrive fitness: within this distance of its source a walker up earns "
                               "reach_bonus", unit="m", low=0)
    reach_bonus: float = option(0.0, "under the arrive fitness: paid times the fraction of the episode spent within "
                                     "reach, up", unit="m", low=0)
    loudness: bool = option(False, "offer the distance cue `loudness` = min(1, 1 m^2 / D^2), D the ears' distance (m) "
                                   "to the source")
    gait_weights: dict = option({}, "the gait lab's terms (airborne, sliding, duty_asymmetry, steps_per_s, ...), "
                                    "weighted and added to each presentation's fitness, e.g. {airborne = -100, sliding "
                                    "= -200}: pays a walk on the way; the terms join history.csv", check=_gait_weights)
    gait_sampling: str = option("control_tick", SAMPLING_HELP, choices=("physics_step", "control_tick"))

    def __post_init__(self):
        from ..core.options import check_fields

        check_fields(self, "episode.task_options")
        check_sampled(self.gait_weights, self.gait_sampling, "gait_weights")
        if self.random_sources:
            if not self.source_distance:
                raise ConfigError("source_distance: random_sources need a range of distances [low, high] m; the "
                                  "distribution is empty")
            lo, hi = self.source_distance
            if lo < MIN_SOURCE_DISTANCE:
                raise ConfigError(f"source_distance: a source {lo:g} m away is inside the walker's start (nearer than "
                                  f"{MIN_SOURCE_DISTANCE:g} m); give low >= {MIN_SOURCE_DISTANCE:g}")
            if len(parse_sources(self.sources)) != self.random_sources:
                raise ConfigError(f"sources: with random_sources = {self.random_sources}, the nominal sources (what a "
                                  f"replay presents) must be {self.random_sources} too, got "
                                  f"{len(parse_sources(self.sources))}")
        lo, hi = self.source_bearing
        if lo < -180 or hi > 180:
            raise ConfigError(f"source_bearing: a bearing range is at most [-180, 180] deg, got [{lo:g}, {hi:g}]")


class SteerTask(Task):
    """Walking to a sound source (:class:`~evobiped.tasks.states.SteerState`)."""

    name = "steer"
    sensor_text = {"sound": "the steer task's ear signal s (its sensor, after the body's)",
                   "loudness": "min(1, 1 m^2 / D^2), D the ears' distance to the source (m)"}
    Options = SteerOptions
    #: ``distance`` from the start (m), ``distance_to_source`` from the row's source at the end (m)
    term_names = ("distance", "distance_to_source")

    def __init__(self, options=None, **given):
        super().__init__(options, **given)
        self.sources = parse_sources(self.options.sources)
        self.presentations = len(self.sources)
        self.fitness_name = self.options.fitness
        self.gait_weights = dict(self.options.gait_weights)
        self.lab_terms = terms(self.options.gait_sampling) if self.gait_weights else ()
        self.term_names = type(self).term_names + self.lab_terms

    def bind_model(self, model) -> None:
        self._ears = ear_sites(model, "steer")

    def reads_feet_steps(self):
        return bool(self.gait_weights) and self.options.gait_sampling == "physics_step"

    def sensor_widths(self):
        return {"sound": 1, **({"loudness": 1} if self.options.loudness else {})}

    def sensor_norms(self):  # sound in [-1, 1], 0 when the source is straight ahead or behind; loudness in [0, 1]
        return {"sound": ((0.0,), (1.0,)), "loudness": ((0.0,), (0.1,))}

    def sensor_mirror(self):  # a source on the left is on the right of the mirrored body; loudness is the same
        return {"sound": ((0,), (-1,)), "loudness": ((0,), (1,))}

    def start(self, body, sims):
        p0 = body.planar_position(sims).copy()
        state = SteerState(start=p0, position=p0.copy(), source=self.sources[self.presentation_of(sims.n)],
                           near=np.zeros(sims.n))
        if self.gait_weights:
            state.gait_lab = self.gait_meter(body, sims, self.options.gait_sampling)
        return state

    def draw_sources(self, key) -> np.ndarray | None:
        """This generation's random sources ``(S, 2)`` m (None: the fixed ones); :func:`draw_sources`."""
        return draw_sources(self.options, key)

    def take_sources(self, state, sources: np.ndarray) -> None:
        """Present ``sources`` ``(S, 2)`` m (a generation's draw) instead of the fixed ones."""
        state.source = np.asarray(sources, float)[self.presentation_of(len(state.source))]

    def sensors(self, body, sims, state):
        left, right = (sims.site_xpos[:, i, :2] for i in self._ears)
        s = ear_signal(left, right, state.source)[:, None]
        out = {"sound": s if self.options.sound_limit >= 1
               else np.clip(s, -self.options.sound_limit, self.options.sound_limit)}
        if self.options.loudness:
            out["loudness"] = np.minimum((intensity(left, state.source) + intensity(right, state.source)) / 2,
                                         1.0)[:, None]
        return out

    def on_tick(self, body, sims, state, ids, healthy, neurons):
        ok = ids[healthy]
        state.position[ok] = body.planar_position(sims)[ok]
        state.ticks += 1
        if self.options.reach > 0:
            near = np.linalg.norm(state.position[ok] - state.source[ok], axis=1) <= self.options.reach
            state.near[ok[near]] += 1
        if state.gait_lab is not None:
            state.gait_lab.tick(body.tick_feet(sims), ok, sims.time[ok])

    def fitness(self, state):
        distance = np.linalg.norm(state.position - state.source, axis=1)
        if self.fitness_name == "distance":
            return -distance
        R, c = float(self.options.fall_penalty), float(self.options.fall_time_cost)
        b = float(self.options.reach_bonus) if self.options.reach > 0 else 0.0
        lost = state.seconds - state.end_time  # s of the episode lost to a fall, 0 for a walker up to the end
        fall = np.where(lost > 0, R + b + c * lost, 0.0)
        linger = b * state.near / max(state.ticks, 1) if b else 0.0
        return -np.minimum(distance, R) + linger - self.presentations * fall + self._gait(state)

    def _gait(self, state) -> np.ndarray | float:
        """The weighted gait terms of each row (0 without ``gait_weights``; a row with no tick up adds nothing)."""
        if state.gait_lab is None:
            return 0.0
        lab = self._lab(state)
        return sum(float(w) * np.nan_to_num(lab[k]) for k, w in self.gait_weights.items())

    def _lab(self, state) -> dict[str, np.ndarray]:
        """The gait lab's measures of each row, its distance from the start (m) the path it measures speed by."""
        return state.gait_lab.measure(np.linalg.norm(state.position - state.start, axis=1))

    def terms(self, state):
        out = {"distance": np.linalg.norm(state.position - state.start, axis=1),
               "distance_to_source": np.linalg.norm(state.position - state.source, axis=1)}
        if state.gait_lab is not None:
            lab = self._lab(state)
            out.update({k: lab[k] for k in self.lab_terms})
        return out

    def end_position(self, body, sims, state):
        return state.position

    def targets(self):
        return self.sources

    def fitness_label(self):
        return self._label() + "".join(f" {'+' if w >= 0 else '-'} {abs(w):g} × {k}" for k,
                                       w in self.gait_weights.items())

    def _label(self):
        if self.fitness_name == "arrive":
            return (f"fitness (m): -distance to the source - ({self.options.fall_penalty:g} m + "
                    f"{self.options.fall_time_cost:g} m/s × time lost) per fall")
        return "fitness: -distance to the source (m)"

    def combine(self, fitness: np.ndarray) -> np.ndarray:
        return fitness.mean(axis=1)
