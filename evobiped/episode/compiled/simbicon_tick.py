"""The SIMBICON-style controller's step compiled (:meth:`Simbicon.step <evobiped.controllers.simbicon.Simbicon.step>`)
for one walker: its two states per step, its balance feedback and its hearing, every expression in NumPy's order."""

from __future__ import annotations

import numpy as np

from ...core.kernel import jit

#: the genes in the order :func:`simbicon_step` reads them (hearing's last: 0 for a deaf controller)
GENES = ("step_time", "hip_early", "hip_late", "knee_early", "knee_late", "stance_knee", "cd", "cv", "roll_offset",
         "cd_lateral", "cv_lateral", "pelvis_gain", "pelvis_damping", "sound_forward", "sound_lateral")
#: the inputs it reads, by name: their offsets in the input vector are handed to :func:`simbicon_step` in this order
INPUTS = ("foot_contact", "pelvis_tilt", "pelvis_tilt_rate", "com_from_feet", "com_velocity", "joint_angles", "sound")


def genes(params: dict, P: int) -> np.ndarray:
    """The genes ``(P, len(GENES))`` of decoded parameters ``params`` (name -> ``(P, 1)``)."""
    return np.ascontiguousarray(np.column_stack([params[k][:, 0] if k in params else np.zeros(P) for k in GENES]),
                                float)


@jit
def simbicon_step(x, at, g, stance, t, hears, sound_limit, pitch_cols, roll_cols, knee_cols, dt, target):
    """One control period of walker ``p``: inputs ``x`` ``(k,)`` (``at`` the offsets of :data:`INPUTS`), genes ``g``
    ``(len(GENES),)``, its stance leg (0 left, 1 right) and time in the swing (s); writes the PD targets ``target``
    ``(n_act,)`` (rad) and returns the new ``(stance, t)``.  ``*_cols``: the actuator column of each leg's joint."""
    step_time = g[0]
    t = t + dt
    swing = 1 - stance
    landed = x[at[0] + swing] > 0
    if (t > step_time and landed) or t > 3 * step_time:
        stance, t = swing, 0.0
    swing = 1 - stance
    early = t < step_time
    out_sw = 1.0 if swing == 0 else -1.0  # + left: the swing side, outward
    pitch, roll = x[at[1]], x[at[1] + 1]
    pitch_rate, roll_rate = x[at[2]], x[at[2] + 1]
    d0, d1 = x[at[3] + 2 * stance], x[at[3] + 2 * stance + 1]
    v0, v1 = x[at[4]], x[at[4] + 1]
    fwd = (g[1] if early else g[2]) + g[6] * d0 + g[7] * v0
    out = g[8] + out_sw * (g[9] * d1 + g[10] * v1)
    if hears:
        sound = x[at[6]]
        if sound_limit < 1.0:
            sound = -sound_limit if sound < -sound_limit else (sound_limit if sound > sound_limit else sound)
        fwd = fwd - out_sw * g[13] * sound
        out = out + out_sw * g[14] * sound
    target[pitch_cols[swing]] = fwd + pitch
    target[roll_cols[swing]] = out - out_sw * roll
    target[knee_cols[swing]] = g[3] if early else g[4]
    target[knee_cols[stance]] = g[5]
    turn_pitch = g[11] * pitch + g[12] * pitch_rate
    turn_roll = g[11] * roll + g[12] * roll_rate
    target[pitch_cols[stance]] = x[at[5] + pitch_cols[stance]] - turn_pitch
    target[roll_cols[stance]] = x[at[5] + roll_cols[stance]] - out_sw * turn_roll
    return stance, t
