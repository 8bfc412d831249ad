"""From controller outputs to a body's actions: the explicit glue that lets any
controller drive any body.

=================  ================  ==============================================
controller output  body takes        action
=================  ================  ==============================================
unit  [0, 1]       PD target (rad)   low + o (high - low)   (Reil & Husbands Sect. II-B)
unit  [0, 1]       torque (N m)      low + o (high - low)   (low = -high: o = 0.5 is 0 N m)
signed             torque (N m)      clip(y, low, high)     (e.g. Matsuoka p_e y_e - p_f y_f)
signed             PD target (rad)   mid + half tanh(y)     (saturating, centred on the range)
angle  (rad)       PD target (rad)   clip(y, low, high)     (e.g. SIMBICON's joint targets)
angle  (rad)       torque (N m)      not allowed            (ConfigError when the episode is built)
=================  ================  ==============================================
"""

from __future__ import annotations

import numpy as np


def to_action(output_kind: str, low: np.ndarray, high: np.ndarray, action_kind: str, outputs: np.ndarray) -> np.ndarray:
    """Map controller outputs ``(P, n)`` onto actions ``(P, n)`` within ``[low, high]``."""
    if output_kind == "unit":
        return low + outputs * (high - low)
    if output_kind == "angle" and action_kind == "position":
        return np.clip(outputs, low, high)
    if output_kind == "signed":
        if action_kind == "torque":
            return np.clip(outputs, low, high)
        return 0.5 * (low + high) + 0.5 * (high - low) * np.tanh(outputs)
    raise ValueError(f"unknown controller output kind {output_kind!r}")
