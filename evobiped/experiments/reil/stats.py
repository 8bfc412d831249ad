"""Statistics over many evolutionary runs: success rates, intervals, distributions."""

from __future__ import annotations

import math

import numpy as np


def wilson_interval(successes: int, n: int, z: float = 1.959963984540054) -> tuple[float, float]:
    """Wilson score interval for a binomial proportion (95 % by default).

    Unlike the normal approximation it stays inside [0, 1] and is not empty
    for 0 or n successes (what a 10 % success rate over few runs needs).
    """
    if n <= 0:
        return (math.nan, math.nan)
    if not 0 <= successes <= n:
        raise ValueError(f"successes {successes} outside 0..{n}")
    p = successes / n
    z2 = z * z
    centre = (p + z2 / (2 * n)) / (1 + z2 / n)
    half = z / (1 + z2 / n) * math.sqrt(p * (1 - p) / n + z2 / (4 * n * n))
    return (max(0.0, centre - half), min(1.0, centre + half))


def mean_std(values) -> tuple[float, float]:
    """Mean and sample standard deviation (n − 1); NaN where undefined (σ needs 2 values)."""
    v = np.asarray(values, float)
    if v.size == 0:
        return (math.nan, math.nan)
    return (float(v.mean()), float(v.std(ddof=1)) if v.size > 1 else math.nan)


def histogram_edges(values, width: float = 1.0) -> np.ndarray:
    """Bin edges of ``width`` from 0 up to the first multiple of ``width`` above every value.

    Fig. 5 of Reil & Husbands bins distances in metres; fixed edges let
    conditions be compared bin by bin.
    """
    v = np.asarray(values, float)
    top = max(1, math.floor(v.max() / width) + 1) if v.size else 1
    return np.arange(top + 1) * width
