"""A walker driven through levels of its rhythm generator's command (``evobiped gait GENOME --u0/--go``): its speed
against the command with the fitted line, and its forward position over time with the stretches marked."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .figures import pyplot, save_figure


def levels_figure(report: dict, path: str | Path, *, title: str) -> Path:
    """Two panels from :func:`evobiped.analysis.rhythm_command.command_sweep`'s ``report``: left, each level's mean
    forward speed (m/s; a hollow mark: it fell in that stretch) against the command, with the least-squares line
    through the others; right, the forward position (m, along the initial facing) over time (s), each stretch shaded
    with its level, the measured part of it drawn thick, a fall marked."""
    plt = pyplot()
    name, fit = report["command"], report["fit"]
    fig, (left, right) = plt.subplots(1, 2, figsize=(12, 4.5), gridspec_kw={"width_ratios": [1, 1.6]})
    done = [s for s in report["stretches"] if s["speed"] is not None]
    for s in done:
        left.plot(s["level"], s["speed"], "o", ms=8, color="#2b6cb0", mfc="white" if s["fell"] else "#2b6cb0")
    if fit["slope"] is not None:
        c = np.linspace(min(fit["levels"]), max(fit["levels"]), 50)
        left.plot(c, fit["intercept"] + fit["slope"] * c, color="black", lw=1, ls="--",
                  label=f"speed = {fit['intercept']:.3f} {'+' if fit['slope'] >= 0 else '-'} "
                        f"{abs(fit['slope']):.3f} {name}")
    if any(s["fell"] for s in done):
        left.plot([], [], "o", color="#2b6cb0", mfc="white", label="fell in its stretch (not fitted)")
    if left.get_legend_handles_labels()[0]:
        left.legend(fontsize=8, loc="best")
    left.set_xlabel(f"command {name}")
    left.set_ylabel(f"forward speed (m/s) from {report['settle']:g} s into each stretch")
    left.grid(alpha=0.3)
    t, x = np.asarray(report["trace"]["time"]), np.asarray(report["trace"]["forward"])
    for i, s in enumerate(report["stretches"]):
        right.axvspan(s["start"], s["end"], color="#e2e8f0" if i % 2 else "#f7fafc", zorder=0)
        right.text((s["start"] + s["end"]) / 2, 0.98, f"{name} {s['level']:g}", transform=right.get_xaxis_transform(),
                   ha="center", va="top", fontsize=8)
        m = (t >= s["measured_from"] - 1e-9) & (t <= s["end"] + 1e-9)
        right.plot(t[m], x[m], color="#c05621", lw=3, alpha=0.7)
    right.plot(t, x, color="#2b6cb0", lw=1, label="forward position")
    right.plot([], [], color="#c05621", lw=3, alpha=0.7, label="measured (after the transition)")
    if report["fell"]:
        right.axvline(report["end_time"], color="red", ls="--", lw=1, label=f"fell at {report['end_time']:.1f} s")
    right.set_xlim(0, report["seconds"])
    right.set_xlabel("time (s)")
    right.set_ylabel("forward position (m)")
    right.legend(fontsize=8, loc="lower right")
    right.grid(alpha=0.3)
    fig.suptitle(title, fontsize=10)
    return save_figure(fig, path)
