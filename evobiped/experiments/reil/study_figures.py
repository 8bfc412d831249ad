"""Figures of a study: Fig. 5's distance histograms and every run's fitness graph."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ...record.png.figures import pyplot, save_figure

_COLORS = {"plain": "tab:blue", "cyclic": "tab:orange"}


def distance_histograms(outcomes: list[dict], conditions, edges: np.ndarray, path: str | Path) -> Path:
    """Fig. 5: best-walker distances, (a) runs whose best fell, (b) runs whose best stayed up; one outlined
    histogram per condition over the same bins (each bar spans exactly its bin)."""
    from matplotlib.ticker import MaxNLocator

    plt = pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(10, 4.2), sharey=True)
    for ax, stable, title in ((axes[0], False, "(a) unstable: fell within the episode"),
                              (axes[1], True, "(b) stable: did not fall")):
        for i, c in enumerate(conditions):
            d = [o["distance"] for o in outcomes if o["condition"] == c and o["fell"] != stable]
            ax.hist(d, bins=edges, histtype="step", lw=1.5 + 1.2 * (len(conditions) - 1 - i),
                    color=_COLORS.get(c, f"C{i}"), label=f"{c} ({len(d)} runs)")
        ax.set_title(title, fontsize=10)
        ax.set_xlabel("distance of the best walker from its start (m)")
        ax.set_xlim(edges[0], edges[-1])
        ax.yaxis.set_major_locator(MaxNLocator(integer=True))
        ax.grid(alpha=0.3, axis="y")
    axes[0].set_ylabel("runs")
    axes[1].legend(frameon=False, fontsize=8, loc="upper left", bbox_to_anchor=(1.0, 1.0), title="condition")
    fig.suptitle("Distance of each run's best walker (Fig. 5)", fontsize=11)
    return save_figure(fig, path)


#: the y-axis label per study condition: the quantity each one's fitness measures
FITNESS_LABELS = {"plain": "fitness (m): distance", "cyclic": "fitness (m): distance × (1 + cyclic activity)",
                  "forward": "fitness (m): (forward displacement + survival credit) × time up / T"}


def fitness_graphs(histories: dict[str, list[dict[str, np.ndarray]]], path: str | Path, *,
                   seeds: list[int] | None = None) -> Path:
    """Best fitness per generation of every run, one panel per condition (Fig. 6 for all runs at once), one
    colour per run (``seeds``: the run seed of each run, in order; default 0, 1, ...) named in a legend."""
    from matplotlib.ticker import MaxNLocator

    plt = pyplot()
    n = len(histories)
    cols = min(3, n)
    rows = -(-n // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(4.6 * cols + 1.0, 3.4 * rows + 0.5), squeeze=False)
    for ax in axes.ravel()[n:]:
        ax.axis("off")
    for ax, (c, runs) in zip(axes.ravel(), histories.items()):
        names = [f"seed {s}" for s in (seeds or range(len(runs)))]
        cmap = plt.get_cmap("tab10" if len(runs) <= 10 else "tab20")
        for k, (h, name) in enumerate(zip(runs, names)):
            ax.plot(h["generation"], h["best"], color=cmap(k % cmap.N), lw=1.1, label=name)
        ax.set_title(f"condition {c} ({len(runs)} runs)", fontsize=9)
        ax.set_xlabel("generation (from 0)", fontsize=9)
        base = c.split("-")[-1] if c.split("-")[-1] in FITNESS_LABELS else c.split("-")[0]
        ax.set_ylabel(FITNESS_LABELS.get(base, "fitness"), fontsize=7)
        ax.ticklabel_format(useOffset=False)
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))
        ax.tick_params(labelsize=8)
        ax.grid(alpha=0.3)
        ax.legend(frameon=False, fontsize=7, loc="upper left", bbox_to_anchor=(1.0, 1.0), title="run", title_fontsize=7)
    fig.suptitle("Best fitness per generation, one line per run", fontsize=11)
    fig.tight_layout()
    return save_figure(fig, path)
