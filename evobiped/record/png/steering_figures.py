"""The steering experiment's figures (Reil & Husbands Figs. 12-13), one colour per sound source.

* :func:`steering_neuron` - how the walker steers toward each source (Fig. 13's question);
* :func:`steering_figures` - Fig. 12 (paths toward every source, :func:`.figures.ground_trajectory`) and Fig. 13.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .figures import _title, ground_trajectory, pyplot, save_figure
from .motor_labels import _motor_quantity
from ..trajectory import Trajectory


def _travel_heading(traj: Trajectory, window: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """(times s, direction of travel over the last ``window`` s relative to the initial facing, deg) of ``traj``."""
    k = max(1, int(round(window / traj.dt)))
    d = traj.planar[k:] - traj.planar[:-k]
    f = traj.start_facing
    ang = np.degrees(np.arctan2(f[0] * d[:, 1] - f[1] * d[:, 0], d @ f))
    return traj.state_time[k:], ang


def steering_neuron(trajs: list[Trajectory], path: str | Path, *, neuron: int | None = None,
                    labels: list[str] | None = None, seconds: float | None = None, who: str = "") -> Path:
    """How the walker steers, one colour per presentation (sound source), as in Fig. 12 (Fig. 13's question):
    the direction it travels relative to its initial facing (deg, over 1 s), the ear signal it hears if it
    has ears, and what the controller does differently: with two sources every output's mean after the first
    2 s, source 1 minus source 2 (the bias that steers), else one output per source overlaid, as
    commanded and as its 1 s running mean: ``neuron`` (the paper's Fig. 13: right hip sagittal = neuron 4, index 3), by
    default the one whose running means differ most between the sources.  ``seconds``: the motor output's first this
    many seconds (default None: all; 10 keeps the rhythm visible)."""
    plt = pyplot()
    colors = plt.get_cmap("tab10").colors
    labels = labels or [f"presentation {j + 1}" for j in range(len(trajs))]
    k = max(1, int(round(1.0 / trajs[0].dt)))  # the running mean over 1 s: the bias that steers, not the rhythm

    def running(x):
        return np.convolve(x, np.ones(k) / k, mode="valid") if len(x) >= k else x

    if neuron is None:  # the output whose 1 s running means differ most between the presentations: where steering acts
        n = min(len(tr.command_time) for tr in trajs)
        means = np.stack([[running(tr.neurons[:n, i]) for i in range(tr.n_motor)] for tr in trajs])  # (S, M, n')
        neuron = int(np.argmax(np.ptp(means, axis=0).mean(axis=-1)))
    name = trajs[0].actuator_names[neuron] if neuron < len(trajs[0].actuator_names) else f"output {neuron + 1}"
    unit, target, quantity = _motor_quantity(trajs[0])
    hearing = all("sound" in tr.sensors for tr in trajs)
    fig, axes = plt.subplots(3 if hearing else 2, 1, figsize=(7.5, 7.5 if hearing else 5.4), squeeze=False)
    axes = axes[:, 0]
    for j, (tr, label) in enumerate(zip(trajs, labels)):
        c = colors[j % 10]
        t, ang = _travel_heading(tr)
        axes[0].plot(t, ang, color=c, lw=1.3, label=label)
        if hearing:
            axes[1].plot(tr.tick_time, tr.sensors["sound"][:, 0], color=c, lw=1.0)
        if len(trajs) != 2:
            keep = tr.command_time <= seconds if seconds else np.ones(len(tr.command_time), bool)
            axes[-1].plot(tr.command_time[keep], tr.neurons[keep, neuron], color=c, lw=0.6, alpha=0.35)
            axes[-1].plot(running(tr.command_time), running(tr.neurons[:, neuron]), color=c, lw=2.0)
    if len(trajs) == 2:  # two sources: every output's mean over the walk (after the first 2 s), source 1 minus source 2
        names = [trajs[0].actuator_names[i] if i < len(trajs[0].actuator_names) else f"output {i + 1}"
                 for i in range(trajs[0].n_motor)]
        # the start-up aside (short episodes: their second half)
        after = min(2.0, 0.5 * min(float(tr.command_time[-1]) for tr in trajs))
        bias = [1000 * (tr0.neurons[tr0.command_time >= after, i].mean()
                        - tr1.neurons[tr1.command_time >= after, i].mean())
                for tr0, tr1 in [trajs] for i in range(trajs[0].n_motor)]
        bars = axes[-1].bar(np.arange(len(names)), bias, color="0.5")
        axes[-1].bar_label(bars, fmt="%+.1f", fontsize=7)
        axes[-1].set_xticks(np.arange(len(names)), names, fontsize=7)
        axes[-1].axhline(0.0, color="0.6", lw=0.8)
    axes[0].axhline(0.0, color="0.6", lw=0.8)
    axes[0].set_ylabel("direction of travel from\nthe initial facing (deg)", fontsize=8)
    axes[0].set_xlabel("time (s)", fontsize=8)
    axes[0].legend(frameon=False, fontsize=7, loc="upper left", bbox_to_anchor=(1.0, 1.0))
    if hearing:
        axes[1].set_ylabel("ear signal s", fontsize=8)
        axes[1].set_xlabel("time (s)", fontsize=8)
    if len(trajs) == 2:
        unit_text = "(1/1000)" if unit else "(mrad)" if target else "(1/1000 of the unit)"
        axes[-1].set_ylabel(f"mean after {after:g} s, source 1\nminus source 2 {unit_text}", fontsize=8)
        axes[-1].set_xlabel("motor neuron" if unit else "joint target" if target else "output", fontsize=8)
        what = "each output's bias between the two sources"
    else:
        axes[-1].set_ylabel(f"{name}\n{quantity}", fontsize=8)
        axes[-1].set_xlabel("time (s)" + (f", first {seconds:g} s" if seconds else "")
                            + "; thin: as commanded, thick: 1 s running mean",
                            fontsize=8)
        what = f"motor neuron {neuron + 1} ({name})" if unit else f"{name} {'target' if target else 'command'}"
    if unit and len(trajs) != 2:
        axes[-1].set_ylim(-0.05, 1.05)
    for ax in axes:
        ax.tick_params(labelsize=7)
        ax.grid(alpha=0.3)
    fig.suptitle(_title(f"Steering toward each source: direction of travel{', ear signal' if hearing else ''} and "
                        f"{what}", who, trajs[0]), fontsize=9)
    fig.tight_layout()
    return save_figure(fig, path)


def steering_figures(trajs: list[Trajectory], out_dir: str | Path, *, who: str = "") -> list[Path]:
    """Fig. 12 (paths toward every source) and Fig. 13 (how it steers toward each)."""
    out = Path(out_dir)
    labels = [f"toward source {i + 1} at ({tr.source[0, 0]:g}, {tr.source[0, 1]:g}) m" for i, tr in enumerate(trajs)]
    return [
        ground_trajectory(trajs, out / "steering_trajectories.png", labels=labels, who=who),
        steering_neuron(trajs, out / "steering_neuron.png", labels=labels, who=who),
    ]
