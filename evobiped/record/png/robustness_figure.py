"""The robustness battery as one PNG: survival per family, and where each trial ended."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ...analysis.robustness import Trial, summarise
from .figures import pyplot, save_figure


def robustness_figure(trials: list[Trial], path: str | Path, *, title: str, seconds: float | None = None) -> Path:
    """Left: survival (%) per family of trials.  Right: each trial's forward displacement (m) against the time
    it stayed up (s), coloured by family, a legend decoding colours and markers (o: up at the end, x: fell);
    the trials that stayed up all ``seconds`` s sit in a column of their own right of the time axis (spread
    sideways so they do not hide each other; the column has no time scale, its one label says they were up all
    ``seconds`` s); families of a few trials (friction, slope) name each trial's value and outcome."""
    from matplotlib.lines import Line2D

    plt = pyplot()
    rows = summarise(trials)
    families = [r["family"] for r in rows]
    colours = {f: plt.get_cmap("tab10")(i % 10) for i, f in enumerate(families)}
    few = {f: [t for t in trials if t.family == f] for f in families if sum(t.family == f for t in trials) <= 4}
    # a family whose trials are named gets the room of its lines of text: one unit per line, bars one unit high
    room = np.array([1.0 + len(few[f]) if f in few else 1.4 for f in families])
    y = room.sum() - (np.cumsum(room) - room / 2)
    fig, (a, b) = plt.subplots(1, 2, figsize=(12.5, max(5.6, 1.6 + 0.2 * room.sum())),
                               gridspec_kw={"width_ratios": [1, 1.4]})
    a.barh(y, [100 * r["survival"] for r in rows], color=[colours[f] for f in families], height=0.9)
    a.set_ylim(0, room.sum())
    for yi, r in zip(y, rows):
        text = f"{r['survived']}/{r['trials']}"
        if r["family"] in few:  # name the values: which stayed up, which fell
            text += "".join(f"\n{t.label}: {'up' if t.survived else f'fell at {t.end_time:.1f} s'}"
                            for t in few[r["family"]])
        a.text(min(100 * r["survival"] + 2, 60), yi, text, va="center", fontsize=9 if r["family"] not in few else 7,
               bbox=dict(facecolor="white", edgecolor="none", alpha=0.85, pad=1.0))  # readable over a long bar
    a.set_yticks(y, families, fontsize=8)
    a.set_xlim(0, 100)
    a.set_xlabel("trials survived (%)")
    a.set_title("Survival per family", fontsize=10)
    end = seconds if seconds is not None else max(t.end_time for t in trials)
    band = 0.2 * end  # survivors are spread over a column of this width by their order, not piled on one point
    gap = 0.25 * band  # the column stands apart from the time axis
    k_up = 0
    n_up = max(1, sum(t.survived for t in trials))
    for f in families:
        ts = [t for t in trials if t.family == f]
        up = [t for t in ts if t.survived]
        down = [t for t in ts if not t.survived]
        xs = [end + gap + band * (k_up + i + 0.5) / n_up for i in range(len(up))]
        k_up += len(up)
        b.scatter(xs, [t.forward for t in up], color=colours[f], marker="o", s=18, zorder=3)
        b.scatter([t.end_time for t in down], [t.forward for t in down], color=colours[f], marker="x", s=24, zorder=3)
    b.axvspan(end + gap, end + gap + band, color="0.92", zorder=0)
    b.axhline(0, color="0.7", lw=0.8)
    b.set_xlim(0, end + 2 * gap + band)
    from matplotlib.ticker import MaxNLocator

    ticks = [t for t in MaxNLocator(nbins=6).tick_values(0, end) if 0 <= t <= end]  # times only on the time axis
    b.set_xticks([*ticks, end + gap + band / 2], [f"{t:g}" for t in ticks] + [f"up all\n{end:g} s"])
    b.set_xlabel("time up (s) until the fall; grey column: still up at the end (spread sideways, no time scale)")
    b.set_ylabel("displacement along the initial facing (m)")
    b.set_title("Each trial", fontsize=10)
    keys = [Line2D([], [], marker="s", ls="", color=colours[f], label=f) for f in families]
    keys += [Line2D([], [], marker="o", ls="", color="0.3", label="still up at the end"),
             Line2D([], [], marker="x", ls="", color="0.3", label="fell (at its time up)")]
    b.legend(handles=keys, fontsize=8, frameon=False, loc="upper left", bbox_to_anchor=(1.0, 1.0))
    fig.suptitle(title, fontsize=10)
    return save_figure(fig, path)
