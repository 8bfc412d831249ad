"""Steering through commands: a commanded walker walks to a sound source when its commands come from its ears.

The rule (:func:`steering_command`).  From the ear signal s = (a - b) / (a + b) (+ when the source is on the left;
a, b each ear's intensity 1 / |e - q|^2, :mod:`evobiped.tasks.sound`) and the loudness L = (a + b) / 2 (1/m^2), the
rule reads the distance D = 1 / sqrt(L) (m) and the bearing theta = asin(s (D^2 + e^2) / (2 D e)) (rad, + left; e the
half distance between the ears), which inverts s = 2 D e sin(theta) / (D^2 + e^2) for a source in front; a source
behind is heard as its mirror image in front, on the same side, so the walker turns towards it all the same.  Then

    turning = clip(gain * theta, -turning_max, turning_max)                                       (rad/s, + left)
    speed   = speed_min + (speed_max - speed_min) * clip((D - reach) / (slow_from - reach), 0, 1)   (m/s)

A source behind is told from one in front by the loudness over time: while the heard distance D, low-passed over
``RECEDE_TAU`` s, grows faster than ``RECEDING`` m/s, the source is behind and the rule turns round at
``turning_max`` towards the side s points to, at ``speed_min``.  And a stop (speed 0, turning 0) from the moment D falls
within ``reach`` until it rises past ``resume`` (a walker that marks time on the spot drifts a little; it walks back
when it has drifted out).  The rule is a documented mapping, not evolved; the walker's network follows the commands as
it follows any (:mod:`evobiped.tasks.command`).

The task (``steer-command``, :class:`SteerCommandTask`): the command task whose commands are the rule's, one
presentation per source (the steer task's ``sources``).  Its fitness is minus the final distance to the source (m);
its terms add ``distance_to_source`` (m, at the end), ``arrival_time`` (s: the first time within ``reach``, NaN if
never) and ``stood`` (1 when it ends up and stopped: it came within ``reach`` and has not drifted past ``resume``).
``evobiped episode --genome W --source X Y`` runs a commanded walker W on it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..core.errors import ConfigError
from ..core.options import option
from .command import CommandOptions, CommandTask
from .sound import DEFAULT_SOURCES, ear_sites, intensity, parse_sources
from .states import SteerCommandState

#: s: the time constant of the low-pass on the distance the walker hears (the stride sways the ears)
RECEDE_TAU = 1.0
#: m/s: the heard distance growing faster than this (low-passed) means the source is behind
RECEDING = 0.05


def steering_command(sound, loudness, *, ear: float, gain: float = 1.0, turning_max: float = 0.35,
                     speed_min: float = 0.2, speed_max: float = 0.6, slow_from: float = 2.0, reach: float = 0.3
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(speed m/s, turning rad/s, distance m) from the ear signal ``sound`` (s in [-1, 1]) and ``loudness`` (L, 1/m^2),
    arrays alike; ``ear`` the half distance between the ears (m), ``gain`` rad/s per rad of bearing (module docstring;
    the stop inside ``reach`` is the task's, which remembers it).  ConfigError for bounds out of order."""
    if not (gain > 0 and turning_max > 0 and 0 < speed_min <= speed_max and 0 < reach < slow_from and ear > 0):
        raise ConfigError("the steering rule needs gain, turning_max, ear > 0, 0 < speed_min <= speed_max and 0 < "
                          f"reach < slow_from, got gain {gain:g}, turning_max {turning_max:g}, speed "
                          f"{speed_min:g}-{speed_max:g}, reach {reach:g}, slow_from {slow_from:g}, ear {ear:g}")
    s, L = np.asarray(sound, float), np.maximum(np.asarray(loudness, float), 1e-12)
    D = 1.0 / np.sqrt(L)
    theta = np.arcsin(np.clip(s * (D ** 2 + ear ** 2) / (2 * D * ear), -1.0, 1.0))
    speed = speed_min + (speed_max - speed_min) * np.clip((D - reach) / (slow_from - reach), 0.0, 1.0)
    return speed, np.clip(gain * theta, -turning_max, turning_max), D


@dataclass(frozen=True, kw_only=True)
class SteerCommandOptions(CommandOptions):
    """Options of the steer-command task: the command task's, the sources, and the rule's."""

    sources: tuple = option(DEFAULT_SOURCES, "sound sources on the ground plane, one presentation each", unit="m",
                            check=parse_sources, span="[[x, y], ...], none at the start")
    gain: float = option(1.0, "the rule's turning rate per radian of the source's bearing", unit="rad/s", above=0)
    speed_min: float = option(0.2, "the rule's speed at the reach radius", unit="m/s", above=0)
    speed_max: float = option(0.6, "the rule's speed farther than slow_from", unit="m/s", above=0)
    slow_from: float = option(2.0, "the rule slows down nearer than this", unit="m", above=0)
    reach: float = option(0.3, "the rule stops within this distance of the source", unit="m", above=0)
    resume: float = option(0.6, "a stopped walker walks again when the source is farther than this", unit="m", above=0)

    def __post_init__(self):
        super().__post_init__()
        if not (self.speed_min <= self.speed_max and self.reach < self.slow_from and self.reach <= self.resume):
            raise ConfigError("steer-command: needs speed_min <= speed_max, reach < slow_from and reach <= resume, "
                              f"got speed {self.speed_min:g}-{self.speed_max:g} m/s, reach {self.reach:g} m, slow_from "
                              f"{self.slow_from:g} m, resume {self.resume:g} m")


class SteerCommandTask(CommandTask):
    """A commanded walker steered to a sound source by :func:`steering_command` (:class:`~evobiped.tasks.states.
    SteerCommandState`)."""

    name = "steer-command"
    docs_note = ("A commanded walker steered to a sound source by the rule of `evobiped/tasks/steer_command.py`\n"
                 "([below](#steering-through-commands)); the command task's options and these:")
    Options = SteerCommandOptions

    def __init__(self, options=None, **given):
        super().__init__(options, **given)
        self.sources = parse_sources(self.options.sources)
        self.presentations = len(self.sources)
        self.term_names = tuple(self.term_names) + ("distance_to_source", "arrival_time", "stood")

    def bind_model(self, model) -> None:
        super().bind_model(model)
        self._ears = ear_sites(model, "steer-command")
        left, right = (model.site_pos[i] for i in self._ears)
        self._ear = float(np.linalg.norm(left[:2] - right[:2]) / 2)

    def start(self, body, sims):
        state = super().start(body, sims)
        n = sims.n
        state = SteerCommandState(**vars(state), source=self.sources[self.presentation_of(n)],
                                  stopped=np.zeros(n, bool),
                                  current=np.zeros((n, 2)), arrival=np.full(n, np.nan), heard=np.full((n, 3), np.nan))
        self._hear(sims, state)
        return state

    def draw_sources(self, key):  # the commands come from the ears, never from a draw
        return None

    def commands(self, state, rows=None):
        rows = slice(None) if rows is None else rows
        return state.current[rows, 0], state.current[rows, 1]

    def _hear(self, sims, state) -> None:
        """The rule's commands for the next tick, from where the ears are now (kept in ``state``; the senses read them,
        so reading the senses changes nothing)."""
        o = self.options
        left, right = (sims.site_xpos[:, i, :2] for i in self._ears)
        a, b = intensity(left, state.source), intensity(right, state.source)
        speed, turning, D = steering_command((a - b) / (a + b), (a + b) / 2, ear=self._ear, gain=o.gain,
                                             turning_max=o.turning_max, speed_min=o.speed_min, speed_max=o.speed_max,
                                             slow_from=o.slow_from, reach=o.reach)
        t = np.asarray(sims.time, float)
        new = np.isnan(state.heard[:, 0])
        k = np.where(new, 1.0, 1.0 - np.exp(-(t - state.heard[:, 2]) / RECEDE_TAU))  # the low-pass's step
        previous = np.where(new, D, state.heard[:, 0])
        heard = previous + k * (D - previous)
        rate = np.where(new, 0.0, state.heard[:, 1] + k * ((heard - previous) / np.maximum(t - state.heard[:, 2], 1e-9)
                                                           - state.heard[:, 1]))
        state.heard = np.stack([heard, rate, t], axis=1)
        behind = rate > RECEDING  # walking on, it hears the source fade: it is behind, turn round towards its side
        turning = np.where(behind, np.where(turning < 0, -o.turning_max, o.turning_max), turning)
        speed = np.where(behind, o.speed_min, speed)
        state.stopped = np.where(D <= o.reach, True, np.where(D > o.resume, False, state.stopped))
        state.current = np.where(state.stopped[:, None], 0.0, np.stack([speed, turning], axis=1))

    def on_tick(self, body, sims, state, ids, healthy, neurons):
        super().on_tick(body, sims, state, ids, healthy, neurons)  # scored against the commands of the tick just run
        ok = ids[healthy]
        near = np.linalg.norm(state.position[ok] - state.source[ok], axis=1) <= self.options.reach
        first = ok[near & np.isnan(state.arrival[ok])]
        state.arrival[first] = np.asarray(sims.time, float)[first]
        self._hear(sims, state)

    def terms(self, state):
        out = super().terms(state)
        d = np.linalg.norm(state.position - state.source, axis=1)
        up = state.end_time >= state.seconds - 1e-9
        out.update(distance_to_source=d, arrival_time=state.arrival.copy(), stood=(up & state.stopped).astype(float))
        return out

    def fitness(self, state):
        return -np.linalg.norm(state.position - state.source, axis=1)

    def end_position(self, body, sims, state):
        return state.position

    def targets(self):
        return self.sources

    def fitness_label(self):
        return "fitness: -distance to the source (m), the commands from the ears"

    def combine(self, fitness: np.ndarray) -> np.ndarray:
        return fitness.mean(axis=1)
