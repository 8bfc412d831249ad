"""The walker seen from the side (along its initial facing), as the motion and stick figures draw it: limbs coloured
by leg, a key naming the bodies between them, and one stride of steady walking to show."""

from __future__ import annotations

import numpy as np

from ..geometry import Shape, body_names, segment
from ..trajectory import Trajectory

#: matplotlib colours of the left and right legs and of the bodies between them
LEFT, RIGHT, OTHER = "tab:blue", "tab:red", "0.25"


def _side_axis(traj: Trajectory) -> np.ndarray:
    """Unit vector on the ground along which the side views look: the walker's initial facing."""
    f = np.asarray(traj.start_facing, float)
    return f / max(float(np.linalg.norm(f)), 1e-12)


def _middle(traj: Trajectory, parts: list[Shape]) -> str:
    """The bodies drawn in neither leg's colour, by their model names (``pelvis`` for Reil's, ``trunk`` for Taga's)."""
    names = body_names(traj.model)
    found = dict.fromkeys(names[s.body] for s in parts if s.body != 0 and _color(names[s.body] + s.name) == OTHER)
    return ", ".join(found) or "other"


def _side_key(ax, traj: Trajectory, parts: list[Shape], *, com: bool = False) -> None:
    """The key of a side view: left and right limbs, the bodies between them by name (and the centre-of-mass line)."""
    from matplotlib.lines import Line2D

    handles = [Line2D([], [], color=LEFT, lw=3, label="left leg"), Line2D([], [], color=RIGHT, lw=3, label="right leg"),
               Line2D([], [], color=OTHER, lw=3, label=_middle(traj, parts))]
    if com:
        handles.append(Line2D([], [], color="black", lw=0.8, label="centre of mass"))
    ax.legend(handles=handles, frameon=False, fontsize=7, loc="upper left", bbox_to_anchor=(1.0, 1.0))


def _color(name: str) -> str:
    n = name.lower()
    return LEFT if "left" in n else RIGHT if "right" in n else OTHER


def _side_points(traj: Trajectory, parts: list[Shape], rows: np.ndarray,
                 axis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
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


def _draw_walker(ax, traj: Trajectory, parts: list[Shape], rows: np.ndarray, axis: np.ndarray, offset: float = 0.0,
                 alpha: float = 1.0) -> None:
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


def steady_stride(traj: Trajectory, after: float = 10.0) -> tuple[float, float, str]:
    """(start s, end s, what it is) of one stride of steady walking: from the first left-foot touchdown after
    ``after`` s to the next; without two such touchdowns (no touch sensors, a fall, no steps) the 2.4 s
    from ``after`` (or the episode's last 2.4 s)."""
    left = [k for k, name in enumerate(traj.touch_names) if "left" in name.lower()]
    if left and traj.n_ticks:
        down = traj.touch[:, left[0]] > 0
        rises = traj.tick_time[1:][down[1:] & ~down[:-1]]
        rises = rises[rises >= after]
        if len(rises) >= 2:
            return float(rises[0]), float(rises[1]), "one stride (left touchdown to left touchdown)"
    end = float(traj.state_time[-1])
    t0 = max(0.0, min(after, end - 2.4))
    return t0, min(end, t0 + 2.4), "no stride found: 2.4 s"
