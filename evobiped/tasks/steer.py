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

from ..physics import gait_lab
from ..core.errors import ConfigError
from ..core.options import given, option
from .base import Task
from .states import SteerState
from .walk import LAB_TERMS

#: the paper's (-3, -10) and (3, -10) in its x-z frame (walking towards -z), in ours (facing +x)
DEFAULT_SOURCES = ((10.0, 3.0), (10.0, -3.0))
#: m: a source nearer than this to the start (the origin) is refused
MIN_SOURCE_DISTANCE = 0.5


def intensity(ear: np.ndarray, source: np.ndarray) -> np.ndarray:
    """I = 1 / |e - q|^2 (1/m^2) at ear ground positions ``(n, 2)`` from sources ``(n, 2)`` -> ``(n,)``."""
    return 1.0 / np.maximum(np.sum((ear - source) ** 2, axis=1), 1e-12)


def ear_signal(left: np.ndarray, right: np.ndarray, source: np.ndarray) -> np.ndarray:
    """s = (a - b) / (a + b) for ear ground positions ``(n, 2)`` and sources ``(n, 2)`` -> ``(n,)``."""
    a, b = intensity(left, source), intensity(right, source)
    return (a - b) / (a + b)


#: the farthest a source may be from the start (m)
MAX_SOURCE_DISTANCE = 1e4


def parse_sources(sources) -> np.ndarray:
    """``[[x, y], ...]`` in m -> ``(S, 2)``; ConfigError for anything else (e.g. a lone number)."""
    try:
        arr = np.array(sources, dtype=float)
    except (TypeError, ValueError):
        arr = None
    if arr is None or arr.ndim != 2 or arr.shape[1] != 2 or len(arr) == 0 or not np.isfinite(arr).all():
        raise ConfigError(f"sources must be a list of [x, y] positions in m, e.g. [[10, 3], [10, -3]]; got {sources!r}")
    near = np.hypot(arr[:, 0], arr[:, 1]) < MIN_SOURCE_DISTANCE
    if near.any():
        x, y = arr[np.argmax(near)]
        raise ConfigError(f"the source ({x:g}, {y:g}) is at the walker's start (nearer than {MIN_SOURCE_DISTANCE:g} m "
                          "to the origin, where it starts): it could not walk towards it")
    far = np.hypot(arr[:, 0], arr[:, 1]) > MAX_SOURCE_DISTANCE
    if far.any():  # the ears' inverse squares underflow there: the sense would be 0/0
        x, y = arr[np.argmax(far)]
        raise ConfigError(f"the source ({x:g}, {y:g}) is farther than {MAX_SOURCE_DISTANCE:g} m from the walker's start: "
                          "its sound could not be told apart by the two ears")
    return arr


def with_sources(config, sources):
    """``config`` (an EpisodeConfig of the steer task) with these sources ``[[x, y], ...]`` m, one presentation
    each (fixed: they replace random sources drawn per generation); ``sources`` None leaves it as it is.  UserError for an
    episode of another task."""
    import dataclasses

    from ..core.errors import UserError

    if sources is None:
        return config
    if config.task != "steer":
        raise UserError(f"--source applies to the steer task (--task steer); this episode's task is {config.task!r}")
    options = {**given(config.task_options), "sources": [list(map(float, s)) for s in sources]}
    options.pop("random_sources", None)  # these sources, fixed, replace a distribution drawn per generation
    return dataclasses.replace(config, task_options=options)


def _range(v) -> None:
    r = tuple(v) if isinstance(v, (list, tuple)) else None
    if r is None or len(r) not in (0, 2) or any(not isinstance(x, (int, float)) or isinstance(x, bool) or not np.isfinite(x)
                                                 for x in r) or (r and r[0] > r[1]):
        raise ConfigError(f"must be [] or [low, high] with low <= high (an empty range draws nothing), got {v!r}")


def draw_sources(options, key) -> np.ndarray | None:
    """The random sources ``(S, 2)`` m of generation key = (run seed, generation, ...) under ``options``
    (:class:`SteerOptions`); None without random sources."""
    S = int(options.random_sources)
    if not S or key is None:
        return None
    rng = np.random.default_rng([int(key[0]), int(key[1]), 0x50D])
    d = rng.uniform(*options.source_distance, S)
    a = np.radians(rng.uniform(*options.source_bearing, S))
    return np.stack([d * np.cos(a), d * np.sin(a)], axis=1)


#: fitness name -> what it pays (see the module docstring)
FITNESS = {"distance": "the paper's: minus the distance to the source when the episode ends, fall or not (m)",
           "arrive": "minus the distance to the source at the end, minus fall_penalty + fall_time_cost (T - t) per fall (m)"}


def _gait_weights(v) -> None:
    if not isinstance(v, dict) or not all(isinstance(w, (int, float)) and not isinstance(w, bool) and np.isfinite(w) for w in v.values()):
        raise ConfigError(f"must be a table of finite weights by gait term, got {v!r}")
    unknown = [k for k in v if k not in LAB_TERMS]
    if unknown:
        raise ConfigError(f"names no gait term: {', '.join(unknown)} (terms: {', '.join(LAB_TERMS)})")


@dataclass(frozen=True, kw_only=True)
class SteerOptions:
    """Options of the steer task."""

    sources: tuple = option(DEFAULT_SOURCES, "sound sources on the ground plane, one presentation each", unit="m",
                            check=parse_sources, span="[[x, y], ...], none at the start")
    fitness: str = option("distance", "`distance`: the paper's, minus the distance to the source when the episode ends, "
                          "fall or not; `arrive`: the same, minus fall_penalty + fall_time_cost (T - t_fall) for every "
                          "presentation that falls", choices=tuple(FITNESS))
    fall_penalty: float = option(100.0, "under the arrive fitness: what a fall costs, and the cap on each final "
                                 "distance (so any fall scores below any walker that stays up)", unit="m", above=0)
    fall_time_cost: float = option(1.0, "under the arrive fitness: what a fall costs per second of the episode it "
                                   "loses", unit="m/s", low=0)
    sound_limit: float = option(1.0, "the sense sound is s clipped to +-sound_limit (1: as heard); keeps the side "
                                "heard and caps the loudness of a near source", above=0, high=1)
    random_sources: int = option(0, "S sources drawn anew each generation of a run from source_distance and "
                                 "source_bearing (0: the fixed sources); sources must then hold S", low=0, high=64, integer=True)
    source_distance: tuple = option((), "[low, high]: the distances of random sources", unit="m", check=_range,
                                    span="[] or [low, high], 0.5 <= low <= high")
    source_bearing: tuple = option((-60.0, 60.0), "[low, high]: the bearings of random sources from the initial facing, "
                                   "left positive", unit="deg", check=_range, span="[low, high] within [-180, 180]")
    reach: float = option(0.0, "under the arrive fitness: within this distance of its source a walker up earns reach_bonus",
                          unit="m", low=0)
    reach_bonus: float = option(0.0, "under the arrive fitness: paid times the fraction of the episode spent within reach, up",
                                unit="m", low=0)
    loudness: bool = option(False, "offer the distance cue `loudness` = min(1, 1 m^2 / D^2), D the ears' distance (m) to the source")
    gait_weights: dict = option({}, "the gait lab's terms (airborne, sliding, duty_asymmetry, steps_per_s, ...), weighted and "
                                "added to each presentation's fitness, e.g. {airborne = -100, sliding = -200}: pays a walk on the "
                                "way; the terms join history.csv", check=_gait_weights)

    def __post_init__(self):
        from ..core.options import check_fields

        check_fields(self, "episode.task_options")
        if self.random_sources:
            if not self.source_distance:
                raise ConfigError("source_distance: random_sources need a range of distances [low, high] m; the distribution is empty")
            lo, hi = self.source_distance
            if lo < MIN_SOURCE_DISTANCE:
                raise ConfigError(f"source_distance: a source {lo:g} m away is inside the walker's start (nearer than "
                                  f"{MIN_SOURCE_DISTANCE:g} m); give low >= {MIN_SOURCE_DISTANCE:g}")
            if len(parse_sources(self.sources)) != self.random_sources:
                raise ConfigError(f"sources: with random_sources = {self.random_sources}, the nominal sources (what a replay "
                                  f"presents) must be {self.random_sources} too, got {len(parse_sources(self.sources))}")
        lo, hi = self.source_bearing
        if lo < -180 or hi > 180:
            raise ConfigError(f"source_bearing: a bearing range is at most [-180, 180] deg, got [{lo:g}, {hi:g}]")


class SteerTask(Task):
    """Walking to a sound source (:class:`~evobiped.tasks.states.SteerState`)."""

    name = "steer"
    Options = SteerOptions
    #: ``distance`` from the start (m), ``distance_to_source`` from the row's source at the end (m)
    term_names = ("distance", "distance_to_source")

    def __init__(self, options=None, **given):
        super().__init__(options, **given)
        self.sources = parse_sources(self.options.sources)
        self.presentations = len(self.sources)
        self.fitness_name = self.options.fitness
        self.gait_weights = dict(self.options.gait_weights)
        if self.gait_weights:
            self.term_names = type(self).term_names + LAB_TERMS
        self._lab_constants = None  # the body's mass and leg length, once known

    def bind_model(self, model) -> None:
        try:
            self._ears = (model.site("left_ear").id, model.site("right_ear").id)
        except KeyError:
            raise ConfigError("steer task: the body has no ears (sites 'left_ear' and 'right_ear')") from None

    def sensor_widths(self):
        return {"sound": 1, **({"loudness": 1} if self.options.loudness else {})}

    def sensor_norms(self):  # sound in [-1, 1], 0 when the source is straight ahead or behind; loudness in [0, 1]
        return {"sound": ((0.0,), (1.0,)), "loudness": ((0.0,), (0.1,))}

    def sensor_mirror(self):  # a source on the left is on the right of the mirrored body; loudness is the same
        return {"sound": ((0,), (-1,)), "loudness": ((0,), (1,))}

    def start(self, body, sims):
        p0 = body.planar_position(sims).copy()
        state = SteerState(start=p0, position=p0.copy(), source=self.sources[self.presentation_of(sims.n)], near=np.zeros(sims.n))
        if self.gait_weights:
            if not body.contact_sensor:
                raise ConfigError(f"gait_weights: the {body.name} body declares no feet to measure a gait by")
            self._lab_constants = self._lab_constants or body.gait_constants(sims.model)
            state.gait_lab = gait_lab.GaitMeter(sims.n, body.contact_sensor[1], *self._lab_constants, float(sims.time.max()))
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
        out = {"sound": s if self.options.sound_limit >= 1 else np.clip(s, -self.options.sound_limit, self.options.sound_limit)}
        if self.options.loudness:
            out["loudness"] = np.minimum((intensity(left, state.source) + intensity(right, state.source)) / 2, 1.0)[:, None]
        return out

    def on_tick(self, body, sims, state, ids, healthy, neurons):
        ok = ids[healthy]
        state.position[ok] = body.planar_position(sims)[ok]
        state.ticks += 1
        if self.options.reach > 0:
            near = np.linalg.norm(state.position[ok] - state.source[ok], axis=1) <= self.options.reach
            state.near[ok[near]] += 1
        if state.gait_lab is not None:
            state.gait_lab.tick(body.feet(sims), ok, sims.time[ok])

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
            out.update({k: lab[k] for k in LAB_TERMS})
        return out

    def end_position(self, body, sims, state):
        return state.position

    def targets(self):
        return self.sources

    def fitness_label(self):
        gait = "".join(f" {'+' if w >= 0 else '-'} {abs(w):g} × {k}" for k, w in self.gait_weights.items())
        if gait:
            return self._label() + gait
        return self._label()

    def _label(self):
        if self.fitness_name == "arrive":
            return f"fitness (m): -distance to the source - ({self.options.fall_penalty:g} m + {self.options.fall_time_cost:g} m/s × time lost) per fall"
        return "fitness: -distance to the source (m)"

    def combine(self, fitness: np.ndarray) -> np.ndarray:
        return fitness.mean(axis=1)
