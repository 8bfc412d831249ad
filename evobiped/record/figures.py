"""The papers' figures as PNG (matplotlib, Agg backend, imported lazily).

* :func:`fitness_graph` - top and mean fitness per generation (Reil & Husbands Fig. 6);
* :func:`motor_activations` - motor neuron outputs over time (Fig. 7);
* :func:`motion_sequence` - the walker in side view at evenly spaced times (Fig. 8);
* :func:`stick_figure` - strobed stick figures along the ground (Taga Figs. 5, 9);
* :func:`ground_trajectory` - the path on the ground plane, sources if any (Fig. 12).

Drawing is generic over the model: every shape of :mod:`.geometry` is drawn
as its long axis (spheres as circles), so a sagittal biped draws as well as the
3D one.  Side views look along the direction the walker faced at the start
(walking backwards goes to the left), never along the direction it travelled.
Every figure of the package is written by :func:`save_figure`: atomically,
at a pixel size bounded whatever the episode length.
"""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from ..fileio import atomic_write
from .geometry import Shape, body_names, segment, shapes
from .trajectory import Trajectory

DPI = 120
#: no figure is drawn larger than this (inches; at DPI 120: 1920 x 1680 px before the tight bounding box)
MAX_SIZE = (16.0, 14.0)
LEFT, RIGHT, OTHER = "tab:blue", "tab:red", "0.25"


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
    from ..tasks.walk import direction_words, displacement_heading

    a, b = traj.planar[:1], traj.planar[-1:]
    heading = float(displacement_heading(a, b, traj.start_facing[None])[0])
    return f"{float(np.linalg.norm(b - a)):.2f} m, {direction_words(heading)}"


def fitness_label(config) -> str:
    """The y-axis label of a fitness graph for an ``EpisodeConfig``: the quantity and its unit (``Task.fitness_label``)."""
    from ..tasks import TASKS

    return TASKS[config.task](config.task_options).fitness_label()


def fitness_graph(history: dict[str, np.ndarray], path: str | Path, *, title: str = "Fitness per generation",
                  ylabel: str = "fitness: distance from the start (m)") -> Path:
    """Top (black) and mean (grey) fitness per generation, as in Fig. 6; ``history`` from :func:`evobiped.rundir.read_history`;
    ``ylabel`` from :func:`fitness_label`."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6.4, 4.0))
    g = history["generation"]
    ax.plot(g, history["best"], color="black", lw=1.8, label="top")
    ax.plot(g, history["mean"], color="0.6", lw=1.5, label="mean")
    from matplotlib.ticker import MaxNLocator

    ax.set_xlabel("generation (from 0)")
    ax.set_ylabel(ylabel)
    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax.set_xlim(g.min(), max(g.max(), g.min() + 1))
    ax.set_title(title)
    ax.legend(frameon=False)
    ax.grid(alpha=0.3)
    return save_figure(fig, path)


def _motor_quantity(traj: Trajectory) -> tuple[bool, bool, str]:
    """(outputs are neuron outputs in [0, 1], commands are PD target angles, the y-axis label)."""
    motor = traj.neurons[:, : traj.n_motor]
    unit = motor.size == 0 or (np.nanmin(motor) >= 0.0 and np.nanmax(motor) <= 1.0)  # else e.g. angles, torques
    target = traj.action_kind == "position"  # PD target angles
    quantity = "output (0-1)" if unit else "target angle (rad)" if target else "torque (N m)" if traj.action_kind == "torque" else "command"
    return unit, target, quantity


def motor_activations(traj: Trajectory, path: str | Path, *, seconds: float | None = 10.0) -> Path:
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
        name = traj.actuator_names[i] if i < len(traj.actuator_names) else f"output {i + 1}"
        ax.text(1.0, 0.5, f" {name}", transform=ax.transAxes, va="center", fontsize=8)
        if unit:
            ax.set_ylim(-0.05, 1.05)
            ax.set_yticks([0, 1])
        ax.tick_params(labelsize=7)
    fig.supylabel(quantity, fontsize=9)
    axes[-1, 0].set_xlabel("time (s)")
    what = "Motor neuron outputs" if unit else "Joint target angles commanded by the controller" if target else "Motor outputs"
    shown = f"first {seconds:g} s of {traj.end_time:g} s" if keep.sum() < len(t) else f"{traj.end_time:g} s"
    axes[0, 0].set_title(f"{what} ({traj.body_name}, {shown}); walked {walk_text(traj)}", fontsize=9)
    return save_figure(fig, path)


def _side_axis(traj: Trajectory) -> np.ndarray:
    """Unit vector on the ground along which the side views look: the walker's initial facing."""
    f = np.asarray(traj.start_facing, float)
    return f / max(float(np.linalg.norm(f)), 1e-12)


def _side_key(ax, *, com: bool = False) -> None:
    """The key of a side view: left and right limbs (and the centre-of-mass line)."""
    from matplotlib.lines import Line2D

    handles = [Line2D([], [], color=LEFT, lw=3, label="left leg"), Line2D([], [], color=RIGHT, lw=3, label="right leg"),
               Line2D([], [], color=OTHER, lw=3, label="trunk")]
    if com:
        handles.append(Line2D([], [], color="black", lw=0.8, label="centre of mass"))
    ax.legend(handles=handles, frameon=False, fontsize=7, loc="upper left", bbox_to_anchor=(1.0, 1.0))


def _color(name: str) -> str:
    n = name.lower()
    return LEFT if "left" in n else RIGHT if "right" in n else OTHER


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


def motion_sequence(traj: Trajectory, path: str | Path, *, frames: int = 12, columns: int = 4, every: float = 0.2) -> Path:
    """The walker in side view every ``every`` s from the start (``frames`` frames), left to right, top to
    bottom (Fig. 8).  Each panel's horizontal axis is the position along the initial facing (m), so its
    tick labels show the progress (negative: backwards)."""
    plt = pyplot()
    step = max(1, int(round(every / traj.dt)))
    idx = np.arange(0, len(traj.state_time), step)[:frames]
    every = step * traj.dt
    rows_n = int(np.ceil(len(idx) / columns))
    axis, parts = _side_axis(traj), shapes(traj.model)
    fig, axes = plt.subplots(rows_n, columns, figsize=(2.4 * columns, 2.4 * rows_n + 0.6), squeeze=False, sharey=True)
    centres = traj.com[idx, :2] @ axis
    h, z = _side_points(traj, parts, idx, axis)
    height = max(float(z.max()) + 0.1, 0.5)
    half = max(0.75, float(np.abs(h - centres[:, None]).max()) + 0.1)
    for ax in axes.ravel()[len(idx):]:
        ax.axis("off")
    for ax, k, centre in zip(axes.ravel(), idx, centres):
        ax.axhline(0.0, color="0.5", lw=1.0)
        _draw_walker(ax, traj, parts, np.array([k]), axis)
        ax.set_xlim(centre - half, centre + half)
        ax.set_ylim(-0.05, height)
        ax.set_aspect("equal")
        ax.tick_params(labelsize=7)
        ax.set_title(f"t = {traj.state_time[k]:.2f} s", fontsize=8)
    fig.supxlabel("position along the initial facing (m)", fontsize=9)
    fig.supylabel("height (m)", fontsize=9)
    _side_key(axes[0, -1])
    fig.suptitle(f"Motion sequence, side view, every {every:g} s ({traj.body_name}); walked {walk_text(traj)}", fontsize=10)
    return save_figure(fig, path)


def stick_figure(traj: Trajectory, path: str | Path, *, every: float = 0.1, max_figures: int = 40, span: float = 4.0) -> Path:
    """Stick figures every ``every`` s (at most ``max_figures``), drawn where they were along the initial
    facing (Taga Figs. 5, 9), from the start until the walker is ``span`` m from it: the figure's size does
    not grow with the episode."""
    plt = pyplot()
    axis, parts = _side_axis(traj), shapes(traj.model)
    h = traj.com[:, :2] @ axis
    far = np.flatnonzero(np.abs(h - h[0]) > span)
    last = int(far[0]) if far.size else len(h) - 1
    step = max(1, int(round(every / traj.dt)), int(np.ceil((last + 1) / max_figures)))
    every = step * traj.dt
    rows = np.arange(0, last + 1, step)
    fig, ax = plt.subplots(figsize=(min(14.0, max(6.0, 2.0 + 2.0 * float(np.ptp(h[: last + 1])))), 3.4))
    ax.axhline(0.0, color="0.5", lw=1.0)
    _draw_walker(ax, traj, parts, rows, axis, alpha=0.45)
    ax.plot(h[: last + 1], traj.com[: last + 1, 2], color="black", lw=0.8)
    ax.set_aspect("equal")
    ax.set_xlabel("position along the initial facing (m; negative = backwards)")
    ax.set_ylabel("height (m)")
    shown = f"first {traj.state_time[last]:.1f} s of {traj.end_time:g} s" if last < len(h) - 1 else f"{traj.end_time:g} s"
    ax.set_title(f"Stick figure every {every:g} s ({traj.body_name}, {shown}); walked {walk_text(traj)}", fontsize=9)
    _side_key(ax, com=True)
    return save_figure(fig, path)


def ground_trajectory(trajs: Trajectory | list[Trajectory], path: str | Path, *, labels: list[str] | None = None) -> Path:
    """The walker's path on the ground plane, start (circle), end (square, x if it fell), sources (star) (Fig. 12)."""
    from matplotlib.lines import Line2D

    plt = pyplot()
    trajs = [trajs] if isinstance(trajs, Trajectory) else list(trajs)
    fig, ax = plt.subplots(figsize=(6.4, 5.2))
    colors = plt.get_cmap("tab10").colors
    every = np.concatenate([tr.planar for tr in trajs])
    scale = max(float(np.ptp(every[:, 0])), float(np.ptp(every[:, 1])), 0.5)
    for i, tr in enumerate(trajs):
        xy, c = tr.planar, colors[i % 10]
        ax.plot(xy[:, 0], xy[:, 1], lw=1.5, color=c, label=labels[i] if labels else f"path: {walk_text(tr)}")
        ax.plot(*xy[0], "o", color=c)
        ax.plot(*xy[-1], "x" if tr.fell else "s", color=c, ms=8)
        f = _side_axis(tr) * 0.12 * scale
        ax.annotate("", xy=xy[0] + f, xytext=xy[0], arrowprops=dict(arrowstyle="->", color=c, lw=1.5))
        ax.plot(*(xy[0] + f), alpha=0.0)  # keep the arrow inside the axes
        if tr.source is not None:  # this walker's source, in its colour
            ax.plot(*tr.source[-1], "*", color=c, ms=15, mec="black", mew=0.5)
    keys = [Line2D([], [], marker="o", ls="", color="0.3", label="start"),
            Line2D([], [], marker=r"$\rightarrow$", ls="", color="0.3", ms=12, label="initial facing"),
            Line2D([], [], marker="s", ls="", color="0.3", label="end, stayed up"),
            Line2D([], [], marker="x", ls="", color="0.3", label="end, fell")]
    if any(t.source is not None for t in trajs):
        keys.append(Line2D([], [], marker="*", ls="", color="0.5", mec="black", ms=12, label="sound source"))
    lines, names = ax.get_legend_handles_labels()
    ax.legend(handles=lines + keys, frameon=False, fontsize=7, loc="upper left", bbox_to_anchor=(1.0, 1.0))
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.grid(alpha=0.3)
    if float(np.ptp(every[:, 1])) < 0.05 * scale:  # a planar walker: no empty square around a line
        ax.set_ylim(-0.1 * scale, 0.1 * scale)
    else:
        ax.set_aspect("equal", adjustable="datalim")
    if len(trajs) > 1:
        ax.set_title(f"Paths on the ground toward each sound source ({trajs[0].body_name})", fontsize=10)
    else:
        ax.set_title(f"Path on the ground ({trajs[0].body_name}, {trajs[0].end_time:g} s)", fontsize=10)
    return save_figure(fig, path)


def replay_figures(traj: Trajectory, out_dir: str | Path, *, history: dict[str, np.ndarray] | None = None,
                   fitness_ylabel: str = "fitness: distance from the start (m)") -> list[Path]:
    """Every figure of one replay (and the fitness graph if a history is given) into ``out_dir``."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = []
    if history is not None:
        paths.append(fitness_graph(history, out / "fitness.png", ylabel=fitness_ylabel))
    paths.append(motor_activations(traj, out / "motor_neurons.png"))
    paths.append(motion_sequence(traj, out / "motion_sequence.png"))
    paths.append(stick_figure(traj, out / "stick_figure.png"))
    paths.append(ground_trajectory(traj, out / "ground_trajectory.png"))
    return paths


def steering_neuron(trajs: list[Trajectory], path: str | Path, *, neuron: int = 3, labels: list[str] | None = None,
                    seconds: float | None = 10.0) -> Path:
    """One motor output per presentation (Fig. 13: right hip sagittal = neuron 4, index 3): a neuron's
    output in [0, 1], or the joint target (rad) a controller such as the balance controller commands.
    ``seconds``: the first this many seconds (default 10, so that the rhythm stays visible; None: all)."""
    plt = pyplot()
    fig, axes = plt.subplots(len(trajs), 1, figsize=(7.0, 1.2 + 1.3 * len(trajs)), sharex=True, squeeze=False)
    name = trajs[0].actuator_names[neuron] if neuron < len(trajs[0].actuator_names) else f"neuron {neuron + 1}"
    unit, target, quantity = _motor_quantity(trajs[0])
    for ax, tr, label in zip(axes[:, 0], trajs, labels or [None] * len(trajs)):
        keep = tr.command_time <= seconds if seconds else np.ones(len(tr.command_time), bool)
        ax.plot(tr.command_time[keep], tr.neurons[keep, neuron], color="black", lw=1.0)
        if unit:
            ax.set_ylim(-0.05, 1.05)
        ax.set_ylabel(quantity, fontsize=8)
        ax.set_title(label or "", fontsize=9)
    axes[-1, 0].set_xlabel("time (s)")
    shown = f", first {seconds:g} s" if seconds and trajs[0].command_time[-1] > seconds else ""
    what = f"Motor neuron {neuron + 1} ({name})" if unit else f"{name} {'target' if target else 'command'}"
    fig.suptitle(f"{what} per sound source{shown}", fontsize=10)
    return save_figure(fig, path)


def steering_figures(trajs: list[Trajectory], out_dir: str | Path) -> list[Path]:
    """Fig. 12 (paths toward every source) and Fig. 13 (right-hip sagittal neuron per source)."""
    out = Path(out_dir)
    labels = [f"toward source {i + 1} at ({tr.source[0, 0]:g}, {tr.source[0, 1]:g}) m" for i, tr in enumerate(trajs)]
    return [
        ground_trajectory(trajs, out / "steering_trajectories.png", labels=labels),
        steering_neuron(trajs, out / "steering_neuron.png", labels=labels),
    ]
