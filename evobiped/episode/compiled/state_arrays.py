"""The tasks' and the controllers' state as the compiled episode (:mod:`.whole`) takes it: the command task's schedule
and arrays, the steer task's sources and ears, the CTRNN's and the SIMBICON-style controller's genes and state; for
the others, arrays of the same types that it does not read; and the gait lab's samples handed back to the task's
meter."""

from __future__ import annotations

import numpy as np

from ...controllers.simbicon import Simbicon
from ...tasks.command import CommandTask
from ...tasks.command_schedule import CLOCK_TOLERANCE, DrawnCommands
from ...tasks.steer import SteerTask
from . import simbicon_tick


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


def controller(ctrl, state, P: int, simbicon_at: np.ndarray) -> tuple[tuple, tuple]:
    """The controller's genes and state as the compiled episode takes them: the CTRNN's tuple and the SIMBICON-style
    controller's (``simbicon_at``: the offsets of its inputs), the one not stepped of the same types."""
    params, f = state.params, np.ascontiguousarray
    if isinstance(ctrl, Simbicon):
        z = np.zeros((P, 0))
        ctrnn = (z, z, np.zeros((P, 0, 0)), np.zeros((P, 0, 0)), z, np.zeros(P, np.int64), 0.0, False, False,
                 np.zeros((0, 0)), np.zeros((0, 0, 0)), 0)
        sc = state.controller
        simb = (True, simbicon_tick.genes(params, P), simbicon_at, f(sc["stance"], np.int64),
                f(sc["t"], float), f(sc["out"], float), ctrl.hears, ctrl.sound_limit, ctrl._pitch.astype(np.int64),
                ctrl._roll.astype(np.int64), ctrl._knee.astype(np.int64), ctrl.dt)
    else:
        c, D = (f(params["c"]), f(params["D"])) if ctrl.direct else (np.zeros((0, 0)), np.zeros((0, 0, 0)))
        substeps = f(params["substeps"], np.int64) if ctrl.exponential else np.zeros(P, np.int64)
        ctrnn = (f(state.controller, float), f(params["alpha"]), f(params["W"]), f(params["V"]), f(params["tau"]),
                 substeps, ctrl.dt, ctrl.exponential, ctrl.outputs_after, c, D, ctrl.n_outputs)
        i2 = np.zeros(2, np.int64)
        simb = (False, np.zeros((P, 1)), np.zeros(7, np.int64), np.zeros(P, np.int64), np.zeros(P),
                np.zeros((P, 1)), False, 1.0, i2, i2, i2, 0.0)
    return ctrnn, simb


def hand_to_meter(meter, samples, T: int, per_tick: int, first_time: float) -> None:
    """The gait lab's samples of the call's ``T`` samples (``per_tick`` a tick) appended to ``meter`` as its own
    :meth:`~evobiped.physics.gait_lab.GaitMeter.tick` would have kept them."""
    contact, slip, height, knee, power, torque, ticked, _ = samples
    if not np.isfinite(meter.dt) and np.isfinite(first_time):
        meter.dt = (float(first_time) - meter._start_time) / per_tick
    for t in range(0, T, per_tick):
        mask = ticked[t].copy()
        meter.ticked.extend([mask] * per_tick)
    fields = {"contact": contact, "slip": slip, "height": height, "knee": knee, "power": power, "torque": torque}
    for name, series in meter.series.items():
        series.extend(fields[name][:T])
    meter._measured = None
