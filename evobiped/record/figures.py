"""The papers' figures as PNG (matplotlib, Agg backend, imported lazily).

* :func:`fitness_graph` - top and mean fitness per generation (Reil & Husbands Fig. 6);
* :func:`motor_activations` - motor neuron outputs over time (Fig. 7);
* :func:`motion_sequence` - the walker in side view at evenly spaced times (Fig. 8);
* :func:`stick_figure` - strobed stick figures along the ground (Taga Figs. 5, 9);
* :func:`ground_trajectory` - the path on the ground plane, sources if any (Fig. 12).

Drawing is generic over the model: every shape of :mod:`.geometry` is drawn
as its long axis (spheres as circles), so a sagittal biped draws as well as the
3D one.  Each function writes one PNG atomically and returns its path.
"""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from ..fileio import atomic_write
from .geometry import Shape, body_names, segment, shapes
from .trajectory import Trajectory

DPI = 120


def _plt():
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    return plt


def _save(fig, path: str | Path) -> Path:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=DPI, bbox_inches="tight")
    _plt().close(fig)
    atomic_write(path, buf.getvalue())
    return Path(path)


def fitness_graph(history: dict[str, np.ndarray], path: str | Path, *, title: str = "Fitness per generation") -> Path:
    """Top (black) and mean (grey) fitness per generation, as in Fig. 6; ``history`` from ``read_history``."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(6.4, 4.0))
    g = history["generation"]
    ax.plot(g, history["best"], color="black", lw=1.8, label="top")
    ax.plot(g, history["mean"], color="0.6", lw=1.5, label="mean")
    ax.set_xlabel("generation")
    ax.set_ylabel("fitness (m)")
    ax.set_xlim(g.min(), max(g.max(), g.min() + 1))
    ax.set_title(title)
    ax.legend(frameon=False)
    ax.grid(alpha=0.3)
    return _save(fig, path)


def motor_activations(traj: Trajectory, path: str | Path, *, seconds: float | None = None) -> Path:
    """One panel per motor neuron: its output O in [0, 1] against time (Fig. 7).

    ``seconds``: plot only the first this many seconds (default: all).
    """
    plt = _plt()
    n = traj.n_motor
    t = traj.command_time
    keep = t <= seconds if seconds else np.ones(len(t), bool)
    motor = traj.neurons[:, :n]
    unit = motor.size == 0 or (np.nanmin(motor) >= 0.0 and np.nanmax(motor) <= 1.0)  # else e.g. angles, torques
    fig, axes = plt.subplots(n, 1, figsize=(7.0, 1.0 + 0.85 * n), sharex=True, squeeze=False)
    for i, ax in enumerate(axes[:, 0]):
        ax.plot(t[keep], traj.neurons[keep, i], color="black", lw=1.0)
        name = traj.actuator_names[i] if i < len(traj.actuator_names) else f"output {i + 1}"
        ax.set_ylabel(f"M{i + 1}", rotation=0, ha="right", va="center")
        ax.text(1.0, 0.5, f" {name}", transform=ax.transAxes, va="center", fontsize=8)
        if unit:
            ax.set_ylim(-0.05, 1.05)
            ax.set_yticks([0, 1])
    axes[-1, 0].set_xlabel("time (s)")
    what = "Motor neuron outputs" if unit else "Motor outputs"
    axes[0, 0].set_title(f"{what} ({traj.body_name}; fitness {traj.final_fitness:.3f} m)")
    return _save(fig, path)


def _side_axis(traj: Trajectory) -> np.ndarray:
    """Unit vector on the ground along which to view the walker from the side."""
    d = traj.planar[-1] - traj.planar[0]
    if np.linalg.norm(d) < 0.05:
        d = np.array([1.0, 0.0])
    return d / np.linalg.norm(d)


def _color(name: str) -> str:
    n = name.lower()
    return "tab:blue" if "left" in n else "tab:red" if "right" in n else "0.25"


def _side_points(traj: Trajectory, parts: list[Shape], rows: np.ndarray, axis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Side-view coordinates ``(R, n)`` (along ``axis``, height) of every shape's extreme points."""
    pts = []
    for s in parts:
        if s.body == 0:
            continue
        seg = segment(s, traj.body_pos[rows, s.body], traj.body_quat[rows, s.body])  # (R, 2, 3)
        r = s.size[0] if s.kind in ("sphere", "capsule", "cylinder") else 0.0
        for dz in (-r, r):
            pts.append(seg + np.array([0.0, 0.0, dz]))
    allp = np.concatenate(pts, axis=1)  # (R, n, 3)
    return allp[..., :2] @ axis, allp[..., 2]


def _draw_walker(ax, traj: Trajectory, parts: list[Shape], rows: np.ndarray, axis: np.ndarray, offset: float = 0.0, alpha: float = 1.0) -> None:
    """Side view of the walker at state rows ``rows``: horizontal = along ``axis``, vertical = z."""
    import matplotlib.patches as mpatches

    names = body_names(traj.model)
    for s in parts:
        if s.body == 0:
            continue
        seg = segment(s, traj.body_pos[rows, s.body], traj.body_quat[rows, s.body])  # (R, 2, 3)
        h = seg[..., :2] @ axis - offset
        z = seg[..., 2]
        col = _color(names[s.body] + s.name)
        for r in range(len(rows)):
            if s.kind == "sphere":
                ax.add_patch(mpatches.Circle((h[r, 0], z[r, 0]), s.size[0], color=col, alpha=alpha, lw=0))
            else:
                ax.plot(h[r], z[r], color=col, lw=3.0, alpha=alpha, solid_capstyle="round")


def motion_sequence(traj: Trajectory, path: str | Path, *, frames: int = 12, columns: int = 4) -> Path:
    """The walker in side view at ``frames`` evenly spaced times, left to right, top to bottom (Fig. 8)."""
    plt = _plt()
    rows_n = int(np.ceil(frames / columns))
    idx = np.unique(np.linspace(0, len(traj.state_time) - 1, frames).round().astype(int))
    axis, parts = _side_axis(traj), shapes(traj.model)
    fig, axes = plt.subplots(rows_n, columns, figsize=(2.2 * columns, 2.6 * rows_n), squeeze=False)
    centres = traj.com[idx, :2] @ axis
    h, z = _side_points(traj, parts, idx, axis)
    height = max(float(z.max()) + 0.1, 0.5)
    half = max(0.75, float(np.abs(h - centres[:, None]).max()) + 0.1)
    for ax in axes.ravel():
        ax.axis("off")
    for ax, k, centre in zip(axes.ravel(), idx, centres):
        ax.axhline(0.0, color="0.5", lw=1.0)
        _draw_walker(ax, traj, parts, np.array([k]), axis, offset=float(centre))
        ax.set_xlim(-half, half)
        ax.set_ylim(-0.05, height)
        ax.set_aspect("equal")
        ax.set_title(f"t = {traj.state_time[k]:.2f} s", fontsize=9)
    fig.suptitle(f"Motion sequence, side view ({traj.body_name}; blue = left, red = right)", fontsize=10)
    return _save(fig, path)


def stick_figure(traj: Trajectory, path: str | Path, *, every: float = 0.1, max_figures: int = 60) -> Path:
    """Stick figures every ``every`` s (at most ``max_figures``), drawn where they were along the ground (Taga Figs. 5, 9)."""
    plt = _plt()
    axis, parts = _side_axis(traj), shapes(traj.model)
    step = max(1, int(round(every / traj.dt)), int(np.ceil(len(traj.state_time) / max_figures)))
    every = step * traj.dt
    rows = np.arange(0, len(traj.state_time), step)
    h = traj.com[:, :2] @ axis
    fig, ax = plt.subplots(figsize=(max(6.0, 2.0 + 2.0 * float(np.ptp(h))), 3.2))
    ax.axhline(0.0, color="0.5", lw=1.0)
    _draw_walker(ax, traj, parts, rows, axis, alpha=0.55)
    ax.plot(h, traj.com[:, 2], color="black", lw=0.8, label="centre of mass")
    ax.set_aspect("equal")
    ax.set_xlabel("distance along the walking direction (m)")
    ax.set_ylabel("height (m)")
    ax.set_title(f"Stick figure every {every:g} s ({traj.body_name})", fontsize=10)
    ax.legend(frameon=False, loc="upper right", fontsize=8)
    return _save(fig, path)


def ground_trajectory(trajs: Trajectory | list[Trajectory], path: str | Path, *, labels: list[str] | None = None) -> Path:
    """The walker's path on the ground plane, start (circle), end (square, x if it fell), sources (star) (Fig. 12)."""
    plt = _plt()
    trajs = [trajs] if isinstance(trajs, Trajectory) else list(trajs)
    fig, ax = plt.subplots(figsize=(5.2, 5.2))
    for i, tr in enumerate(trajs):
        xy = tr.planar
        label = labels[i] if labels else None
        line = ax.plot(xy[:, 0], xy[:, 1], lw=1.5, label=label)[0]
        ax.plot(*xy[0], "o", color=line.get_color())
        ax.plot(*xy[-1], "x" if tr.fell else "s", color=line.get_color(), ms=8)
        srcs = tr.sources if tr.sources is not None else (np.unique(tr.source, axis=0) if tr.source is not None else None)
        if srcs is not None:
            ax.plot(srcs[:, 0], srcs[:, 1], "*", color="tab:orange", ms=14, label="source" if i == 0 else None)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.grid(alpha=0.3)
    end = trajs[0]
    ax.set_title(f"Ground trajectory ({end.body_name}; o start, x fell, square stayed up)", fontsize=10)
    if labels or any(t.source is not None or t.sources is not None for t in trajs):
        ax.legend(frameon=False, fontsize=8)
    return _save(fig, path)


def replay_figures(traj: Trajectory, out_dir: str | Path, *, history: dict[str, np.ndarray] | None = None) -> list[Path]:
    """Every figure of one replay (and the fitness graph if a history is given) into ``out_dir``."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = []
    if history is not None:
        paths.append(fitness_graph(history, out / "fitness.png"))
    paths.append(motor_activations(traj, out / "motor_neurons.png"))
    paths.append(motion_sequence(traj, out / "motion_sequence.png"))
    paths.append(stick_figure(traj, out / "stick_figure.png"))
    paths.append(ground_trajectory(traj, out / "ground_trajectory.png"))
    return paths


def steering_neuron(trajs: list[Trajectory], path: str | Path, *, neuron: int = 3, labels: list[str] | None = None) -> Path:
    """One motor neuron's output per presentation (Fig. 13: right hip sagittal = neuron 4, index 3)."""
    plt = _plt()
    fig, axes = plt.subplots(len(trajs), 1, figsize=(7.0, 1.2 + 1.3 * len(trajs)), sharex=True, squeeze=False)
    name = trajs[0].actuator_names[neuron] if neuron < len(trajs[0].actuator_names) else f"neuron {neuron + 1}"
    for ax, tr, label in zip(axes[:, 0], trajs, labels or [None] * len(trajs)):
        ax.plot(tr.command_time, tr.neurons[:, neuron], color="black", lw=1.0)
        ax.set_ylim(-0.05, 1.05)
        ax.set_ylabel("output")
        ax.set_title(label or "", fontsize=9)
    axes[-1, 0].set_xlabel("time (s)")
    fig.suptitle(f"Motor neuron {neuron + 1} ({name}) per sound source", fontsize=10)
    return _save(fig, path)


def steering_figures(trajs: list[Trajectory], out_dir: str | Path) -> list[Path]:
    """Fig. 12 (paths toward every source) and Fig. 13 (right-hip sagittal neuron per source)."""
    out = Path(out_dir)
    labels = [f"source {i + 1} at ({tr.source[0, 0]:g}, {tr.source[0, 1]:g}) m" for i, tr in enumerate(trajs)]
    return [
        ground_trajectory(trajs, out / "steering_trajectories.png", labels=labels),
        steering_neuron(trajs, out / "steering_neuron.png", labels=labels),
    ]
