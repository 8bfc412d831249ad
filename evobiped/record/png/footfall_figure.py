"""A footfall diagram: stance bars per foot over time (as in the G3 gait diagrams), titled with the gait's numbers."""

from __future__ import annotations

import io
from pathlib import Path

from ...core.fileio import atomic_write


def footfall_figure(report: dict, path: Path, *, title: str = "", window: float = 4.0) -> None:
    """Draw ``report``'s (:func:`evobiped.analysis.gait_report.gait_report`) debounced stance episodes per foot: the
    whole measured time on top, its last ``window`` s below; written atomically to ``path`` (PNG)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ...analysis.gait_report import gait_line

    feet = report["feet"]
    end = report["time_up"]
    fig, axes = plt.subplots(2, 1, figsize=(9, 3.6), gridspec_kw={"height_ratios": [1, 1]})
    colours = ("#2b6cb0", "#c05621")
    for ax, (lo, hi) in zip(axes, ((0.0, end), (max(0.0, end - window), end))):
        for i, foot in enumerate(feet):
            bars = [(a, b - a) for a, b in report["stance"][foot] if b > lo and a < hi]
            ax.broken_barh(bars, (len(feet) - 1 - i + 0.15, 0.7), color=colours[i % 2])
        ax.set_yticks([len(feet) - 1 - i + 0.5 for i in range(len(feet))], [f"{f} foot" for f in feet])
        ax.set_xlim(lo, hi)
        ax.set_ylim(0, len(feet))
        ax.grid(axis="x", alpha=0.3)
    axes[1].set_xlabel("time (s); bars: the foot on the ground (stance)")
    verdict = "walks" if report.get("walks") else "does not walk: " + ", ".join(report.get("failed", []))
    fig.suptitle(f"{title}: {verdict}\n{gait_line(report)}", fontsize=9)
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110)
    plt.close(fig)
    atomic_write(path, buf.getvalue())
