"""A gait repertoire (a MAP-Elites archive) as PNG figures: the grid's cells coloured by their elite, and the QD score
and coverage against the evaluations."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .figures import pyplot, save_figure


def archive_figure(path: str | Path, *, cells: np.ndarray, objective: np.ndarray, walking: np.ndarray,
                   names: tuple[str, str],
                   low: np.ndarray, high: np.ndarray, resolution: tuple[int, int], objective_label: str,
                   who: str = "") -> Path:
    """Left: each filled cell coloured by its elite's objective (white: empty); right: the cells whose elite walks
    (``walking`` ``(E,)`` bool), coloured by the second measure's value at the cell centre to read turning left from
    right.  ``cells`` ``(E, 2)`` grid coordinates (i along ``names[0]``, x axis), ``objective`` ``(E,)``; ``names`` the
    two measures with units, ``low``/``high`` ``(2,)`` their bounds, ``resolution`` the cells along each."""
    plt = pyplot()
    grid = np.full(tuple(resolution), np.nan)
    grid[cells[:, 0], cells[:, 1]] = objective
    walk = np.full(tuple(resolution), np.nan)
    centre = low[1] + (np.arange(resolution[1]) + 0.5) * (high[1] - low[1]) / resolution[1]
    walk[cells[walking, 0], cells[walking, 1]] = centre[cells[walking, 1]]
    extent = (low[0], high[0], low[1], high[1])
    fig, (a, b) = plt.subplots(1, 2, figsize=(12.5, 5.2), sharey=True)
    im = a.imshow(grid.T, origin="lower", extent=extent, aspect="auto", cmap="viridis", interpolation="nearest")
    fig.colorbar(im, ax=a, label=objective_label)
    a.set_title(f"Elites: {len(cells)} of {grid.size} cells filled", fontsize=10)
    b.imshow(walk.T, origin="lower", extent=extent, aspect="auto", cmap="coolwarm", interpolation="nearest",
             vmin=low[1], vmax=high[1])
    b.set_title(f"Walking gaits: {int(walking.sum())} cells", fontsize=10)
    for ax in (a, b):
        ax.set_xlabel(names[0])
        ax.grid(alpha=0.2)
    a.set_ylabel(names[1])
    fig.suptitle(f"Gait repertoire (MAP-Elites archive)\n{who}".rstrip(), fontsize=11)
    fig.tight_layout()
    return save_figure(fig, path)


def progress_figure(path: str | Path, *, progress: np.ndarray, walking_cells: int, cells_total: int,
                    who: str = "") -> Path:
    """The QD score (the sum of the elites' objectives; left axis) and the cells filled (right axis, % of
    ``cells_total``) after each generation, against the evaluations so far; ``progress`` ``(generations, 3)``
    evaluations, cells, QD score as archive.json keeps it; ``walking_cells`` noted at the end."""
    plt = pyplot()
    ev, filled, qd = progress[:, 0], progress[:, 1], progress[:, 2]
    fig, a = plt.subplots(figsize=(8.5, 4.8))
    a.plot(ev, qd, color="black", label="QD score")
    a.set_xlabel("evaluations (episodes)")
    a.set_ylabel("QD score (sum of the elites' objectives)")
    b = a.twinx()
    b.plot(ev, 100 * filled / cells_total, color="tab:blue", label="coverage")
    b.set_ylabel("coverage (% of cells filled)", color="tab:blue")
    b.set_ylim(0, 100)
    a.set_title(f"Archive growth: {int(filled[-1])} cells filled, {walking_cells} of them walking, after {int(ev[-1])} "
                "evaluations"
                + (f"\n{who}" if who else ""), fontsize=10)
    a.grid(alpha=0.3)
    fig.tight_layout()
    return save_figure(fig, path)
