"""The run's record: checkpoint.json as one frozen, versioned value, and the one place that writes
(:meth:`RunRecord.to_dict`), checks and reads (:meth:`RunRecord.from_dict`) and upgrades it (:func:`upgrade`).

Every older format is read by one step per format, in order, to the current one (:data:`FORMAT`, written as
``format``); the formats before the key was written are told apart by the keys they lack (format: what its
checkpoint holds; in parentheses what the step to it supplies, for an older one)::

1      ``ga`` (the optimizer's state), ``history``, ``best``, ``wall_seconds``, ``outcome`` (fell, unstable, end_time)
2      and ``best_genome`` (supplied: the best generation's file's genome)
3      and ``history_terms`` (one empty table per generation), ``best_walk`` (null: not known), the outcome's
       ``terms`` and ``walk`` (not known: nulls)
4      the optimizer's state under ``optimizer`` (was ``ga``)
5      and ``settings``, ``start`` (supplied: the run's config and start genome, as the resume reads them)
6      and the outcome's ``previous`` and ``parents`` (individuals.jsonl's lineage; nothing to supply)
7      and ``generation_digests`` (null each: kept from then on)
8      and ``format`` (``"evobiped-checkpoint/8"``)

A run directory of each older format is kept under ``tests/fixtures/rundirs``.  The optimizer's state
(``optimizer``) and the run context's keys (:data:`CONTEXT_KEYS`: the running normaliser, the curriculum, the
stopping and lost-run rules' record) are their owners' tables, checked by them.
"""

from __future__ import annotations

import dataclasses
import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import numpy as np

from ...core.errors import UserError
from .history_file import _COUNTS, _FITNESS, HISTORY_COLUMNS
from .layout import generation_file

#: the format this code writes (``format``: format 8; see the module's table), read by ``read_json`` (any other
#: ``format`` is refused there, by name)
FORMAT, FORMAT_KEY = "evobiped-checkpoint/8", "format"
#: the keys of the optimizer's state (``OptimizerState.to_dict``; ``ga`` before format 4), of the settings the run
#: was created with and its start genome (null: none), and of the generation files' digests
OPTIMIZER_KEY, OLD_OPTIMIZER_KEY, SETTINGS_KEY, START_KEY, DIGESTS_KEY = "optimizer", "ga", "settings", "start", \
    "generation_digests"
#: the run context's keys (:meth:`evobiped.run.run_context.RunContext.to_dict`; none: a run without a context)
CONTEXT_KEYS = ("history_extra", "curriculum", "normaliser", "best_context", "restarts")
#: what each individual's outcome may hold (lists, ``terms`` and ``walk`` tables of lists)
OUTCOME_KEYS = ("fell", "unstable", "end_time", "terms", "walk", "previous", "parents")


@dataclass(frozen=True)
class RunRecord:
    """A run's committed state after its last committed generation (none: the empty record of a new run)."""

    #: the settings the run was created with (:func:`evobiped.run.fingerprint.settings`)
    settings: dict
    #: the start genome ``(G,)`` (None: the run has none)
    start: list[float] | None = None
    #: the optimizer's state (``OptimizerState.to_dict()``; empty: none yet)
    optimizer: dict = field(default_factory=dict)
    #: one row per committed generation (HISTORY_COLUMNS)
    history: tuple[list, ...] = ()
    #: the run's best (fitness, fell, end_time s, seed, generation, terms) and its genome ``(G,)`` (None: no
    #: generation committed)
    best: dict | None = None
    best_genome: list[float] | None = None
    #: the evaluation's wall-clock time over all sessions (s)
    wall_seconds: float = 0.0
    #: each individual's outcome (:meth:`evobiped.run.individuals.Individuals.to_dict`)
    outcome: dict = field(default_factory=dict)
    #: the best's terms per generation (name -> mean over its presentations; None: undefined)
    history_terms: tuple[dict, ...] = ()
    #: where the best walker went in its evaluation (``EpisodeResult.walk``; None: not known)
    best_walk: dict | None = None
    #: each committed generation file's digest (None: committed before digests were kept)
    generation_digests: tuple[str | None, ...] = ()
    #: the run context's state (:data:`CONTEXT_KEYS`; empty: a run without a context)
    context: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        """checkpoint.json's table."""
        return {FORMAT_KEY: FORMAT, SETTINGS_KEY: self.settings, START_KEY: self.start, OPTIMIZER_KEY: self.optimizer,
                "history": list(self.history), "best": self.best, "best_genome": self.best_genome,
                "wall_seconds": self.wall_seconds, "outcome": self.outcome, "history_terms": list(self.history_terms),
                "best_walk": self.best_walk, DIGESTS_KEY: list(self.generation_digests), **self.context}

    @classmethod
    def from_dict(cls, table: Any, *, generations: int, low: np.ndarray, high: np.ndarray) -> "RunRecord":
        """The record of a current-format ``table`` (:func:`upgrade` first), every field's type and range checked:
        a UserError names the first bad field (e.g. "best.fitness must be finite").  ``generations``: the run's
        total; ``low``/``high`` ``(G,)``: the gene bounds."""
        _check(table, generations, low, high)
        return cls(**{f.name: table[f.name] for f in dataclasses.fields(cls) if f.name != "context"},
                   context={k: table[k] for k in CONTEXT_KEYS if k in table}).replace()

    def replace(self, **changes) -> "RunRecord":
        """This record with ``changes`` (sequences kept as tuples)."""
        done = dataclasses.replace(self, **changes)
        for name in ("history", "history_terms", "generation_digests"):
            object.__setattr__(done, name, tuple(getattr(done, name)))
        return done

    def committed(self, row: list, terms: dict, digest: str, *, optimizer: dict, outcome: dict, context: dict,
                  best: tuple[dict, list[float], dict | None] | None) -> "RunRecord":
        """The record after one more generation: its history ``row`` and best's ``terms``, its generation file's
        ``digest``, the optimizer's, outcomes' and context's states after it, and the run's new best (meta, genome
        ``(G,)``, walk; None: the best stays)."""
        new = dict(zip(("best", "best_genome", "best_walk"), best)) if best is not None else {}
        return self.replace(history=(*self.history, row), history_terms=(*self.history_terms, terms),
                            generation_digests=(*self.generation_digests, digest), optimizer=optimizer,
                            outcome=outcome, context=context, **new)

    def timed(self, seconds: float) -> "RunRecord":
        """The last generation took ``seconds`` of wall-clock time (its row's wall_seconds, and the run's)."""
        wall = HISTORY_COLUMNS.index("wall_seconds")
        last = [*self.history[-1][:wall], seconds, *self.history[-1][wall + 1:]]
        return self.replace(history=(*self.history[:-1], last), wall_seconds=self.wall_seconds + seconds)


def format_of(table: dict) -> int:
    """The format of a table written before the format was: the first key it lacks tells (format 5 from 6: the
    outcome's ``previous``)."""
    for n, key in ((2, "best_genome"), (3, "history_terms"), (4, OPTIMIZER_KEY), (5, SETTINGS_KEY), (7, DIGESTS_KEY)):
        if key not in table:
            lineage = isinstance(table.get("outcome"), dict) and "previous" in table["outcome"]
            return n - 1 if n != 7 or lineage else 5
    return 7


def upgrade(table: Any, directory: Path, *, settings: dict | None = None,
            start: Callable[[], list | None] = lambda: None) -> Any:
    """``table`` (checkpoint.json's, read with ``file_format=FORMAT``: of this format or one before the key) in the
    current format, one step per format (the module's table); a table of another type, or one too malformed to
    upgrade, is returned for :meth:`RunRecord.from_dict` to name what is wrong.  ``settings`` and ``start`` supply
    what a table before format 5 lacks (the run's config's settings, its start genome read as a resume reads it);
    a reader of the committed generations alone gives neither (None then)."""
    if not isinstance(table, dict) or FORMAT_KEY in table:
        return table
    t, history = dict(table), table.get("history")
    rows = len(history) if isinstance(history, list) else 0
    n = format_of(t)
    if n < 2 and isinstance(t.get("best"), dict) and isinstance(t["best"].get("generation"), int):
        path = generation_file(directory, t["best"]["generation"])  # the best generation's file holds it
        try:
            t["best_genome"] = json.loads(path.read_text())["genome"]
        except (OSError, ValueError, KeyError, TypeError):
            raise UserError(f"best_genome is missing, and {path.name}, which holds it, cannot be read") from None
    if n < 3:
        t.setdefault("history_terms", [{}] * rows)
        t.setdefault("best_walk", None)
        fell = t["outcome"].get("fell") if isinstance(t.get("outcome"), dict) else None
        if isinstance(fell, list) and "walk" not in t["outcome"]:
            t["outcome"] = {**t["outcome"], "walk": {"displacement": [[None, None]] * len(fell),
                                                     "heading_deg": [None] * len(fell)}}
    if n < 4 and OLD_OPTIMIZER_KEY in t:
        t.setdefault(OPTIMIZER_KEY, t.pop(OLD_OPTIMIZER_KEY))
    if n < 5:
        t.setdefault(SETTINGS_KEY, settings)
        if START_KEY not in t:
            t[START_KEY] = start()
    if n < 7:
        t.setdefault(DIGESTS_KEY, [None] * rows)
    return {FORMAT_KEY: FORMAT, **t}


def _bad(field: str, why: str) -> UserError:
    return UserError(f"{field} {why}")


def _number(v: Any, field: str, *, integer: bool = False, low: float | None = None,
            allow_minus_inf: bool = False) -> float:
    ok_type = isinstance(v, int) if integer else isinstance(v, (int, float))
    if isinstance(v, bool) or not ok_type:
        raise _bad(field, f"must be {'a whole number' if integer else 'a number'}, got {v!r}")
    if not math.isfinite(v) and not (allow_minus_inf and v == -math.inf):
        raise _bad(field, f"must be finite, got {v!r}")
    if low is not None and v < low:
        raise _bad(field, f"must be >= {low:g}, got {v!r}")
    return v


def check_start(start: Any) -> None:
    """UserError unless ``start`` is a list of numbers (the start genome) or None."""
    if start is not None and not (isinstance(start, list)
                                  and all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in start)):
        raise _bad(START_KEY, "must be a list of numbers (the start genome) or null")


def _check(ck: Any, generations: int, low: np.ndarray, high: np.ndarray) -> None:
    """Every field of a current-format table (:meth:`RunRecord.from_dict`); the optimizer's state is checked by
    its ``state_from`` and ``restore``, the context's by ``RunContext.restore``."""
    if not isinstance(ck, dict):
        raise UserError(f"expected a table of fields, got {type(ck).__name__}")
    if ck.get(FORMAT_KEY) != FORMAT:
        raise _bad(FORMAT_KEY, f"must be {FORMAT}, got {ck.get(FORMAT_KEY)!r}")
    for key in (OPTIMIZER_KEY, "history", "best", "wall_seconds", "best_genome", "outcome", "history_terms",
                "best_walk", START_KEY, SETTINGS_KEY, DIGESTS_KEY):
        if key not in ck:
            raise _bad(key, "is missing")
    if not isinstance(ck[OPTIMIZER_KEY], dict):
        raise _bad(OPTIMIZER_KEY, "must be a table")
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
                _number(v, f"{where}.{name}", allow_minus_inf=name in _FITNESS,
                        low=0 if name == "wall_seconds" else None)
        if row[0] != g:
            raise _bad(f"{where}.generation", f"must be {g}, got {row[0]!r}")
    _number(ck["wall_seconds"], "wall_seconds", low=0)
    _check_best(ck["best"], ck["best_genome"], history, low, high)
    check_start(ck[START_KEY])
    if not isinstance(ck[SETTINGS_KEY], dict):
        raise _bad(SETTINGS_KEY, "must be a table of the settings the run was created with")
    _check_outcome(ck["outcome"], ck["history_terms"], history)
    walk = ck["best_walk"]
    if walk is not None and not (isinstance(walk, dict) and isinstance(walk.get("distance"), (int, float))):
        raise _bad("best_walk", "must be a table with the best walker's distance, or null")
    check_digests(ck)


def check_digests(ck: dict) -> None:
    """UserError unless the table's generation digests are one per history row, each a digest or null."""
    found = ck.get(DIGESTS_KEY)
    if not isinstance(found, list) or len(found) != len(ck.get("history", [])):
        raise _bad(DIGESTS_KEY, "must be a list of one digest per generation")
    if not all(d is None or (isinstance(d, str) and len(d) == 64) for d in found):
        raise _bad(DIGESTS_KEY, "must hold SHA-256 digests (64 hexadecimal digits) or null")


def _check_best(best: Any, genome: Any, history: list, low: np.ndarray, high: np.ndarray) -> None:
    if best is None:
        if history:
            raise _bad("best", "is null although generations were completed")
        if genome is not None:
            raise _bad("best_genome", "must be null while the run has no best")
        return
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
        raise _bad("best.fitness", f"must be the best fitness of generation {best['generation']} in the history, "
                                   f"got {best['fitness']!r}")
    if "seed" in best:
        _number(best["seed"], "best.seed", integer=True, low=0)
    if not isinstance(genome, list) or len(genome) != len(low):
        raise _bad("best_genome", f"must be a list of {len(low)} genes")
    for i, v in enumerate(genome):
        _number(v, f"best_genome[{i}]")
        if not low[i] <= v <= high[i]:
            raise _bad(f"best_genome[{i}]", f"must be within the gene's bounds [{low[i]:g}, {high[i]:g}], got {v!r}")


def _check_outcome(outcome: Any, terms: Any, history: list) -> None:
    """The outcome table (:data:`OUTCOME_KEYS`) and the best's terms per generation."""
    if not isinstance(outcome, dict) or not set(outcome) <= set(OUTCOME_KEYS):
        raise _bad("outcome", "must be a table of fell, unstable and end_time lists (and tables of terms and walk, "
                              "lists of previous and parent rows)")
    if history and not {"fell", "unstable", "end_time", "walk"} <= set(outcome):
        raise _bad("outcome", "must hold fell, unstable, end_time and walk")
    for key in ("terms", "walk"):
        if key in outcome and not isinstance(outcome[key], dict):
            raise _bad(f"outcome.{key}", "must be a table of lists")
    for key, vals in outcome.items():
        if key not in ("terms", "walk") and (not isinstance(vals, list) or not all(
                v is None or isinstance(v, (bool, int, float)) for v in vals)):
            raise _bad(f"outcome.{key}", "must be a list of numbers or booleans (null: not known)")
    entry = lambda v: v is None or (isinstance(v, (int, float)) and not isinstance(v, bool))  # noqa: E731
    for key, vals in ((f"{k}.{n}", v) for k in ("terms", "walk") for n, v in outcome.get(k, {}).items()):
        if not isinstance(vals, list) or not all(entry(v) or (isinstance(v, list) and all(map(entry, v)))
                                                 for v in vals):
            raise _bad(f"outcome.{key}", "must be a list of numbers (or of lists of numbers)")
    if not isinstance(terms, list) or len(terms) != len(history) or not all(
            isinstance(t, dict) and all(map(entry, t.values())) for t in terms):
        raise _bad("history_terms",
                   f"must be a list of tables of numbers (or nulls), one per generation ({len(history)})")
    if any(terms) and "terms" not in outcome:
        raise _bad("outcome.terms", "is missing")
