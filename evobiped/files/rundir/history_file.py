"""history.csv: one row per generation (HISTORY_COLUMNS, then the best's terms and the run's further columns), its
reader and writer."""

from __future__ import annotations

import csv
import io
from pathlib import Path

import numpy as np

from ...core.errors import UserError
from ...core.fileio import atomic_write

HISTORY_COLUMNS = ("generation", "best", "mean", "median", "worst", "evaluations", "falls", "unstable", "wall_seconds")
#: history.csv's further columns: the best individual's task terms (``best_distance``, ...; the mean over its
#: presentations), one per term; nan where undefined, or for generations of a checkpoint written before terms were kept
TERM_PREFIX = "best_"
#: columns holding counts (whole numbers >= 0) and fitness values (a number or -inf)
_COUNTS = ("generation", "evaluations", "falls", "unstable")
_FITNESS = ("best", "mean", "median", "worst")


def _term_names(terms: list[dict] | None) -> list[str]:
    return list(dict.fromkeys(k for t in terms or () for k in t))


def history_columns(rows: list[list], terms: list[dict] | None = None,
                    extra: list[dict] | None = None) -> dict[str, np.ndarray]:
    """History rows (HISTORY_COLUMNS each), the best's terms per generation (name -> value) and further columns per
    generation (``extra``: name -> value, e.g. a curriculum's phase) -> ``{column: (n_generations,) array}``, as
    :func:`read_history` gives (a missing value: NaN)."""
    out = {c: np.array([float(r[i]) for r in rows]) for i, c in enumerate(HISTORY_COLUMNS)}
    for prefix, table in ((TERM_PREFIX, terms), ("", extra)):
        padded = [*(table or ()), *[{}] * (len(rows) - len(table or ()))]
        for name in _term_names(table):
            out[prefix + name] = np.array([np.nan if t.get(name) is None else float(t[name]) for t in padded])
    return out


def column(rows: list[list], name: str) -> list:
    """One column of history rows, e.g. ``column(rows, "evaluations")``."""
    i = HISTORY_COLUMNS.index(name)
    return [r[i] for r in rows]


def read_history(path: str | Path) -> dict[str, np.ndarray]:
    """``history.csv`` -> ``{column: (n_generations,) float array}``; needs generation/best/mean (UserError
    otherwise)."""
    path = Path(path)
    if not path.is_file():
        raise UserError(f"history file not found: {path}")
    try:
        with path.open(newline="") as f:
            rows = list(csv.DictReader(f))
    except (UnicodeDecodeError, csv.Error) as exc:
        raise UserError(f"{path} is not a run history ({exc})") from None
    if not rows or not {"generation", "best", "mean"} <= set(rows[0]):
        raise UserError(f"{path} is not a run history (needs columns generation, best, mean)")
    try:
        out = {k: np.array([float(r[k]) for r in rows]) for k in rows[0] if k is not None}
    except (TypeError, ValueError) as exc:
        raise UserError(f"{path}: not a number in the history ({exc})") from None
    for name, values in out.items():
        bad = np.isnan(values) | (values == np.inf) if name in _FITNESS else ~np.isfinite(
            values) if name in HISTORY_COLUMNS else None
        if name in _COUNTS:
            bad = bad | (values < 0) | (values != np.round(values))
        if bad is not None and bad.any():
            row = int(np.flatnonzero(bad)[0])
            raise UserError(f"{path}: {name} of row {row + 1} is {values[row]:g}, not a "
                            f"{'count' if name in _COUNTS else 'fitness' if name in _FITNESS else 'number'}")
    if not np.array_equal(out["generation"], np.arange(len(rows))):
        raise UserError(f"{path}: the generations must be numbered 0, 1, 2, ... one row each")
    return out


def history_text(rows: list[list], terms: list[dict] | None = None, extra: list[dict] | None = None) -> str:
    """history.csv's exact content for ``rows`` (one per generation, HISTORY_COLUMNS), the best's terms
    per generation (name -> value; the TERM_PREFIX columns) and further columns (``extra``, unprefixed)."""
    names, more = _term_names(terms), _term_names(extra)
    padded = [*(terms or ()), *[{}] * (len(rows) - len(terms or ()))]
    padded_more = [*(extra or ()), *[{}] * (len(rows) - len(extra or ()))]
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow([*HISTORY_COLUMNS, *(TERM_PREFIX + n for n in names), *more])
    w.writerows([*r, *("nan" if t.get(n) is None else t[n] for n in names),
                 *("nan" if x.get(n) is None else x[n] for n in more)]
                for r, t, x in zip(rows, padded, padded_more))
    return buf.getvalue()


def write_history(path: Path, rows: list[list]) -> None:
    atomic_write(path, history_text(rows))

