"""What the compiled episode reads of one walker's ``MjData`` each tick: the controller's senses, as the Reil body and
the walk task compute them, and the gait lab's foot samples, as the body takes them; every expression in NumPy's
order, every transcendental NumPy's own loop."""

from __future__ import annotations

import numpy as np

from ...core.kernel import jit
from ...core.ufunc_calls import apply_loop, apply_loop2, call_scalar2
from ...physics import gait
from .command_tick import heading_error as command_heading_error

#: the senses the compiled tick reads, by code (the Reil body's groups, the walk or command task's heading, the command
#: task's commands, the steer task's ears)
SENSES = ("joint_angles", "joint_velocities", "foot_contact", "pelvis_tilt", "pelvis_tilt_rate", "com_from_feet",
          "com_velocity", "stance_leg", "since_touchdown", "stance_side", "heading_error", "command_speed",
          "command_turning", "command_stop", "sound", "loudness")


@jit
def _frame_dot(fx, fy, a, b):
    """The heading frame's rows (forward (fx, fy), left (-fy, fx)) times (a, b), as the body's einsum adds them."""
    return fx * a + fy * b, -fy * a + fx * b


@jit
def facing(xmat, pelvis):
    """The direction the walker faces on the ground ``(fx, fy)`` (:meth:`ReilBiped.heading`)."""
    fx, fy = xmat[pelvis, 0], xmat[pelvis, 3]
    n = np.sqrt(fx * fx + fy * fy)
    n = n if n > 1e-12 else 1e-12
    return fx / n, fy / n


@jit
def _intensity(dx, dy):
    """I = 1 / |e - q|^2 (1/m^2) of an ear ``(dx, dy)`` m from its source (:func:`evobiped.tasks.sound.intensity`)."""
    d = dx * dx + dy * dy
    return 1.0 / (d if d > 1e-12 else (d if d != d else 1e-12))


@jit
def senses(codes, widths, x, funcs, q, v, xmat, com, site, cvel, xipos, sens, time, body_ids, qadr, dadr, share,
            stance, touchdown, facing0, command, hearing, scratch):
    """The controller's inputs ``x`` ``(k,)`` of one walker now, in input order (``codes`` into :data:`SENSES`), as
    :meth:`ReilBiped.sensors <evobiped.bodies.reil.ReilBiped.sensors>` and the walk or command task compute them
    (``command``: whether the task is the command task, the speed m/s and turning rate rad/s it asks for now, and its
    commanded facing rad; ``hearing``: the steer task's source ``(2,)`` m, its ears' site ids and its sound limit)."""
    pelvis, touch0, touch1, site0, site1 = body_ids[0], body_ids[1], body_ids[2], body_ids[3], body_ids[4]
    arcsin, arctan2 = funcs[1], funcs[2]
    fx, fy = facing(xmat, pelvis)
    at = 0
    for g in range(codes.shape[0]):
        c = codes[g]
        if c == 0:
            for i in range(6):
                x[at + i] = q[qadr[i]]
        elif c == 1:
            for i in range(6):
                x[at + i] = v[dadr[i]]
        elif c == 2:
            x[at] = 1.0 if sens[touch0] > 0 else 0.0
            x[at + 1] = 1.0 if sens[touch1] > 0 else 0.0
        elif c == 3:
            for i in range(2):
                e = xmat[pelvis, 6 + i]
                scratch[i] = -1.0 if e < -1.0 else (1.0 if e > 1.0 else e)
            apply_loop(arcsin, scratch[:2], scratch[:2])
            x[at], x[at + 1] = scratch[0] * -1.0, scratch[1] * 1.0
        elif c == 4:
            r0, r1 = _frame_dot(fx, fy, cvel[pelvis, 0], cvel[pelvis, 1])
            x[at], x[at + 1] = r1, r0
        elif c == 5:
            for f in range(2):
                s = site0 if f == 0 else site1
                x[at + 2 * f], x[at + 2 * f + 1] = _frame_dot(fx, fy, com[pelvis, 0] - site[s, 0],
                                                              com[pelvis, 1] - site[s, 1])
        elif c == 6:
            vx, vy = 0.0, 0.0
            for b in range(1, cvel.shape[0]):
                w0, w1, w2 = cvel[b, 0], cvel[b, 1], cvel[b, 2]
                ra, rb, rc = xipos[b, 0] - com[pelvis, 0], xipos[b, 1] - com[pelvis, 1], xipos[b, 2] - com[pelvis, 2]
                vx += share[b - 1] * (cvel[b, 3] + (w1 * rc - w2 * rb))
                vy += share[b - 1] * (cvel[b, 4] + (w2 * ra - w0 * rc))
            x[at], x[at + 1] = _frame_dot(fx, fy, vx, vy)
        elif c == 7 or c == 9:
            x[at] = 1.0 if stance == 0 else -1.0
        elif c == 8:
            s = time - touchdown
            x[at] = s if s < gait.CAP else gait.CAP  # np.minimum: NaN stays NaN
            if s != s:
                x[at] = s
        elif c == 10 and command[0]:  # the command task's heading_error: from the commanded facing
            x[at] = command_heading_error(funcs, fx, fy, command[3], scratch)
        elif c == 11:
            x[at] = command[1]
        elif c == 12:
            x[at] = command[2]
        elif c == 13:
            x[at] = 1.0 if command[1] == 0 else 0.0
        elif c == 14 or c == 15:  # the steer task's ears
            source, ears, limit = hearing
            a = _intensity(site[ears[0], 0] - source[0], site[ears[0], 1] - source[1])
            b = _intensity(site[ears[1], 0] - source[0], site[ears[1], 1] - source[1])
            if c == 14:
                s = (a - b) / (a + b)
                x[at] = s if limit >= 1 else (-limit if s < -limit else (limit if s > limit else s))
            else:
                s = (a + b) / 2
                x[at] = s if s < 1.0 else (1.0 if s == s else s)  # np.minimum: NaN stays NaN
        else:  # the walk task's heading_error: the facing's angle from the initial facing
            scratch[0] = facing0[0] * fy - facing0[1] * fx
            scratch[1] = facing0[0] * fx + facing0[1] * fy
            apply_loop2(arctan2, scratch[:1], scratch[1:2], scratch[2:3])
            x[at] = scratch[2]
        at += widths[g]


@jit
def foot_sample(funcs, s, p, q, gxpos, cvel, com, force, avel, body_ids, radius, knees,
                 contact, slip, height, knee, power, torque):
    """The gait lab's sample ``s`` of walker ``p`` now, as :meth:`ReilBiped.feet <evobiped.bodies.reil.ReilBiped.feet>`
    takes it."""
    pelvis = body_ids[0]
    for f in range(2):
        g, b = body_ids[5 + f], body_ids[7 + f]
        h = gxpos[g, 2] - radius[f]
        r0, r1, r2 = gxpos[g, 0] - com[pelvis, 0], gxpos[g, 1] - com[pelvis, 1], gxpos[g, 2] - com[pelvis, 2]
        r2 -= radius[f]
        w0, w1, w2 = cvel[b, 0], cvel[b, 1], cvel[b, 2]
        vx = cvel[b, 3] + w1 * r2 - w2 * r1
        vy = cvel[b, 4] + w2 * r0 - w0 * r2
        height[s, p, f] = h
        contact[s, p, f] = h < 0.0
        slip[s, p, f] = call_scalar2(funcs[3], vx, vy)
        knee[s, p, f] = q[knees[f]]
    for j in range(force.shape[0]):
        power[s, p, j] = force[j] * avel[j]
        torque[s, p, j] = force[j]
