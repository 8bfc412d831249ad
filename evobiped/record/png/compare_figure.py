"""A comparison's figure (``evobiped compare``): the success rate of each configuration against the episodes its
runs evaluated, with the Wilson 95 % interval as a band, from the runs' checkpoints re-evaluated on fresh noise."""

from __future__ import annotations

from pathlib import Path

from .figures import pyplot, save_figure


def success_figure(results: dict, path: str | Path) -> Path:
    """success.png of ``results`` (:func:`evobiped.usecases.compare_report.comparison_results`'s)."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(7.0, 4.2))
    for c in results["configurations"]:
        x = [p["episodes"] for p in c["curve"]]
        rate = [p["successes"] / p["runs"] for p in c["curve"]]
        line, = ax.plot(x, rate, marker="o", label=f"{c['name']} ({c['runs']} runs)")
        ax.fill_between(x, [p["wilson"][0] for p in c["curve"]], [p["wilson"][1] for p in c["curve"]],
                        color=line.get_color(), alpha=0.2, linewidth=0)
    ax.set_xlim(0, results["budget"] * 1.02)
    ax.set_ylim(-0.02, 1.02)
    ax.set_xlabel("episodes evaluated per run")
    ax.set_ylabel("success rate (Wilson 95 %)")
    ax.set_title(f"success ({results['success']}) on {results['trials']} fresh presentations per run", fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="best")
    return save_figure(fig, path)
