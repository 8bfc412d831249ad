"""Figures of a study: Fig. 5's distance histograms and every run's fitness graph."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .figures import _plt, _save

_COLORS = {"plain": "tab:blue", "cyclic": "tab:orange"}


def distance_histograms(outcomes: list[dict], conditions, edges: np.ndarray, path: str | Path) -> Path:
    """Fig. 5: best-walker distances, (a) runs whose best fell, (b) runs whose best stayed up; a bar per condition."""
    plt = _plt()
    fig, axes = plt.subplots(1, 2, figsize=(10, 3.8), sharey=True)
    width = (edges[1] - edges[0]) / (len(conditions) + 1)
    for ax, stable, title in ((axes[0], False, "(a) unstable: fell within the episode"), (axes[1], True, "(b) stable: did not fall")):
        for i, c in enumerate(conditions):
            d = [o["distance"] for o in outcomes if o["condition"] == c and o["fell"] != stable]
            counts, _ = np.histogram(d, bins=edges)
            ax.bar(edges[:-1] + (i + 0.5) * width, counts, width=width, align="edge", color=_COLORS.get(c), label=f"{c} ({len(d)} runs)")
        ax.set_title(title, fontsize=10)
        ax.set_xlabel("distance of the best walker (m)")
        ax.set_xlim(edges[0], edges[-1])
        ax.legend(frameon=False, fontsize=8)
        ax.grid(alpha=0.3, axis="y")
    axes[0].set_ylabel("runs")
    return _save(fig, path)


def fitness_graphs(histories: dict[str, list[dict[str, np.ndarray]]], path: str | Path) -> Path:
    """Best fitness per generation of every run, one panel per condition (Fig. 6 for all runs at once)."""
    plt = _plt()
    fig, axes = plt.subplots(1, len(histories), figsize=(5 * len(histories), 3.6), sharey=True, squeeze=False)
    for ax, (c, runs) in zip(axes[0], histories.items()):
        for h in runs:
            ax.plot(h["generation"], h["best"], color=_COLORS.get(c), lw=1.0, alpha=0.6)
        ax.set_title(f"{c}: best fitness of {len(runs)} runs", fontsize=10)
        ax.set_xlabel("generation")
        ax.grid(alpha=0.3)
    axes[0][0].set_ylabel("fitness (m)")
    return _save(fig, path)
