"""summary.json: what a complete run says of itself, written once its last generation is committed (and by a resume
of a complete run whose summary is missing or disagrees with the checkpoint).

::

    {"evobiped": "0.x", "generations": 120, "best": {...}, "wall_seconds": 812.3, "evaluations": 6000,
     "stable": true, "best_walk": {"distance": ..., "direction_deg": ...}, "stopped_early": false}

``best``: the run's best (fitness, fell, end time in s, seed, generation, terms); ``wall_seconds``: the evaluation's
wall-clock time over all sessions (s, rounded to ms); ``best_walk``: the best walker's walk in the nominal episode;
``stopped_early`` only in runs with a stopping rule (true when it held), ``lost`` only in runs with a lost-run rule
(``[restart]``: each lost phase's generation, phase and action).
"""

from __future__ import annotations

from pathlib import Path
from typing import Callable

from ...core.errors import UserError
from ...core.fileio import json_text, read_json, write_json
from .history_file import column
from .layout import SUMMARY


def summary_table(*, version: str, generations: int, best: dict | None, wall_seconds: float, history: list[list],
                  best_walk: dict | None, stopped_early: bool | None = None, lost: list | None = None) -> dict:
    """summary.json's fields: ``history`` the committed rows (its evaluations are summed); ``stopped_early`` None when
    the run has no stopping rule (no such field); ``lost`` (each lost phase: generation, phase, what was done) None
    when it has no lost-run rule (no such field)."""
    out = {
        "evobiped": version,
        "generations": generations,
        "best": best,
        "wall_seconds": round(wall_seconds, 3),
        "evaluations": int(sum(column(history, "evaluations"))),
        "stable": best is not None and not best["fell"],
        "best_walk": best_walk,
    }
    if stopped_early is not None:
        out["stopped_early"] = stopped_early
    if lost is not None:
        out["lost"] = lost
    return out


def agreeing_summary(directory: Path, table_with: Callable[[dict | None], dict]) -> dict | None:
    """``directory``'s summary.json when it is exactly ``table_with(its best_walk)`` (the walk is kept: it costs an
    episode); None when it is missing, unreadable or disagrees."""
    path = directory / SUMMARY
    try:
        old = read_json(path, what="summary") if path.exists() else None
        if isinstance(old, dict) and "best_walk" in old and path.read_text() == json_text(table_with(old["best_walk"])):
            return old
    except UserError:
        pass
    return None


def write_summary_file(directory: Path, table: dict) -> None:
    """Write ``directory``'s summary.json (atomically)."""
    write_json(directory / SUMMARY, table)
