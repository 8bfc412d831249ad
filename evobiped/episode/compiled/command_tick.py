"""The command task compiled (:mod:`evobiped.tasks.command`): the command a walker follows at a time, its senses'
angle wrap, and one walker's tick of the task's bookkeeping (measured speeds, tracking integrals, the commanded
facing), every expression in NumPy's order, every transcendental NumPy's own loop."""

from __future__ import annotations

import math

import numpy as np

from ...core.kernel import jit
from ...core.ufunc_calls import apply_loop, apply_loop2
from ...tasks.command import HEADING_LEASH
from ...tasks.command_schedule import CLOCK_TOLERANCE


@jit
def command_at(times, speeds, turns, stretch, t):
    """The command (speed m/s, turning rad/s) of a tick beginning at ``t`` s from the episode start: a piecewise
    schedule's (``stretch`` 0: the last ``times[i] <= t``, as ``searchsorted``) or a drawn one's (stretches of
    ``stretch`` s, value i of stretch i)."""
    x = t + CLOCK_TOLERANCE
    if stretch > 0:
        i = int(math.floor(x / stretch))
    else:
        i = 0
        while i < times.shape[0] and times[i] <= x:
            i += 1
        i = i - 1 if i > 0 else 0
    return speeds[i], turns[i]


@jit
def wrap(remainder, a, scratch):
    """An angle in (-pi, pi] (the command task's ``_wrap``), ``remainder`` the address of NumPy's ``np.mod`` loop."""
    scratch[0], scratch[1] = np.pi - a, 2 * np.pi
    apply_loop2(remainder, scratch[:1], scratch[1:2], scratch[2:3])
    return np.pi - scratch[2]


@jit
def _exp(exp, x, scratch):
    scratch[0] = x
    apply_loop(exp, scratch[:1], scratch[:1])
    return scratch[0]


@jit
def _atan2(arctan2, y, x, scratch):
    scratch[0], scratch[1] = y, x
    apply_loop2(arctan2, scratch[:1], scratch[1:2], scratch[2:3])
    return scratch[2]


@jit
def heading_error(funcs, fx, fy, yaw_cmd, scratch):
    """The facing ``(fx, fy)``'s angle from the commanded facing ``yaw_cmd`` (rad)."""
    return wrap(funcs[4], _atan2(funcs[2], fy, fx, scratch) - yaw_cmd, scratch)


@jit
def tick(funcs, p, now_time, fx, fy, x, y, both, position, state, options, v_cmd, w_cmd, scratch):
    """:meth:`CommandTask.on_tick <evobiped.tasks.command.CommandTask.on_tick>` of walker ``p`` after its tick: its
    time ``now_time`` s, its facing ``(fx, fy)`` and planar position ``(x, y)`` m now, ``both`` feet down,
    ``position`` ``(P, 2)`` its position before the tick; ``state`` the task's arrays (clock, up, last_facing,
    yaw_cmd, measured, sums, first), ``options`` (sigma_speed^2, sigma_turning^2, smoothing s); the command
    ``(v_cmd, w_cmd)`` the tick was scored against; ``funcs`` NumPy's exp, arcsin, arctan2, hypot and mod."""
    exp, arctan2 = funcs[0], funcs[2]
    clock, up, last_facing, yaw_cmd, measured, sums, first = state
    sv2, sw2, smoothing = options
    d = now_time - clock[p]
    dt = d if d > 1e-12 else (d if d != d else 1e-12)
    f0x, f0y = last_facing[p, 0], last_facing[p, 1]
    sx, sy = x - position[p, 0], y - position[p, 1]
    turn = _atan2(arctan2, f0x * fy - f0y * fx, f0x * fx + f0y * fy, scratch)
    v, speed, w = (sx * fx + sy * fy) / dt, np.sqrt(sx * sx + sy * sy) / dt, turn / dt
    if smoothing > 0:  # a first-order low-pass, started at the first tick's reading
        a = 1.0 if first[p] else 1.0 - _exp(exp, -dt / smoothing, scratch)
        v = measured[p, 0] + a * (v - measured[p, 0])
        speed = measured[p, 1] + a * (speed - measured[p, 1])
        w = measured[p, 2] + a * (w - measured[p, 2])
    measured[p, 0], measured[p, 1], measured[p, 2] = v, speed, w
    first[p] = False
    still = ((1.0 if (v_cmd == 0 and both) else 0.0) * _exp(exp, -(speed * speed) / sv2, scratch)
             * _exp(exp, -(w * w) / sw2, scratch))
    dv, dw = v - v_cmd, w - w_cmd
    sums[p, 0] += dt * _exp(exp, -(dv * dv) / sv2, scratch)
    sums[p, 1] += dt * _exp(exp, -(dw * dw) / sw2, scratch)
    sums[p, 2] += dt * still
    up[p] += dt
    yaw = _atan2(arctan2, fy, fx, scratch)
    cmd = yaw_cmd[p] + w_cmd * dt
    e = wrap(funcs[4], yaw - cmd, scratch)
    e = -HEADING_LEASH if e < -HEADING_LEASH else (HEADING_LEASH if e > HEADING_LEASH else e)
    yaw_cmd[p] = yaw - e
    last_facing[p, 0], last_facing[p, 1] = fx, fy
    clock[p] = now_time
