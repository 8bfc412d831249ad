"""The statistics of a comparison of run configurations: pure functions of numbers, nothing simulated.

Each configuration gives one value per run (seed): a success (0 or 1) and a measure.  Runs are the
independent units, so every interval and test here is over runs, never over the presentations of one run:

* :func:`wilson_ci`: the Wilson score interval of a success rate k/n (95 %; SciPy's
  ``binomtest(k, n).proportion_ci(method="wilson")``), which stays inside [0, 1] and is not empty at 0 or n;
* :func:`median_iqr`: the median and the interquartile range (25th and 75th percentiles, linear interpolation);
* :func:`vargha_delaney`: Vargha and Delaney's A, the probability that a run of the first configuration
  measures more than one of the second, ties counting half (0.5: no difference; 0.56, 0.64, 0.71: the
  conventional small, medium and large effects);
* :func:`mann_whitney_p`: the two-sided Mann-Whitney U test's p, exact (the permutation distribution of the rank
  sum, ties included) for the sample sizes of a comparison over seeds; 1 where every value of both samples is the
  same (no evidence of a difference).
"""

from __future__ import annotations

import math

import numpy as np


def wilson_ci(successes: int, n: int, confidence: float = 0.95) -> tuple[float, float]:
    """The Wilson score interval ``(low, high)`` of ``successes`` of ``n``; ``(nan, nan)`` for ``n`` = 0."""
    from scipy.stats import binomtest

    if n <= 0:
        return (math.nan, math.nan)
    if not 0 <= successes <= n:
        raise ValueError(f"successes {successes} outside 0..{n}")
    ci = binomtest(int(successes), int(n)).proportion_ci(confidence_level=confidence, method="wilson")
    return (float(ci.low), float(ci.high))


def median_iqr(values) -> tuple[float, float, float]:
    """``(median, 25th percentile, 75th percentile)`` of ``values``; NaNs for none."""
    v = np.asarray(values, float)
    if v.size == 0:
        return (math.nan, math.nan, math.nan)
    q25, med, q75 = np.percentile(v, [25, 50, 75])
    return (float(med), float(q25), float(q75))


def vargha_delaney(a, b) -> float:
    """Vargha and Delaney's A of sample ``a`` over sample ``b``: P(X > Y) + P(X = Y) / 2 over every pair."""
    x, y = np.asarray(a, float)[:, None], np.asarray(b, float)[None, :]
    if x.size == 0 or y.size == 0:
        return math.nan
    return float(((x > y).sum() + 0.5 * (x == y).sum()) / (x.size * y.size))


#: pooled samples up to this size get the exact permutation p (:func:`mann_whitney_p`)
EXACT_MAX = 400


def mann_whitney_p(a, b) -> float:
    """The two-sided Mann-Whitney U test's p of samples ``a`` and ``b`` (NaN when one is empty): exact, over every
    split of the pooled sample into groups of their sizes (ties by midranks: the permutation distribution of the
    rank sum, counted by dynamic programming), for pooled samples of up to :data:`EXACT_MAX`; beyond, SciPy's normal
    approximation with the tie correction."""
    from scipy.stats import mannwhitneyu, rankdata

    x, y = np.asarray(a, float), np.asarray(b, float)
    if x.size == 0 or y.size == 0:
        return math.nan
    if np.unique(np.concatenate([x, y])).size == 1:
        return 1.0
    if x.size + y.size > EXACT_MAX:
        return float(mannwhitneyu(x, y, alternative="two-sided").pvalue)
    doubled = np.rint(2 * rankdata(np.concatenate([x, y]))).astype(int)  # midranks times 2: integers
    m, total = x.size, int(doubled.sum())
    counts = np.zeros((m + 1, total + 1))  # counts[k, s]: subsets of k values whose doubled ranks sum to s
    counts[0, 0] = 1.0
    for r in doubled:
        counts[1:, r:] += counts[:-1, :total + 1 - r].copy()
    centre = m * (x.size + y.size + 1)  # twice the rank sum's mean
    observed = abs(2 * int(doubled[:m].sum()) - 2 * centre) / 2
    deviation = np.abs(np.arange(total + 1) - centre)
    tail = counts[m, deviation >= observed - 1e-9].sum()
    return float(min(1.0, tail / counts[m].sum()))
