"""Steering through commands: a commanded walker walks to a sound source when its commands come from its ears.

The rule.  From the steer task's ear signal s = (a - b) / (a + b) (+ when the source is on the left) and its loudness
L = min(1, (a + b) / 2 * 1 m^2) ~ min(1, 1 / D^2) at distance D (m), the commands are

    turning = clip(gain * s, -turning_max, turning_max)                              (rad/s, + left)
    speed   = speed_max * clip((L_stop - L) / (L_stop - L_slow), 0, 1)                (m/s)

with L_slow = 1 / slow_from^2 (full speed farther than ``slow_from`` m) and L_stop = min(1, 1 / reach^2): the
walker turns towards the side it hears louder, more as the source gets nearer (s grows as 1 / D), slows down
linearly in loudness from ``slow_from`` m and stops (speed 0) inside the reach radius.  The loudness is 1 within
1 m, so a reach under 1 m stops it at 1 m.  A source straight behind gives s = 0: the rule walks away from it until
the ears tell the sides apart (a source behind and slightly to one side turns it round).
"""

from __future__ import annotations

import numpy as np

from ..core.errors import ConfigError


def steering_command(sound, loudness, *, gain: float = 4.0, turning_max: float = 0.35, speed_max: float = 0.6,
                     slow_from: float = 3.0, reach: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """The commands (speed m/s, turning rad/s), arrays like ``sound``, from the ear signal ``sound`` (s in [-1, 1])
    and ``loudness`` (L in [0, 1]); ``gain`` rad/s per unit of s, ``slow_from`` and ``reach`` m (module docstring).
    ConfigError for a reach not inside ``slow_from`` or a non-positive gain, speed or turning bound."""
    if not (gain > 0 and turning_max > 0 and speed_max > 0 and 0 < reach < slow_from):
        raise ConfigError(f"steering_command: needs gain, turning_max, speed_max > 0 and 0 < reach < slow_from, got "
                          f"gain {gain:g}, turning_max {turning_max:g}, speed_max {speed_max:g}, reach {reach:g}, "
                          f"slow_from {slow_from:g}")
    s, L = np.asarray(sound, float), np.clip(np.asarray(loudness, float), 0.0, 1.0)
    slow, stop = 1.0 / slow_from ** 2, min(1.0, 1.0 / reach ** 2)
    speed = speed_max * np.clip((stop - L) / (stop - slow), 0.0, 1.0)
    return speed, np.clip(gain * s, -turning_max, turning_max)
