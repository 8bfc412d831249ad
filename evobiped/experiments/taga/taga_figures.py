"""Taga et al. 1991 figures as PNG: stick figures (Figs. 5, 8, 9), neuron activity
(Fig. 6), bifurcation diagrams (Fig. 11).

Inputs are plain arrays from :class:`evobiped.experiments.taga.walking.Trace`
(``t`` (T,), ``hip`` (T, P, 2) as x and height above terrain, ``hip_z`` (T, P),
``knee``/``ankle`` (T, P, 2, 2) with legs (right, left) and (x, y), ``contact``
(T, P, 2), ``u`` (T, P, 12)).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ...record.png.figures import pyplot, save_figure

LEG_COLOURS = ("tab:red", "tab:blue")  # right, left


def _draw_sticks(ax, tr: dict, p: int, idx: np.ndarray, terrain=None, shift: float = 0.0) -> None:
    for k, i in enumerate(idx):
        hx, hz = tr["hip"][i, p, 0], tr["hip_z"][i, p]
        dx = shift * k
        for leg in (1, 0):  # left behind, right in front
            kx, ky = tr["knee"][i, p, leg]
            ax_, ay_ = tr["ankle"][i, p, leg]
            ax.plot([hx + dx, kx + dx, ax_ + dx], [hz, ky, ay_], color=LEG_COLOURS[leg], lw=0.8, alpha=0.8)
            if tr["contact"][i, p, leg]:
                ax.plot(ax_ + dx, ay_, "k.", ms=3)
        ax.plot(hx + dx, hz, "o", color="0.2", ms=2.5)
    x = np.linspace(tr["ankle"][idx, p, :, 0].min() - 0.3 + 0, tr["ankle"][idx, p, :, 0].max() + 0.3 + shift * len(idx),
                    200)
    ax.plot(x, terrain(x) if terrain is not None else 0 * x, color="0.4", lw=1.2)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m): forward, the walker's initial facing")
    ax.set_ylabel("height (m)")


def _stick_key(ax, marks: bool = False) -> None:
    from matplotlib.lines import Line2D

    handles = [Line2D([], [], color=LEG_COLOURS[1], lw=1.5, label="left leg"),
               Line2D([], [], color=LEG_COLOURS[0], lw=1.5, label="right leg"),
               Line2D([], [], marker="o", ls="", color="0.2", ms=4, label="hip"),
               Line2D([], [], marker=".", ls="", color="k", label="foot on the ground")]
    if marks:
        handles.append(Line2D([], [], marker="v", ls="", color="tab:green", label="push"))
    ax.legend(handles=handles, frameon=False, fontsize=7, loc="upper left", bbox_to_anchor=(1.0, 1.0))


def taga_stick_figure(path: Path, tr: dict, *, p: int = 0, t0: float = 0.0, t1: float = 10.0, every: float = 0.1,
                 title: str = "", terrain=None, marks: list[float] | None = None) -> Path:
    """Fig. 5A/9A-style: the walker traced every ``every`` s over [t0, t1]."""
    t = tr["t"]
    idx = _every(t, t0, t1, every)
    span = float(np.ptp(tr["hip"][idx, p, 0])) + 1.5
    fig, ax = pyplot().subplots(figsize=(min(16, max(8, 1.2 * span)), 3.2))
    _draw_sticks(ax, tr, p, idx, terrain)
    for m in marks or []:  # dots where a push acted (Fig. 7)
        i = int(np.searchsorted(t, m))
        ax.plot(tr["hip"][i, p, 0], tr["hip_z"][i, p] + 0.15, "v", color="tab:green", ms=7)
    ax.set_title(title)
    _stick_key(ax, marks=bool(marks))
    return _save(fig, path)


def cycle_figure(path: Path, tr: dict, start: float, end: float, *, p: int = 0, every: float = 0.02,
                 title: str = "") -> Path:
    """Fig. 5B/9B-style: one cycle traced every ``every`` s, split into the phases with
    both feet down / neither down (left panel) and one foot down (right panel)."""
    t = tr["t"]
    idx = _every(t, start, end, every)
    c = tr["contact"][idx, p]
    single = c.sum(1) == 1
    fig, axes = pyplot().subplots(1, 2, figsize=(10, 3.6), sharey=True)
    for ax, sel, name in ((axes[0], ~single, "double support / flight"), (axes[1], single, "single support")):
        if sel.any():
            _draw_sticks(ax, tr, p, idx[sel])
        ax.set_title(f"{name} ({sel.sum()} frames)")
    _stick_key(axes[1])
    fig.suptitle(title)
    return _save(fig, path)


def activity_figure(path: Path, panels: list[tuple[str, np.ndarray, np.ndarray]], names: list[str]) -> Path:
    """Fig. 6-style: each panel (title, t (T,), u (T, 12)) as 12 stacked traces."""
    fig, axes = pyplot().subplots(1, len(panels), figsize=(6 * len(panels), 7), sharey=True)
    axes = np.atleast_1d(axes)
    for ax, (title, t, u) in zip(axes, panels):
        for k in range(u.shape[1]):
            ax.plot(t, u[:, k] / 10 - 1.2 * k, lw=0.8, color="k")
        ax.set_yticks(-1.2 * np.arange(len(names)), names)
        x0 = t[0] - 0.02 * (t[-1] - t[0])  # amplitude scale bar: 10 units of u
        ax.plot([x0, x0], [0.4, -0.6], color="tab:red", lw=2.5, clip_on=False)
        ax.text(x0, -0.1, "10 ", color="tab:red", ha="right", va="center", fontsize=8)
        ax.set_xlabel("time (s)")
        ax.set_title(f"{title}\nneuron inner state u (red bar: 10 units)", fontsize=10)
    return _save(fig, path)


def bifurcation_figure(path: Path, up: list[dict], down: list[dict], *, title: str = "") -> Path:
    """Fig. 11: stride length, cycle duration and speed against u0, sweeping up and down.

    Squares: walking, diamonds: running (filled: sweep up, open: sweep down); falls
    are omitted."""
    keys = (("stride_length", "stride length (m)"), ("cycle_duration", "stride cycle duration (s)"),
            ("speed", "speed (m/s)"))
    fig, axes = pyplot().subplots(1, 3, figsize=(14, 4))
    for ax, (k, label) in zip(axes, keys):
        for rows, fill, dname in ((up, True, "up"), (down, False, "down")):
            for gait, marker in (("walk", "s"), ("run", "D")):
                sel = [r for r in rows if r["gait"] == gait]
                if sel:
                    ax.plot([r["u0"] for r in sel], [r[k] for r in sel], marker, ls="none", ms=6,
                            mfc=("tab:blue" if gait == "walk" else "tab:red") if fill else "none",
                            mec="tab:blue" if gait == "walk" else "tab:red", label=f"{gait} ({dname})")
        ax.set_xlabel("u0")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8)
    fig.suptitle(title)
    return _save(fig, path)


def _every(t: np.ndarray, t0: float, t1: float, every: float) -> np.ndarray:
    marks = np.arange(t0, t1 + 1e-9, every)
    idx = np.searchsorted(t, marks)
    return np.unique(idx[idx < len(t)])


def _save(fig, path: Path) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.tight_layout()
    return save_figure(fig, path, dpi=110)
