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
"""

from __future__ import annotations

import numpy as np

from dataclasses import dataclass

from ..errors import ConfigError
from ..options import given, option
from .base import Task

#: the paper's (-3, -10) and (3, -10) in its x-z frame (walking towards -z), in ours (facing +x)
DEFAULT_SOURCES = ((10.0, 3.0), (10.0, -3.0))
#: m: a source nearer than this to the start (the origin) is refused
MIN_SOURCE_DISTANCE = 0.5


def ear_signal(left: np.ndarray, right: np.ndarray, source: np.ndarray) -> np.ndarray:
    """s = (a - b) / (a + b) for ear ground positions ``(n, 2)`` and sources ``(n, 2)`` -> ``(n,)``."""
    a = 1.0 / np.maximum(np.sum((left - source) ** 2, axis=1), 1e-12)
    b = 1.0 / np.maximum(np.sum((right - source) ** 2, axis=1), 1e-12)
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
    each; ``sources`` None leaves it as it is.  UserError for an episode of another task."""
    import dataclasses

    from ..errors import UserError

    if sources is None:
        return config
    if config.task != "steer":
        raise UserError(f"--source applies to the steer task (--task steer); this episode's task is {config.task!r}")
    return dataclasses.replace(config, task_options={**given(config.task_options), "sources": [list(map(float, s)) for s in sources]})


#: fitness name -> what it pays (see the module docstring)
FITNESS = {"distance": "the paper's: minus the distance to the source when the episode ends, fall or not (m)",
           "arrive": "minus the distance to the source at the end, minus fall_penalty + fall_time_cost (T - t) per fall (m)"}


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


class SteerTask(Task):
    """State: ``start``, ``position`` ``(n, 2)`` m (the last finite planar position), ``source`` ``(n, 2)`` m
    (each row's source)."""

    name = "steer"
    Options = SteerOptions
    #: ``distance`` from the start (m), ``distance_to_source`` from the row's source at the end (m)
    term_names = ("distance", "distance_to_source")

    def __init__(self, options=None, **given):
        super().__init__(options, **given)
        self.sources = parse_sources(self.options.sources)
        self.presentations = len(self.sources)
        self.fitness_name = self.options.fitness

    def bind_model(self, model) -> None:
        try:
            self._ears = (model.site("left_ear").id, model.site("right_ear").id)
        except KeyError:
            raise ConfigError("steer task: the body has no ears (sites 'left_ear' and 'right_ear')") from None

    def sensor_widths(self):
        return {"sound": 1}

    def sensor_norms(self):
        return {"sound": ((0.0,), (1.0,))}  # already in [-1, 1], 0 when the source is straight ahead or behind

    def start(self, body, sims):
        p0 = body.planar_position(sims).copy()
        return {"start": p0, "position": p0.copy(), "source": self.sources[self.presentation_of(sims.n)]}

    def sensors(self, body, sims, state):
        left, right = (sims.site_xpos[:, i, :2] for i in self._ears)
        return {"sound": ear_signal(left, right, state["source"])[:, None]}

    def on_tick(self, body, sims, state, ids, healthy, neurons):
        ok = ids[healthy]
        state["position"][ok] = body.planar_position(sims)[ok]

    def fitness(self, state):
        distance = np.linalg.norm(state["position"] - state["source"], axis=1)
        if self.fitness_name == "distance":
            return -distance
        R, c = float(self.options.fall_penalty), float(self.options.fall_time_cost)
        lost = state["seconds"] - state["end_time"]  # s of the episode lost to a fall, 0 for a walker up to the end
        fall = np.where(lost > 0, R + c * lost, 0.0)
        return -np.minimum(distance, R) - self.presentations * fall

    def terms(self, state):
        return {"distance": np.linalg.norm(state["position"] - state["start"], axis=1),
                "distance_to_source": np.linalg.norm(state["position"] - state["source"], axis=1)}

    def end_position(self, body, sims, state):
        return state["position"]

    def targets(self):
        return self.sources

    def fitness_label(self):
        if self.fitness_name == "arrive":
            return f"fitness (m): -distance to the source - ({self.options.fall_penalty:g} m + {self.options.fall_time_cost:g} m/s × time lost) per fall"
        return "fitness: -distance to the source (m)"

    def combine(self, fitness: np.ndarray) -> np.ndarray:
        return fitness.mean(axis=1)
