"""G3 figures as PNG: Pearson-style gait diagrams (Figs. 1, 4B, 8) and
frequency / duty versus GO level (Figs. 9, 11).

In a gait diagram each channel is a bar, white while its activity is above the
threshold (the foot off the ground) and black otherwise.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .gaits import THRESHOLD
from ...record.png.figures import pyplot, save_figure

GAIT_COLOURS = {"walk": "tab:blue", "trot": "tab:orange", "pace": "tab:green", "gallop": "tab:red",
                "pronk": "tab:purple", "none": "0.6"}


def draw_bars(ax, t: np.ndarray, x: np.ndarray, names, threshold: float = THRESHOLD) -> None:
    """Pearson bars on ``ax``: ``x`` ``(T, N)`` over ``t`` ``(T,)``, first channel on top."""
    up = (x > threshold).T.astype(float)  # (N, T)
    ax.imshow(up, aspect="auto", cmap="gray", vmin=0, vmax=1, interpolation="nearest",
              extent=(t[0], t[-1], len(names) - 0.5, -0.5))
    ax.set_yticks(range(len(names)), names)
    ax.set_yticks(np.arange(len(names) + 1) - 0.5, minor=True)
    ax.grid(which="minor", axis="y", color="0.5", lw=2)
    ax.tick_params(which="minor", length=0)


def run_figure(path: Path, t: np.ndarray, x: np.ndarray, names, *, title: str, threshold: float = THRESHOLD,
               go: np.ndarray | None = None) -> Path:
    """Activities x_k(t) above their thresholded Pearson diagram (Fig. 4A/B, 10A/B)."""
    n = 3 if go is not None else 2
    fig, axes = pyplot().subplots(n, 1, figsize=(10, 2.2 + 1.6 * n), sharex=True,
                                  gridspec_kw={"height_ratios": [2, 1.2, 0.6][:n]})
    for k, name in enumerate(names):
        axes[0].plot(t, x[:, k], lw=1, label=name)
    axes[0].axhline(threshold, color="k", ls=":", lw=0.8, label=f"threshold {threshold:g}")
    axes[0].set_ylabel("activity x (model units)")
    axes[0].legend(loc="upper right", ncol=len(names), fontsize=8)
    axes[0].set_title(title, fontsize=10)
    draw_bars(axes[1], t, x, names, threshold)
    axes[1].set_title("gait diagram: white = above threshold (limb off the ground), black = below", fontsize=8)
    if go is not None:
        axes[2].plot(t, go, color="k")
        axes[2].set_ylabel("GO I")
    axes[-1].set_xlabel("time (model units)")
    fig.tight_layout()
    return save_figure(fig, path, dpi=110)


def sweep_diagrams(path: Path, t: np.ndarray, xs: list[np.ndarray], labels: list[str], names, *, title: str,
                   threshold: float = THRESHOLD) -> Path:
    """One Pearson diagram per GO level (Fig. 8A style); ``xs[l]`` ``(T_l, N)`` over ``t``-aligned windows."""
    fig, axes = pyplot().subplots(len(xs), 1, figsize=(10, 0.3 + 1.0 * len(xs)), squeeze=False)
    for ax, x, lab in zip(axes[:, 0], xs, labels):
        draw_bars(ax, t[: len(x)], x, names, threshold)
        ax.set_ylabel(lab, rotation=0, ha="right", va="center", fontsize=8)
        ax.set_yticks([])
        ax.set_xticks([])
    axes[-1, 0].set_xticks(np.linspace(t[0], t[len(xs[-1]) - 1], 5))
    axes[-1, 0].set_xlabel("time within the window (model units)")
    axes[0, 0].set_title(f"{title}\nwhite = above threshold (limb off the ground), black = below", fontsize=10)
    fig.tight_layout()
    return save_figure(fig, path, dpi=110)


def frequency_figure(path: Path, levels: np.ndarray, freq: np.ndarray, duty: np.ndarray, labels: list[str], *,
                     title: str, duty_lines=()) -> Path:
    """Frequency (Figs. 9, 11A) and fraction of cycle above threshold (Fig. 11B) vs GO level."""
    fig, (a1, a2) = pyplot().subplots(1, 2, figsize=(11, 4))
    osc = freq > 0  # levels without a steady oscillation are left out
    for lab in dict.fromkeys(labels):
        m = np.array([l_ == lab for l_ in labels]) & osc
        a1.plot(levels[m], freq[m], "o", color=GAIT_COLOURS.get(lab, "k"), label=lab)
        a2.plot(levels[m], duty[m], "o", color=GAIT_COLOURS.get(lab, "k"), label=lab)
    a1.plot(levels[osc], freq[osc], "-", color="0.7", lw=0.8, zorder=0)
    a1.set_xlabel("GO level I")
    a1.set_ylabel("frequency (cycles / model time unit)")
    a1.legend(fontsize=8)
    for y, ls in zip(duty_lines, (":", "--", "-.")):
        a2.axhline(y, color="k", ls=ls, lw=0.8, label=f"{y:g}")
    if len(duty_lines):
        a2.legend(fontsize=8, title="reference", title_fontsize=8)
    a2.set_xlabel("GO level I")
    a2.set_ylabel("fraction of the cycle above threshold (limb off the ground)")
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    return save_figure(fig, path, dpi=110)


def sweep_files(out_dir: Path, stem: str) -> list[Path]:
    """Every PNG :func:`sweep_figures` may write for ``stem`` (a level's run, the diagrams, frequency/duty): one set,
    so a sweep of one level never leaves its run's figure beside another sweep's frequency plot."""
    return [Path(out_dir) / f"{stem}_{kind}.png" for kind in ("run", "diagrams", "frequency")]


def sweep_figures(out_dir: Path, stem: str, sweep, channels: list[int], names, *, title: str, span: float = 40.0,
                  max_diagrams: int = 12) -> list[Path]:
    """The PNGs of a :class:`~evobiped.experiments.g3.simulation.GoSweep`: each level's run (one level) or
    one diagram per level over the last ``span`` time units of its hold (at
    most ``max_diagrams`` evenly spaced levels), plus frequency/duty vs I
    (several levels).  Returns the paths written."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    tr, names = sweep.traj, [names[c] for c in channels]
    run_png, diagrams_png, frequency_png = sweep_files(out_dir, stem)
    written = []
    if len(sweep.levels) == 1:
        r = sweep.rows[0]
        written.append(run_figure(run_png, tr.t, tr.x[r][:, channels], names,
                                  title=f"{title}: I = {sweep.levels[0]:g}, {sweep.gaits[0].label}", go=tr.go[r]))
    xs, labels = [], []
    L = len(sweep.levels)
    pick = np.unique(np.round(np.linspace(0, L - 1, min(L, max_diagrams))).astype(int))
    for i in pick:
        lv, g, r, b = sweep.levels[i], sweep.gaits[i], sweep.rows[i], sweep.end[i]
        m = (tr.t > b - span - 1e-9) & (tr.t <= b + 1e-9)
        xs.append(tr.x[r][m][:, channels])
        labels.append(f"I={lv:.3g}\n{g.label}")
    t = tr.t[: max(len(x) for x in xs)] - tr.t[0]
    heading = f"{title}: last {span:g} units of each level; bars top to bottom: {', '.join(names)}"
    written.append(sweep_diagrams(diagrams_png, t, xs, labels, names, title=heading))
    if len(sweep.levels) > 1:
        freq = np.array([g.frequency for g in sweep.gaits])
        duty = np.array([np.mean(g.duty) for g in sweep.gaits])
        written.append(frequency_figure(frequency_png, sweep.levels, freq, duty,
                                        [g.label for g in sweep.gaits], title=title, duty_lines=(0.23, 0.31)))
    return written
