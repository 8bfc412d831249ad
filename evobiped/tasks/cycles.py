"""Counting oscillation cycles of motor neurons (the walk task's cyclic-activity criterion)."""

from __future__ import annotations

import numpy as np


def count_cycles(series: np.ndarray, lengths: np.ndarray, band: float) -> np.ndarray:
    """Hysteresis cycles per row and channel.

    ``series`` (T, P, n), ``lengths`` (P,) valid ticks per row -> counts (P, n).
    """
    T, P, n = series.shape
    valid = np.arange(T)[:, None] < lengths[None, :]  # (T, P)
    w = valid[:, :, None]
    mean = (series * w).sum(0) / np.maximum(lengths, 1)[:, None]
    low, high = mean - band, mean + band
    below = np.zeros((P, n), bool)
    count = np.zeros((P, n), int)
    for t in range(T):
        x, ok = series[t], w[t]
        rise = below & (x > high) & ok
        count += rise
        below = np.where(ok & (x < low), True, np.where(rise, False, below))
    return count
