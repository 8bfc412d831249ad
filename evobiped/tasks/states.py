"""The tasks' states: what each task keeps of an episode in progress, beside the fields every task state has and the
episode writes (:class:`~evobiped.tasks.base.TaskState`).  A field None is one the task's options leave out; arrays
are ``(n, ...)`` over the episode's simulation rows."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..physics.gait_lab import GaitMeter
from .base import TaskState
from .command_schedule import CommandSchedule, DrawnCommands


@dataclass(eq=False, kw_only=True)
class WalkState(TaskState):
    """The walk task's (:mod:`evobiped.tasks.walk`)."""

    #: m ``(n, 2)``: where each row started, its last finite planar position; its facing at the start ``(n, 2)``
    start: np.ndarray
    position: np.ndarray
    facing: np.ndarray
    #: the motor neurons (the first of a controller's neuron outputs)
    n_motor: int
    #: the cyclic criterion: the motor neurons' outputs of every tick ``(n, n_motor)``, each row's ticks up ``(n,)``,
    #: and the criterion as last counted (ticks counted, c ``(n,)``)
    motor: list[np.ndarray] | None = None
    ticks: np.ndarray | None = None
    cyclicity: tuple[int, np.ndarray] | None = None
    #: what the terms of :data:`evobiped.tasks.terms.WALK_TERMS` keep from tick to tick, by name (their ``start``):
    #: the steps (``stance``, ``steps``), the gait measures (``travel``, ``yaw``, ``facing_now``), the gait lab's
    #: meter (``gait_lab``)
    kept: dict[str, Any] = field(default_factory=dict)


@dataclass(eq=False, kw_only=True)
class SteerState(TaskState):
    """The steer task's (:mod:`evobiped.tasks.steer`)."""

    #: m ``(n, 2)``: where each row started, its last finite planar position, its source
    start: np.ndarray
    position: np.ndarray
    source: np.ndarray
    #: control ticks each row spent within reach of its source, up ``(n,)``; control ticks of the episode
    near: np.ndarray
    ticks: int = 0
    #: the gait lab's meter, under ``gait_weights``
    gait_lab: GaitMeter | None = None


@dataclass(eq=False, kw_only=True)
class CommandState(WalkState):
    """The command task's (:mod:`evobiped.tasks.command`): the walk task's and its own."""

    #: the commands followed (the schedule, or a generation's draw)
    commands: CommandSchedule | DrawnCommands
    #: s ``(n,)``: each row's start, the end of its last tick, and its time scored
    t0: np.ndarray
    clock: np.ndarray
    up: np.ndarray
    #: the facing at the last tick ``(n, 2)``, the commanded facing (rad, ``(n,)``)
    last_facing: np.ndarray
    yaw_cmd: np.ndarray
    #: the measured forward speed, speed and turning rate (m/s, m/s, rad/s; smoothed) ``(n, 3)``, the tracking terms'
    #: integrals ``(n, 3)``, and whether a row has yet to take its first tick ``(n,)``
    measured: np.ndarray
    sums: np.ndarray
    first: np.ndarray


@dataclass(eq=False, kw_only=True)
class SteerCommandState(CommandState):
    """The steer-command task's (:mod:`evobiped.tasks.steer_command`): the command task's and its own."""

    #: m ``(n, 2)``: each row's source; whether the rule has it stopped ``(n,)``; its commands now (speed m/s,
    #: turning rad/s) ``(n, 2)``; the first time it was within reach (s, NaN: not yet) ``(n,)``; the distance it hears
    #: (m, low-passed), its rate (m/s, low-passed) and when it last heard (s) ``(n, 3)`` (NaN: not yet heard)
    source: np.ndarray
    stopped: np.ndarray
    current: np.ndarray
    arrival: np.ndarray
    heard: np.ndarray
