"""The tasks' state as the compiled episode (:mod:`.whole`) takes it: the command task's schedule and arrays, the steer
task's sources and ears; for the other tasks, arrays of the same types that it does not read."""

from __future__ import annotations

import numpy as np

from ...tasks.command import CommandTask
from ...tasks.command_schedule import CLOCK_TOLERANCE, DrawnCommands
from ...tasks.steer import SteerTask


def hearing(task, tstate, P: int) -> tuple:
    """The steer task's sources, ears, sound limit, reach and ticks near as the compiled episode takes them (other
    tasks': none)."""
    if not isinstance(task, SteerTask):
        return np.zeros((P, 2)), np.zeros(2, np.int64), 1.0, 0.0, np.zeros(P)
    if tstate.near.dtype != float or not tstate.near.flags.c_contiguous:
        raise AssertionError("the steer task counts its ticks near in a contiguous float array")
    o = task.options
    return (np.ascontiguousarray(tstate.source, float), np.array(task._ears, np.int64), float(o.sound_limit),
            float(o.reach), tstate.near)


def commands(task, tstate, n: int, control_dt: float) -> tuple:
    """The command task's schedule, arrays and options as the compiled episode takes them (the walk task's: none);
    a drawn schedule's stretches drawn up to the end of these ``n`` ticks."""
    if not isinstance(task, CommandTask):
        z = np.zeros(1)
        return False, z, z, z, 0.0, z, (z, z, np.zeros((1, 2)), z, np.zeros((1, 3)), np.zeros((1, 3)),
                                        np.zeros(1, bool)), (1.0, 1.0, 0.0)
    s, f = tstate.commands, np.ascontiguousarray
    if isinstance(s, DrawnCommands):
        last = float(np.max(tstate.clock - tstate.t0)) + n * control_dt + CLOCK_TOLERANCE
        drawn = [s.stretch_commands(i) for i in range(int(np.floor(last / s.stretch)) + 2)]
        times, speeds, turns, stretch = (np.zeros(1), np.array([d[0] for d in drawn], float),
                                         np.array([d[1] for d in drawn], float), float(s.stretch))
    else:
        times, speeds, turns, stretch = f(s.times, float), f(s.speed, float), f(s.turning, float), 0.0
    o = task.options
    kept = (tstate.clock, tstate.up, tstate.last_facing, tstate.yaw_cmd, tstate.measured, tstate.sums,
            tstate.first)
    for a in kept:
        if not a.flags.c_contiguous:
            raise AssertionError("the command task's arrays are contiguous")
    return (True, times, speeds, turns, stretch, f(tstate.t0, float), kept,
            (o.sigma_speed ** 2, o.sigma_turning ** 2, float(o.smoothing)))
