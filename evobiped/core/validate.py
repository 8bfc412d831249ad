"""One check for every number a config or a file gives: its type, finiteness and range.

A bool is not a number here (TOML ``true`` is no episode length), NaN and
infinities are refused, and the message names the setting and the value.
"""

from __future__ import annotations

import math
from typing import Any

from .errors import ConfigError


def number(value: Any, name: str, *, low: float | None = None, high: float | None = None, above: float | None = None,
           below: float | None = None, integer: bool = False, unit: str = "") -> float | int:
    """``value`` if it is a finite number (a whole one with ``integer``) with ``low <= value <= high``,
    ``value > above`` and ``value < below``; otherwise a ConfigError naming ``name`` (e.g. "episode.seconds:") and the
    value."""
    kind = "a whole number" if integer else "a number"
    ok = isinstance(value, int) if integer else isinstance(value, (int, float))
    if isinstance(value, bool) or not ok:
        raise ConfigError(f"{name} must be {kind}, got {value!r}")
    if not math.isfinite(value):
        raise ConfigError(f"{name} must be finite, got {value!r}")
    u = f" {unit}" if unit else ""
    if above is not None and not value > above:
        raise ConfigError(f"{name} must be > {above:g}{u}, got {value!r}")
    if below is not None and not value < below:
        raise ConfigError(f"{name} must be < {below:g}{u}, got {value!r}")
    if (low is not None and value < low) or (high is not None and value > high):
        span = (f"in [{low:g}, {high:g}]" if low is not None and high is not None else f">= {low:g}" if low is not None
                else f"<= {high:g}")
        raise ConfigError(f"{name} must be {span}{u}, got {value!r}")
    return value
