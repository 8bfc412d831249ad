"""Stride metrics of a biped from its foot-contact sequence (Taga et al. 1991, Fig. 11).

Input: sample times ``t`` (T,) in s, contact flags ``contact`` (T, 2) for
(leg 0, leg 1), the feet's horizontal positions ``foot_x`` (T, 2) in m and the
hip's height ``hip_z`` (T,).  Contact phases shorter than ``min_phase`` (s)
and gaps shorter than it are first removed (touchdown bounces of a stiff
ground).  Within the window [t_start, t_end]:

* strides: successive touchdowns of leg 0 (contact onsets); stride cycle
  duration = median interval, stride length = median distance between the
  touchdown positions (the paper's "distance between successive contact
  points of the same leg"), speed = length / duration;
* double support: both feet down; flight: neither; each as a fraction of the
  window and counted per stride;
* gait: "walk" if every stride has double support and none has flight, "run"
  if every stride has flight and none has double support, else "mixed";
  "none" with fewer than two strides.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np


@dataclass(frozen=True)
class StrideMetrics:
    gait: str
    strides: int
    stride_length: float  # m
    cycle_duration: float  # s
    speed: float  # m/s, stride length / cycle duration
    double_support: float  # fraction of the window
    flight: float  # fraction of the window
    strides_with_double_support: int
    strides_with_flight: int
    hip_min: float  # m
    hip_max: float  # m

    def as_dict(self) -> dict:
        return asdict(self)


def clean(t: np.ndarray, on: np.ndarray, min_phase: float) -> np.ndarray:
    """Remove gaps, then contact phases, shorter than ``min_phase`` s from a bool series (T,)."""
    on = np.asarray(on, bool).copy()
    for value in (False, True):  # fill short gaps first, then drop short contacts
        edges = np.flatnonzero(np.diff(on.astype(int))) + 1
        bounds = np.concatenate([[0], edges, [len(on)]])
        for a, b in zip(bounds[:-1], bounds[1:]):
            inner = a > 0 and b < len(on)
            if on[a] == value and inner and t[b - 1] - t[a] < min_phase:
                on[a:b] = not value
    return on


def contact_onsets(on: np.ndarray) -> np.ndarray:
    """Indices where a bool series (T,) switches on."""
    on = np.asarray(on, bool)
    return np.flatnonzero(on[1:] & ~on[:-1]) + 1


def analyse_strides(
    t: np.ndarray,
    contact: np.ndarray,
    foot_x: np.ndarray,
    hip_z: np.ndarray,
    *,
    t_start: float | None = None,
    t_end: float | None = None,
    min_phase: float = 0.01,
) -> StrideMetrics:
    """Metrics of the window [t_start, t_end] (default: the whole series)."""
    t = np.asarray(t, float)
    c = np.stack([clean(t, contact[:, k], min_phase) for k in range(2)], 1)
    t0 = t[0] if t_start is None else t_start
    t1 = t[-1] if t_end is None else t_end
    win = (t >= t0) & (t <= t1)
    both = c[:, 0] & c[:, 1]
    none = ~c[:, 0] & ~c[:, 1]
    td = contact_onsets(c[:, 0])
    td = td[win[td]]
    n = len(td) - 1
    hz = np.asarray(hip_z)[win]
    hip_min, hip_max = (float(hz.min()), float(hz.max())) if hz.size else (np.nan, np.nan)
    ds_frac = float(both[win].mean()) if win.any() else np.nan
    fl_frac = float(none[win].mean()) if win.any() else np.nan
    if n < 1:
        return StrideMetrics("none", 0, np.nan, np.nan, np.nan, ds_frac, fl_frac, 0, 0, hip_min, hip_max)
    durations = np.diff(t[td])
    lengths = np.abs(np.diff(np.asarray(foot_x)[td, 0]))
    with_ds = sum(bool(both[a:b].any()) for a, b in zip(td[:-1], td[1:]))
    with_fl = sum(bool(none[a:b].any()) for a, b in zip(td[:-1], td[1:]))
    if n < 2:
        gait = "none"
    elif with_ds == n and with_fl == 0:
        gait = "walk"
    elif with_fl == n and with_ds == 0:
        gait = "run"
    else:
        gait = "mixed"
    L, D = float(np.median(lengths)), float(np.median(durations))
    return StrideMetrics(gait, n, L, D, L / D, ds_frac, fl_frac, with_ds, with_fl, hip_min, hip_max)


def per_stride(t: np.ndarray, contact: np.ndarray, foot_x: np.ndarray, *,
               min_phase: float = 0.01) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every stride of leg 0: (start times (n,), lengths (n,) m, durations (n,) s)."""
    t = np.asarray(t, float)
    td = contact_onsets(clean(t, contact[:, 0], min_phase))
    return t[td[:-1]], np.abs(np.diff(np.asarray(foot_x)[td, 0])), np.diff(t[td])
