"""A study's results: per condition the success rate (Wilson 95 %), the distances of stable and unstable best
walkers and the wall time (:func:`summarize`), written as runs.csv, table.csv/.md/.json and the two figures
(:func:`write_results`; the study directory: :mod:`.study`)."""

from __future__ import annotations

import csv
import io
from pathlib import Path

from ... import __version__
from ...files import rundir
from ...core.fileio import atomic_write, write_json
from .stats import histogram_edges, mean_std, wilson_interval
from .study import StudyConfig, run_dir


def summarize(outcomes: list[dict], conditions: tuple[str, ...]) -> list[dict]:
    """One row per condition: counts, success rate with Wilson 95 % interval, distances, wall time."""
    rows = []
    for c in conditions:
        runs = [o for o in outcomes if o["condition"] == c]
        stable = [o["distance"] for o in runs if not o["fell"]]
        unstable = [o["distance"] for o in runs if o["fell"]]
        n, k = len(runs), len(stable)
        lo, hi = wilson_interval(k, n)
        sm, ss = mean_std(stable)
        um, us = mean_std(unstable)
        rows.append({
            "condition": c,
            "runs": n,
            "stable": k,
            "success_rate": k / n if n else float("nan"),
            "ci95_low": lo,
            "ci95_high": hi,
            "stable_mean_m": sm,
            "stable_std_m": ss,
            "unstable_mean_m": um,
            "unstable_std_m": us,
            "walks_indefinitely": sum(1 for o in runs if o["walks_indefinitely"]),
            "forward_walkers": sum(1 for o in runs if o.get("forward_walker")),
            "wall_seconds": float(sum(o["wall_seconds"] for o in runs)),
        })
    return rows


RUN_COLUMNS = ("condition", "seed", "distance", "heading_deg", "fitness", "fell", "end_time", "generation",
               "wall_seconds", "walks_indefinitely", "recheck_end_time", "forward_walker")


def _csv(rows: list[dict], columns) -> str:
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=list(columns), lineterminator="\n", extrasaction="ignore")
    w.writeheader()
    w.writerows(rows)
    return buf.getvalue()


def _fmt(x: float, spec: str = ".2f") -> str:
    return "–" if x != x else format(x, spec)


def table_markdown(rows: list[dict], recheck_seconds: float) -> str:
    lines = [
        "| condition | runs | stable (no fall in the episode) | success rate [95 % Wilson CI] | stable: distance (m) "
        f"mean ± σ | unstable: distance (m) mean ± σ | walks {recheck_seconds:g} s | forward walkers | wall time, runs "
        "summed (s) |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['condition']} | {r['runs']} | {r['stable']} | {100 * r['success_rate']:.0f} % "
            f"[{100 * r['ci95_low']:.0f}, {100 * r['ci95_high']:.0f}] | {_fmt(r['stable_mean_m'])} ± "
            f"{_fmt(r['stable_std_m'])} | {_fmt(r['unstable_mean_m'])} ± {_fmt(r['unstable_std_m'])} | "
            f"{r['walks_indefinitely']} | {r['forward_walkers']} | {r['wall_seconds']:.0f} |"
        )
    return "\n".join(lines) + "\n"


def write_results(directory: str | Path, config: StudyConfig, outcomes: list[dict]) -> list[Path]:
    """runs.csv, table.csv/.md/.json and the two figures; returns the paths written."""
    from .study_figures import distance_histograms, fitness_graphs

    d = Path(directory)
    rows = summarize(outcomes, config.condition_names)
    atomic_write(d / "runs.csv", _csv(outcomes, RUN_COLUMNS))
    atomic_write(d / "table.csv", _csv(rows, rows[0].keys()))
    atomic_write(d / "table.md", table_markdown(rows, config.recheck_seconds))
    write_json(d / "table.json", {"evobiped": __version__, "conditions": rows})
    edges = histogram_edges([o["distance"] for o in outcomes])
    histories = {c: [rundir.read_history(run_dir(d, c, k, config) / rundir.HISTORY) for k in range(config.runs)]
                 for c in config.condition_names}
    return [d / "runs.csv", d / "table.csv", d / "table.md", d / "table.json",
            distance_histograms(outcomes, config.condition_names, edges, d / "distances.png"),
            fitness_graphs(histories, d / "fitness_graphs.png",
                           seeds=[config.first_seed + k for k in range(config.runs)])]

