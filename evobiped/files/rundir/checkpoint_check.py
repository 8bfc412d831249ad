"""The checkpoint's fields checked before use: every type and range, one UserError naming the first bad field."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ...core.errors import UserError
from .history_file import _COUNTS, _FITNESS, HISTORY_COLUMNS

def _bad(field: str, why: str):
    return UserError(f"{field} {why}")


def _number(v: Any, field: str, *, integer: bool = False, low: float | None = None, allow_minus_inf: bool = False) -> float:
    ok_type = isinstance(v, int) if integer else isinstance(v, (int, float))
    if isinstance(v, bool) or not ok_type:
        raise _bad(field, f"must be {'a whole number' if integer else 'a number'}, got {v!r}")
    if not math.isfinite(v) and not (allow_minus_inf and v == -math.inf):
        raise _bad(field, f"must be finite, got {v!r}")
    if low is not None and v < low:
        raise _bad(field, f"must be >= {low:g}, got {v!r}")
    return v


#: the checkpoint's key for the optimizer's state (``OptimizerState.to_dict``); checkpoints written before it was
#: named for what it holds kept the state, the GA's or CMA-ES's, under ``ga``
OPTIMIZER_KEY, OLD_OPTIMIZER_KEY = "optimizer", "ga"


#: the checkpoint's keys for the settings the run was created with and its start genome (null: none); a checkpoint
#: that has them must have every key this version writes
SETTINGS_KEY, START_KEY = "settings", "start"


def optimizer_table(ck: dict) -> Any:
    """The optimizer's state in checkpoint ``ck`` (under ``optimizer``, or ``ga`` in an older checkpoint)."""
    return ck[OPTIMIZER_KEY] if OPTIMIZER_KEY in ck else ck[OLD_OPTIMIZER_KEY]


def validate_checkpoint(ck: Any, *, generations: int, low: np.ndarray, high: np.ndarray) -> None:
    """Check every field's type and range before use; a UserError names the first bad field (e.g. "best.fitness must be finite").

    ``generations``: the run's total; ``low``/``high`` ``(G,)``: the gene bounds.
    (The optimizer's own state is checked by its ``state_from`` and ``restore``.)
    """
    if not isinstance(ck, dict):
        raise UserError(f"expected a table of fields, got {type(ck).__name__}")
    if OPTIMIZER_KEY not in ck and OLD_OPTIMIZER_KEY not in ck:
        raise _bad(OPTIMIZER_KEY, "is missing")
    for key in ("history", "best", "wall_seconds"):
        if key not in ck:
            raise _bad(key, "is missing")
    if not isinstance(optimizer_table(ck), dict):
        raise _bad(OPTIMIZER_KEY if OPTIMIZER_KEY in ck else OLD_OPTIMIZER_KEY, "must be a table")
    history = ck["history"]
    if not isinstance(history, list):
        raise _bad("history", f"must be a list of rows, got {type(history).__name__}")
    if len(history) > generations:
        raise _bad("history", f"has {len(history)} rows for a run of {generations} generations")
    for g, row in enumerate(history):
        where = f"history[{g}]"
        if not isinstance(row, list) or len(row) != len(HISTORY_COLUMNS):
            raise _bad(where, f"must be a list of {len(HISTORY_COLUMNS)} values ({', '.join(HISTORY_COLUMNS)})")
        for name, v in zip(HISTORY_COLUMNS, row):
            if name in _COUNTS:
                _number(v, f"{where}.{name}", integer=True, low=0)
            else:
                _number(v, f"{where}.{name}", allow_minus_inf=name in _FITNESS, low=0 if name == "wall_seconds" else None)
        if row[0] != g:
            raise _bad(f"{where}.generation", f"must be {g}, got {row[0]!r}")
    _number(ck["wall_seconds"], "wall_seconds", low=0)
    best = ck["best"]
    if best is None:
        if history:
            raise _bad("best", "is null although generations were completed")
    else:
        if not isinstance(best, dict):
            raise _bad("best", f"must be a table, got {type(best).__name__}")
        for key in ("fitness", "fell", "end_time", "generation"):
            if key not in best:
                raise _bad(f"best.{key}", "is missing")
        _number(best["fitness"], "best.fitness", allow_minus_inf=True)
        if not isinstance(best["fell"], bool):
            raise _bad("best.fell", f"must be true or false, got {best['fell']!r}")
        _number(best["end_time"], "best.end_time", low=0)
        _number(best["generation"], "best.generation", integer=True, low=0)
        if best["generation"] >= len(history):
            raise _bad("best.generation", f"must be a completed generation (< {len(history)}), got {best['generation']}")
        if best["fitness"] != history[best["generation"]][1]:
            raise _bad("best.fitness", f"must be the best fitness of generation {best['generation']} in the history, got {best['fitness']!r}")
        if "seed" in best:
            _number(best["seed"], "best.seed", integer=True, low=0)
        genome = ck.get("best_genome")
        if genome is not None:
            if not isinstance(genome, list) or len(genome) != len(low):
                raise _bad("best_genome", f"must be a list of {len(low)} genes")
            for i, v in enumerate(genome):
                _number(v, f"best_genome[{i}]")
                if not low[i] <= v <= high[i]:
                    raise _bad(f"best_genome[{i}]", f"must be within the gene's bounds [{low[i]:g}, {high[i]:g}], got {v!r}")
    if SETTINGS_KEY in ck:  # written by a run that records its settings: nothing it writes may be missing
        for key in ("best_genome", "outcome", "history_terms", "best_walk", START_KEY):
            if key not in ck:
                raise _bad(key, "is missing")
        if history and len(ck["history_terms"]) != len(history):
            raise _bad("history_terms", f"must have one table per generation ({len(history)})")
        if history and not {"fell", "unstable", "end_time", "walk"} <= set(ck["outcome"] if isinstance(ck["outcome"], dict) else ()):
            raise _bad("outcome", "must hold fell, unstable, end_time and walk")
        if history and any(ck["history_terms"]) and "terms" not in ck["outcome"]:
            raise _bad("outcome.terms", "is missing")
    outcome = ck.get("outcome", {})
    if not isinstance(outcome, dict) or not set(outcome) <= {"fell", "unstable", "end_time", "terms", "walk", "previous", "parents"}:
        raise _bad("outcome", "must be a table of fell, unstable and end_time lists (and tables of terms and walk, lists of "
                              "previous and parent rows)")
    nested = {f"{k}.{n}": v for k in ("terms", "walk") if isinstance(outcome.get(k), dict) for n, v in outcome[k].items()}
    for key in ("terms", "walk"):
        if key in outcome and not isinstance(outcome[key], dict):
            raise _bad(f"outcome.{key}", "must be a table of lists")
    plain = {k: v for k, v in outcome.items() if k not in ("terms", "walk")}
    for key, vals in plain.items():
        if not isinstance(vals, list) or not all(v is None or isinstance(v, (bool, int, float)) for v in vals):
            raise _bad(f"outcome.{key}", "must be a list of numbers or booleans (null: not known)")
    entry = lambda v: v is None or (isinstance(v, (int, float)) and not isinstance(v, bool))  # noqa: E731
    for key, vals in nested.items():
        if not isinstance(vals, list) or not all(entry(v) or (isinstance(v, list) and all(map(entry, v))) for v in vals):
            raise _bad(f"outcome.{key}", "must be a list of numbers (or of lists of numbers)")
    walk = ck.get("best_walk")
    if walk is not None and not (isinstance(walk, dict) and isinstance(walk.get("distance"), (int, float))):
        raise _bad("best_walk", "must be a table with the best walker's distance, or null")
    terms = ck.get("history_terms", [])
    if not isinstance(terms, list) or len(terms) > len(history) or not all(
            isinstance(t, dict) and all(map(entry, t.values())) for t in terms):
        raise _bad("history_terms", "must be a list of tables of numbers (or nulls), at most one per generation")
