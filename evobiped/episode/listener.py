"""Who may watch an episode (:class:`Listener`: recording, figures, measures) and what it sees of it."""

from __future__ import annotations

from typing import Protocol

import mujoco
import numpy as np

from ..bodies.base import Body
from ..controllers.base import Controller
from ..physics.sim import Sims
from ..tasks.base import Task, TaskState
from .result import EpisodeResult


class Watched(Protocol):
    """What a listener reads of the episode it watches (an :class:`~evobiped.episode.Episode`)."""

    body: Body
    task: Task
    controller: Controller | None
    model: mujoco.MjModel
    #: s per control tick
    control_dt: float
    #: the action bounds ``(n_act,)`` (rad targets or N m torques)
    low: np.ndarray
    high: np.ndarray


class Listener(Protocol):
    """Watches an episode (recording, figures); never changes it.  A listener with ``reads_feet_steps = True`` reads
    the gait lab's samples after every physics step of each tick (``Body.tick_feet``), which the episode then
    collects."""

    def start(self, episode: Watched, sims: Sims) -> None: ...
    def tick(self, t: float, sims: Sims, ids: np.ndarray, neurons: np.ndarray, action: np.ndarray,
             task_state: TaskState) -> None: ...
    def end(self, result: EpisodeResult) -> None: ...


class Listeners:
    """Several listeners as one (e.g. one recorder per presentation)."""

    def __init__(self, *listeners: Listener):
        self.listeners = listeners
        self.reads_feet_steps = any(getattr(x, "reads_feet_steps", False) for x in listeners)

    def start(self, episode, sims):
        for x in self.listeners:
            x.start(episode, sims)

    def tick(self, t, sims, ids, neurons, action, task_state):
        for x in self.listeners:
            x.tick(t, sims, ids, neurons, action, task_state)

    def end(self, result):
        for x in self.listeners:
            x.end(result)
