"""The robustness battery as one PNG: survival per family, and where each trial ended."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..robustness import Trial, summarise
from .figures import pyplot, save_figure


def robustness_figure(trials: list[Trial], path: str | Path, *, title: str) -> Path:
    """Left: survival (%) per family of trials.  Right: each trial's forward displacement (m)
    against the time it stayed up (s), coloured by family; a fall is a cross, survival a dot."""
    plt = pyplot()
    rows = summarise(trials)
    families = [r["family"] for r in rows]
    colours = {f: plt.get_cmap("tab10")(i % 10) for i, f in enumerate(families)}
    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4.2), gridspec_kw={"width_ratios": [1, 1.3]})
    y = np.arange(len(rows))[::-1]
    a.barh(y, [100 * r["survival"] for r in rows], color=[colours[f] for f in families])
    for yi, r in zip(y, rows):
        a.text(min(100 * r["survival"] + 2, 88), yi, f"{r['survived']}/{r['trials']}", va="center", fontsize=9)
    a.set_yticks(y, families)
    a.set_xlim(0, 100)
    a.set_xlabel("trials survived (%)")
    a.set_title("Survival per family")
    for f in families:
        ts = [t for t in trials if t.family == f]
        up = [t for t in ts if t.survived]
        down = [t for t in ts if not t.survived]
        b.scatter([t.end_time for t in up], [t.forward for t in up], color=colours[f], marker="o", s=18, label=f)
        b.scatter([t.end_time for t in down], [t.forward for t in down], color=colours[f], marker="x", s=22)
    b.axhline(0, color="0.7", lw=0.8)
    b.set_xlabel("time up (s); x = fell, o = still up at the end")
    b.set_ylabel("displacement along the initial facing (m)")
    b.set_title("Each trial")
    b.legend(fontsize=8, loc="best")
    fig.suptitle(title, fontsize=10)
    return save_figure(fig, path)
