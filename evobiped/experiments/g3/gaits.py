"""Gait analysis of limb oscillator outputs: period, phases, duty, gait label.

A channel is "up" (the foot off the ground: white in a Pearson diagram) while
its activity is above ``threshold`` (0.33, Fig. 4B).  Onsets are the upward
crossings, located by linear interpolation between samples.  Over a
steady-state window:

* period: median interval between channel 0's onsets (frequency = 1/period,
  both in the time units of ``t``);
* phase of channel k: (onset_k - onset_0) / period mod 1, the circular mean over
  the window's cycles (channel 0 = left fore has phase 0);
* duty: fraction of the window (whole cycles of channel 0) spent above
  threshold, per channel;
* label: the quadruped gait (channels LF, RF, LH, RH) whose phase template is
  within ``tol`` (circular distance, fraction of a cycle) of every phase:

  ======  ===========================  =====================================
  label   phases (RF, LH, RH)          meaning
  ======  ===========================  =====================================
  pronk   (0, 0, 0)                    all four together
  trot    (1/2, 1/2, 0)                diagonal pairs together
  pace    (1/2, 0, 1/2)                ipsilateral pairs together
  gallop  (0, 1/2, 1/2)                fore pair and hind pair together (Fig. 1)
  walk    (1/2, 3/4, 1/4)  lateral     four beats LF, RH, RF, LH
          (1/2, 1/4, 3/4)  diagonal    four beats LF, LH, RF, RH
  none    no steady oscillation, or no template fits
  ======  ===========================  =====================================

The transient is reported separately: the label of the first whole cycle and
the time at which every later cycle's phases stay within ``tol`` of the steady
phases.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from ...core.errors import ConfigError

THRESHOLD = 0.33

#: label -> phases of channels 1..3 relative to channel 0 (fractions of a cycle)
TEMPLATES = {
    "pronk": (0.0, 0.0, 0.0),
    "trot": (0.5, 0.5, 0.0),
    "pace": (0.5, 0.0, 0.5),
    "gallop": (0.0, 0.5, 0.5),
    "walk": (0.5, 0.75, 0.25),
    "walk(diagonal)": (0.5, 0.25, 0.75),
}


@dataclass
class Gait:
    """The steady gait of one batch row (times in the units of ``t``)."""

    label: str
    sequence: str  # "lateral"/"diagonal" for a walk, else ""
    oscillating: bool
    period: float
    frequency: float
    phases: list[float]  # (N,), channel 0 = 0
    duty: list[float]  # (N,) fraction of the cycle above threshold
    steps: list[float]  # (N,) onsets per cycle of channel 0 (1 = steps every cycle, 0 = never up)
    n_cycles: int
    transient_label: str  # label of the first whole cycle
    settle_time: float  # time after which every cycle matches the steady phases

    def as_dict(self) -> dict:
        return asdict(self)


def upward_crossings(t: np.ndarray, x: np.ndarray, threshold: float = THRESHOLD) -> np.ndarray:
    """Upward crossing times of one channel ``x`` ``(T,)`` through ``threshold``."""
    a = x > threshold
    i = np.flatnonzero(~a[:-1] & a[1:])
    frac = (threshold - x[i]) / (x[i + 1] - x[i])
    return t[i] + frac * (t[i + 1] - t[i])


def circ_dist(a, b) -> np.ndarray:
    """Circular distance between phases (fractions of a cycle), in [0, 0.5]."""
    d = np.mod(np.asarray(a) - np.asarray(b), 1.0)
    return np.minimum(d, 1.0 - d)


def circ_mean(p: np.ndarray, axis=None) -> np.ndarray:
    """Circular mean of phases (fractions of a cycle), in [0, 1)."""
    z = np.exp(2j * np.pi * np.asarray(p)).mean(axis=axis)
    return np.mod(np.angle(z) / (2 * np.pi), 1.0)


def classify(phases, tol: float = 0.1) -> tuple[str, str]:
    """(label, sequence) for phases ``(4,)`` of LF, RF, LH, RH (LF first)."""
    ph = np.asarray(phases, float)
    if ph.shape != (4,) or not np.all(np.isfinite(ph)):
        return "none", ""
    for name, tpl in TEMPLATES.items():
        if np.all(circ_dist(ph[1:], tpl) <= tol):
            if name.startswith("walk"):
                return "walk", "diagonal" if "diagonal" in name else "lateral"
            return name, ""
    return "none", ""


def cycle_phases(t: np.ndarray, x: np.ndarray, threshold: float = THRESHOLD) -> tuple[np.ndarray, np.ndarray]:
    """Per-cycle phases: (cycle start times ``(K,)``, phases ``(K, N)``).

    Cycle m runs from channel 0's onset m to onset m+1 (length L); channel k's
    phase is (onset - start) / L mod 1 for its onset within
    [start - 0.02 L, start + 0.98 L) (NaN when it has none there).
    """
    o0 = upward_crossings(t, x[:, 0], threshold)
    if o0.size < 2:
        return o0[:0], np.zeros((0, x.shape[1]))
    starts, lengths = o0[:-1], np.diff(o0)
    ph = np.full((starts.size, x.shape[1]), np.nan)
    ph[:, 0] = 0.0
    eps = 0.02  # an onset up to 2 % of a cycle before channel 0's still counts for this cycle
    for k in range(1, x.shape[1]):
        ok = upward_crossings(t, x[:, k], threshold)
        if ok.size == 0:
            continue
        j = np.searchsorted(ok, starts - eps * lengths)
        o = ok[np.minimum(j, ok.size - 1)]
        inside = (j < ok.size) & (o < starts + (1 - eps) * lengths)
        ph[:, k] = np.where(inside, np.mod((o - starts) / lengths, 1.0), np.nan)
    return starts, ph


def analyse_gait(t: np.ndarray, x: np.ndarray, *, t_start: float | None = None, threshold: float = THRESHOLD,
                 tol: float = 0.1) -> Gait:
    """Analyse one run: ``t`` ``(T,)``, ``x`` ``(T, N)``; steady window ``t >= t_start``.

    t_start defaults to the second half of the run.
    """
    t = np.asarray(t, float)
    x = np.asarray(x, float)
    if x.ndim != 2 or x.shape[0] != t.size or x.shape[1] < 1:
        raise ConfigError("gait analysis needs x of shape (T, N) with N >= 1 channels")
    if t_start is None:
        t_start = 0.5 * (t[0] + t[-1])
    starts, ph = cycle_phases(t, x, threshold)
    o0 = upward_crossings(t, x[:, 0], threshold)
    w = o0[o0 >= t_start]
    N = x.shape[1]
    nan = [float("nan")] * N
    first = classify(ph[0])[0] if len(ph) and N == 4 else "none"
    if w.size < 3:
        return Gait("none", "", False, float("nan"), 0.0, nan, nan, nan, 0, first, float("nan"))
    period = float(np.median(np.diff(w)))
    sel = (starts >= w[0] - 1e-9) & (starts < w[-1] - 1e-9)
    wp = ph[sel]
    if np.isnan(wp).any():  # some channel skips cycles: not a steady gait
        phases = [float("nan")] * N
    else:
        phases = [float(v) for v in np.mod(np.round(circ_mean(wp, axis=0), 6), 1.0)]
    a, b = w[0], w[-1]
    m = (t >= a) & (t < b)
    duty = [float(v) for v in (x[m] > threshold).mean(axis=0)]
    steps = [float(np.sum((o >= a - 0.02 * period) & (o < b - 0.02 * period)) / (w.size - 1))
             for o in (upward_crossings(t, x[:, k], threshold) for k in range(N))]
    label, seq = classify(phases, tol) if N == 4 else ("none", "")
    # settling: the first time after which every cycle stays within tol of the steady phases
    if np.all(np.isfinite(phases)):
        bad = np.flatnonzero(np.any(~(circ_dist(ph, phases) <= tol), axis=1))
        settle = float(starts[bad[-1]
                              + 1]) if bad.size and bad[-1] + 1 < starts.size else (float(starts[
                                  0]) if starts.size else float("nan"))
    else:
        settle = float("nan")
    return Gait(label, seq, True, period, 1.0 / period, phases, duty, steps, int(w.size - 1), first, settle)

