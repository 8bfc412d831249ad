"""The papers' figures as PNG (matplotlib, Agg backend, imported lazily).

* :func:`fitness_graph` - best and mean fitness per generation (Reil & Husbands Fig. 6);
* :func:`motor_activations` - motor neuron outputs (or the controller's joint targets) over time (Fig. 7);
* :func:`motion_sequence` - the walker in side view through one stride of steady walking (Fig. 8);
* :func:`stick_figure` - strobed stick figures along the ground, spaced apart (Taga Figs. 5, 9);
* :func:`ground_trajectory` - the path on the ground plane, sources if any (Fig. 12).

The steering experiment's pair (Figs. 12-13) is :mod:`.steering_figures`; the side view's drawing :mod:`.side_view`,
the motor outputs' names :mod:`.motor_labels`.

Drawing is generic over the model: every shape of :mod:`..geometry` is drawn
as its long axis (spheres as circles), so a sagittal biped draws as well as the
3D one.  Side views look along the direction the walker faced at the start
(walking backwards goes to the left), never along the direction it travelled.
Every figure of the package is written by :func:`save_figure`: atomically,
at a pixel size bounded whatever the episode length.  Every title names what
the figure shows and whose it is (``who``: the walker, e.g. its run directory
and seed; default the body's name); paths on the ground have equal scales on
both axes.
"""

from __future__ import annotations

import io
import textwrap
from pathlib import Path

import numpy as np

from ...core.fileio import atomic_write
from ..geometry import shapes
from .motor_labels import _motor_label, _motor_quantity, motor_file
from .side_view import _draw_walker, _side_axis, _side_key, _side_points, steady_stride
from ..trajectory import Trajectory

DPI = 120
#: no figure is drawn larger than this (inches; at DPI 120: 1920 x 1680 px before the tight bounding box)
MAX_SIZE = (16.0, 14.0)


def pyplot():
    """matplotlib.pyplot with the file-only Agg backend (imported on first use)."""
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    return plt


def save_figure(fig, path: str | Path, *, dpi: int = DPI) -> Path:
    """Write ``fig`` as PNG to ``path`` atomically (at most :data:`MAX_SIZE` inches), close it, return the path."""
    w, h = fig.get_size_inches()
    scale = min(1.0, MAX_SIZE[0] / w, MAX_SIZE[1] / h)
    if scale < 1.0:
        fig.set_size_inches(w * scale, h * scale)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi, bbox_inches="tight")
    pyplot().close(fig)
    atomic_write(path, buf.getvalue())
    return Path(path)


def walk_text(traj: Trajectory) -> str:
    """'38.65 m, -166 deg from the initial facing: backwards' for the end of ``traj``."""
    from ...tasks.walk import direction_words, displacement_heading

    a, b = traj.planar[:1], traj.planar[-1:]
    heading = float(displacement_heading(a, b, traj.start_facing[None])[0])
    return f"{float(np.linalg.norm(b - a)):.2f} m, {direction_words(heading)}"


def _title(what: str, who: str, traj: Trajectory | None = None) -> str:
    """A figure's title: what it shows, then (second line) whose it is."""
    return f"{what}\n{who or (traj.body_name if traj is not None else '')}".rstrip()


def fitness_label(config) -> str:
    """The y-axis label of a fitness graph for an ``EpisodeConfig``: the quantity and its unit
    (``Task.fitness_label``)."""
    return config.parts()[2].fitness_label()


def fitness_graph(history: dict[str, np.ndarray], path: str | Path, *, title: str = "Fitness per generation",
                  ylabel: str = "fitness: distance from the start (m)", who: str = "") -> Path:
    """Each generation's best (black; "this generation's" in the progress lines) and mean (grey) fitness, as in Fig. 6;
    ``history`` from :func:`evobiped.files.rundir.read_history`; ``ylabel`` from :func:`fitness_label`.  The last tick
    is the last generation."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6.4, 4.0))
    g = history["generation"]
    ax.plot(g, history["best"], color="black", lw=1.8, label="best of the generation")
    ax.plot(g, history["mean"], color="0.6", lw=1.5, label="mean of the generation")
    from matplotlib.ticker import MaxNLocator

    ax.set_xlabel("generation (from 0)")
    # a weighted fitness's label names every term: wrapped to the axis's height rather than stretching the figure
    long = len(ylabel) > 45
    ax.set_ylabel(textwrap.fill(ylabel, 50) if long else ylabel, fontsize=7 if long else 10)
    lo, hi = int(g.min()), int(max(g.max(), g.min() + 1))
    ticks = [t for t in MaxNLocator(nbins=7, integer=True).tick_values(lo, hi) if lo <= t <= hi]
    if hi - ticks[-1] < 0.08 * (hi - lo):
        ticks = ticks[:-1]
    ax.set_xticks([*ticks, hi])  # the last generation is a tick
    ax.set_xlim(lo, hi)
    ax.set_title(_title(title, who), fontsize=10)
    ax.legend(frameon=False)
    ax.grid(alpha=0.3)
    return save_figure(fig, path)


def motor_activations(traj: Trajectory, path: str | Path, *, seconds: float | None = 10.0, who: str = "") -> Path:
    """One panel per motor output against time (Fig. 7): a neuron's output in [0, 1], or what the
    controller commands (joint target angles in rad, torques in N m).

    ``seconds``: plot only the first this many seconds (default 10, so the rhythm stays visible; None: all).
    """
    plt = pyplot()
    n = traj.n_motor
    t = traj.command_time
    keep = t <= seconds if seconds else np.ones(len(t), bool)
    unit, target, quantity = _motor_quantity(traj)
    fig, axes = plt.subplots(n, 1, figsize=(7.0, 1.0 + 0.85 * n), sharex=True, squeeze=False)
    for i, ax in enumerate(axes[:, 0]):
        ax.plot(t[keep], traj.neurons[keep, i], color="black", lw=1.0)
        ax.text(1.0, 0.5, f" {_motor_label(traj, i)}", transform=ax.transAxes, va="center", fontsize=8)
        if unit:
            ax.set_ylim(-0.05, 1.05)
            ax.set_yticks([0, 1])
        ax.tick_params(labelsize=7)
    fig.supylabel(quantity, fontsize=9)
    axes[-1, 0].set_xlabel("time (s)")
    what = ("Motor neuron outputs" if unit else "Joint target angles (the controller's outputs)" if target
            else "Motor outputs")
    if traj.stance_frame:
        what += " in the stance frame"
    if traj.direct_path:
        what += " (the direct path adds to them)"
    shown = f"first {seconds:g} s of {traj.end_time:g} s" if keep.sum() < len(t) else f"{traj.end_time:g} s"
    fig.suptitle(_title(f"{what}, {shown}", f"{who or traj.body_name}; walked {walk_text(traj)}"), fontsize=9)
    return save_figure(fig, path)


def motion_sequence(traj: Trajectory, path: str | Path, *, frames: int = 12, columns: int = 4, after: float = 10.0,
                    who: str = "") -> Path:
    """The walker in side view at up to ``frames`` recorded states through one stride of steady walking
    (:func:`steady_stride` after ``after`` s), every k-th state from the stride's start so that the frames are
    exactly evenly spaced (the spacing is in the title), left to right, top to bottom (Fig. 8).  Every panel shows
    the same window of the position along the initial facing (m), so the walker moves across the panels."""
    plt = pyplot()
    t0, t1, what = steady_stride(traj, after)
    first = int(np.searchsorted(traj.state_time, t0 - 1e-9).clip(0, len(traj.state_time) - 1))
    last = int(np.searchsorted(traj.state_time, t1 - 1e-9).clip(first, len(traj.state_time) - 1))
    every = max(1, int(np.ceil((last - first) / max(frames - 1, 1))))  # at most ``frames``, all within the stride
    idx = np.arange(first, last + 1, every)[:frames]
    spacing = float(traj.state_time[idx[1]] - traj.state_time[idx[0]]) if len(idx) > 1 else 0.0
    rows_n = int(np.ceil(len(idx) / columns))
    axis, parts = _side_axis(traj), shapes(traj.model)
    fig, axes = plt.subplots(rows_n, columns, figsize=(2.4 * columns, 2.2 * rows_n + 0.8), squeeze=False, sharex=True,
                             sharey=True)
    h, z = _side_points(traj, parts, idx, axis)
    height = max(float(z.max()) + 0.1, 0.5)
    lo, hi = float(h.min()) - 0.1, float(h.max()) + 0.1
    for ax in axes.ravel()[len(idx):]:
        ax.axis("off")
    for ax, k in zip(axes.ravel(), idx):
        ax.axhline(0.0, color="0.5", lw=1.0)
        _draw_walker(ax, traj, parts, np.array([k]), axis)
        ax.set_xlim(lo, hi)
        ax.set_ylim(-0.05, height)
        ax.set_aspect("equal")
        ax.tick_params(labelsize=7)
        ax.set_title(f"t = {traj.state_time[k]:.2f} s", fontsize=8)
    fig.supxlabel("position along the initial facing (m)", fontsize=9)
    fig.supylabel("height (m)", fontsize=9)
    _side_key(axes[0, -1], traj, parts)
    fig.suptitle(_title(f"Side view through {what}, t = {t0:.2f}-{t1:.2f} s of {traj.end_time:g} s; "
                        f"one frame every {spacing:.2f} s",
                        f"{who or traj.body_name}; walked {walk_text(traj)}"), fontsize=10)
    return save_figure(fig, path)


def stick_figure(traj: Trajectory, path: str | Path, *, every: float = 0.1, spacing: float = 0.3, max_figures: int = 16,
                 span: float = 4.0, who: str = "") -> Path:
    """Stick figures drawn where they were along the initial facing (Taga Figs. 5, 9): one at least every
    ``every`` s and at least ``spacing`` m (along the facing) after the previous one, so that they do not
    pile up into a blob, at most ``max_figures``, from the start until the walker is ``span`` m from it
    (the figure's size does not grow with the episode)."""
    plt = pyplot()
    axis, parts = _side_axis(traj), shapes(traj.model)
    h = traj.com[:, :2] @ axis
    far = np.flatnonzero(np.abs(h - h[0]) > span)
    last = int(far[0]) if far.size else len(h) - 1
    step = max(1, int(round(every / traj.dt)))
    rows = [0]
    for k in range(step, last + 1, step):
        if abs(h[k] - h[rows[-1]]) >= spacing and len(rows) < max_figures:
            rows.append(k)
    rows = np.array(rows)
    fig, ax = plt.subplots(figsize=(min(14.0, max(6.0, 2.0 + 2.0 * float(np.ptp(h[: last + 1])))), 3.6))
    ax.axhline(0.0, color="0.5", lw=1.0)
    _draw_walker(ax, traj, parts, rows, axis, alpha=0.6)
    ax.plot(h[: last + 1], traj.com[: last + 1, 2], color="black", lw=0.8)
    for k in rows[:: max(1, len(rows) // 6)]:
        ax.text(h[k], -0.03, f"{traj.state_time[k]:.1f} s", ha="center", va="top", fontsize=8, color="0.1", zorder=6)
    ax.set_aspect("equal")
    top = float(_side_points(traj, parts, rows, axis)[1].max())
    ax.set_ylim(-0.16, max(top + 0.05, 0.5))  # room below the ground for the times
    lo, hi = ax.get_xlim()
    if hi - lo < 1.0:  # a walker that hardly moved: a metre of ground, so the ticks stay apart
        ax.set_xlim((lo + hi) / 2 - 0.5, (lo + hi) / 2 + 0.5)
    ax.set_xlabel("position along the initial facing (m; negative = backwards)")
    ax.set_ylabel("height (m)")
    shown = f"first {traj.state_time[last]:.1f} s of {traj.end_time:g} s" if last < len(
        h) - 1 else f"{traj.end_time:g} s"
    ax.set_title(_title(f"Stick figures {spacing:g} m or more apart ({len(rows)} in the {shown}); times below the "
                        "ground line",
                        f"{who or traj.body_name}; walked {walk_text(traj)}"), fontsize=9)
    _side_key(ax, traj, parts, com=True)
    return save_figure(fig, path)


def ground_trajectory(trajs: Trajectory | list[Trajectory], path: str | Path, *, labels: list[str] | None = None,
                      who: str = "") -> Path:
    """The walker's path on the ground plane, equal scales on both axes: start (circle), initial facing (arrow),
    end (square, x if it fell), sources (star) (Fig. 12); markers drawn above every path."""
    from matplotlib.lines import Line2D

    plt = pyplot()
    trajs = [trajs] if isinstance(trajs, Trajectory) else list(trajs)
    fig, ax = plt.subplots(figsize=(6.4, 5.2))
    colors = plt.get_cmap("tab10").colors
    every = np.concatenate([tr.planar for tr in trajs])
    scale = max(float(np.ptp(every[:, 0])), float(np.ptp(every[:, 1])), 0.5)
    marks = dict(mec="black", mew=0.8, zorder=5)
    for i, tr in enumerate(trajs):
        xy, c = tr.planar, colors[i % 10]
        ax.plot(xy[:, 0], xy[:, 1], lw=1.5, color=c, zorder=2, label=labels[i] if labels else f"path: {walk_text(tr)}")
        f = _side_axis(tr) * 0.12 * scale
        ax.annotate("", xy=xy[0] + f, xytext=xy[0], arrowprops=dict(arrowstyle="->", color=c, lw=1.5), zorder=4)
        ax.plot(*(xy[0] + f), alpha=0.0)  # keep the arrow inside the axes
        ax.plot(*xy[-1], "X" if tr.fell else "s", color=c, ms=9, **marks)
        ax.plot(*xy[0], "o", color="white", ms=8, **marks)
        if tr.source is not None:  # this walker's source, in its colour
            ax.plot(*tr.source[-1], "*", color=c, ms=16, **marks)
    # the key names only what is drawn, in the colour it is drawn in (one path: its colour; several: each its own)
    c = colors[0] if len(trajs) == 1 else "0.6"
    each = "" if len(trajs) == 1 else " (each path's colour)"
    keys = [Line2D([], [], marker="o", ls="", color="white", mec="black", label="start"),
            Line2D([], [], marker=r"$\rightarrow$", ls="", color=c, ms=12, label="initial facing" + each)]
    if any(not t.fell for t in trajs):
        keys.append(Line2D([], [], marker="s", ls="", color=c, mec="black", label="end, stayed up"))
    if any(t.fell for t in trajs):
        keys.append(Line2D([], [], marker="X", ls="", color=c, mec="black", label="end, fell"))
    if any(t.source is not None for t in trajs):
        keys.append(Line2D([], [], marker="*", ls="", color=c, mec="black", ms=12, label="sound source"))
    lines, names = ax.get_legend_handles_labels()
    ax.legend(handles=lines + keys, frameon=False, fontsize=7, loc="upper left", bbox_to_anchor=(1.0, 1.0))
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.grid(alpha=0.3)
    ax.set_aspect("equal", adjustable="datalim")  # 1 m is as long across as up: a drift looks as large as it is
    if len(trajs) > 1:
        what = f"Paths on the ground toward each of {len(trajs)} sound sources"
    else:
        what = f"Path on the ground, {trajs[0].end_time:g} s; walked {walk_text(trajs[0])}"
    ax.set_title(_title(what, who, trajs[0]), fontsize=9)
    return save_figure(fig, path)


def replay_figures(traj: Trajectory, out_dir: str | Path, *, history: dict[str, np.ndarray] | None = None,
                   fitness_ylabel: str = "fitness: distance from the start (m)", who: str = "") -> list[Path]:
    """Every figure of one replay (and the fitness graph if a history is given) into ``out_dir``;
    ``who`` names the walker in every title."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = []
    if history is not None:
        paths.append(fitness_graph(history, out / "fitness.png", ylabel=fitness_ylabel, who=who))
    paths.append(motor_activations(traj, out / motor_file(traj), who=who))
    paths.append(motion_sequence(traj, out / "motion_sequence.png", who=who))
    paths.append(stick_figure(traj, out / "stick_figure.png", who=who))
    paths.append(ground_trajectory(traj, out / "ground_trajectory.png", who=who))
    return paths
