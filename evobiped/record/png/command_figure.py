"""A commanded walker's figure: commanded against walked speed and turning rate over time (``evobiped gait GENOME``)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from .figures import pyplot, save_figure

#: s: the walked speed and turning rate are drawn as running means over this window (the stride's sway smoothed)
WINDOW = 1.0


def _running_mean(x: np.ndarray, t: np.ndarray) -> np.ndarray:
    if len(t) < 2:
        return x
    k = max(1, int(round(WINDOW / float(np.median(np.diff(t))))))
    c = np.concatenate([[0.0], np.cumsum(x)])
    i = np.arange(1, len(x) + 1)
    lo = np.maximum(i - k, 0)
    return (c[i] - c[lo]) / (i - lo)


def command_figure(report: dict, path: str | Path, *, title: str) -> Path:
    """Two panels over time: the commanded speed (m/s) and the walked one (running mean over :data:`WINDOW` s, and
    each stretch's settled measurement as a bar), then the same for the turning rate (deg/s, + left); a fall marked."""
    plt = pyplot()
    tr = report["trace"]
    t = np.asarray(tr["time"], float)
    fig, axes = plt.subplots(2, 1, figsize=(10, 6), sharex=True)
    for ax, key, scale, unit in ((axes[0], "speed", 1.0, "m/s"), (axes[1], "turning", 180 / math.pi, "deg/s, + left")):
        ax.step(t, scale * np.asarray(tr[f"commanded_{key}"]), where="post", color="black", lw=1.5, label="commanded")
        ax.plot(t, scale * _running_mean(np.asarray(tr[f"walked_{key}"], float), t), color="#2b6cb0", lw=1.0,
                label=f"walked ({WINDOW:g} s running mean)")
        for s in report["stretches"]:
            value = s[f"walked_{key}"]
            if value is not None and math.isfinite(value):
                ax.hlines(scale * value, s["measured_from"], s["end"], color="#c05621", lw=3, alpha=0.8)
        ax.plot([], [], color="#c05621", lw=3, label="walked, settled mean per stretch")
        if report["fell"]:
            ax.axvline(report["end_time"], color="red", ls="--", lw=1)
        ax.set_ylabel(f"{key} ({unit})")
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8, loc="best")
    axes[1].set_xlabel("time (s)" + (f"; fell at {report['end_time']:.1f} s" if report["fell"] else ""))
    axes[1].set_xlim(0, report["seconds"])
    fig.suptitle(title, fontsize=10)
    return save_figure(fig, path)
