"""From controller outputs to a body's actions: the explicit glue that lets any
controller drive any body.

=================  ================  ==============================================
controller output  body takes        action
=================  ================  ==============================================
unit  [0, 1]       PD target (rad)   low + o (high - low)   (Reil & Husbands Sect. II-B)
unit  [0, 1]       torque (N m)      low + o (high - low)   (low = -high: o = 0.5 is 0 N m)
centred [0, 1]     PD target (rad)   clip((o - 1/2)(high - low), low, high)  (o = 0.5 is 0 rad: standing)
centred_full       PD target (rad)   clip((o - 1/2) 2 max(|low|, |high|), low, high)  (standing at 0.5, whole range)
signed             torque (N m)      clip(y, low, high)     (e.g. Matsuoka p_e y_e - p_f y_f)
signed             PD target (rad)   mid + half tanh(y)     (saturating, centred on the range)
angle  (rad)       PD target (rad)   clip(y, low, high)     (e.g. SIMBICON's joint targets)
angle  (rad)       torque (N m)      not allowed            (ConfigError when the episode is built)
=================  ================  ==============================================
"""

from __future__ import annotations

import numpy as np


def _unit(low, high, o):
    return low + o * (high - low)


def _clip(low, high, y):
    return np.clip(y, low, high)


def _centred(low, high, o):
    return np.clip((o - 0.5) * (high - low), low, high)


def _centred_full(low, high, o):
    return np.clip((o - 0.5) * 2.0 * np.maximum(np.abs(low), np.abs(high)), low, high)


def _tanh(low, high, y):
    return 0.5 * (low + high) + 0.5 * (high - low) * np.tanh(y)


#: (controller output kind, body action kind) -> map; a pair not here is not allowed
MAPS = {
    ("unit", "position"): _unit,
    ("unit", "torque"): _unit,
    ("centred", "position"): _centred,
    ("centred_full", "position"): _centred_full,
    ("signed", "torque"): _clip,
    ("signed", "position"): _tanh,
    ("angle", "position"): _clip,
}


def to_action(output_kind: str, low: np.ndarray, high: np.ndarray, action_kind: str, outputs: np.ndarray) -> np.ndarray:
    """Map controller outputs ``(P, n)`` onto actions ``(P, n)`` within ``[low, high]``."""
    return MAPS[output_kind, action_kind](low, high, outputs)
