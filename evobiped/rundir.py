"""The run-directory format in one place: file names, columns, readers and writers, the lock, checkpoint validation.

A run directory (``evobiped evolve --out DIR``)::

    start.json             the start genome (genome-file format, ``source``: where it came from), for a run started --from
    config.json            the full resolved RunConfig
    checkpoint.json        the commit point: optimizer state (key ``optimizer``), history, best genome, outcomes after the last generation
    history.csv            one row per generation (HISTORY_COLUMNS)           } derived from the checkpoint,
    best.json              best genome of the run so far                      } rebuilt by a resume when
    evolution.rrd          fitness per generation, a Rerun recording          } missing, stale or damaged
    summary.json           written when the run ends: the best walker, its distance and walking direction
    generations/gen_NNNN.json   best genome of each generation (genome-file format), written just before its commit
    .lock                  held (flock) by the one process that evolves the run

Other commands add to it: ``outcome.json`` (a study's result for the run),
``replay_<label>.rrd`` and ``figures_<label>/`` (replay), ``robustness[_<label>].json/.png``
(the robustness battery), where the label is ``best`` or ``gen_NNNN``.

``start.json`` is written before config.json when the run is created: a resume
never reads ``--from`` again (the run may be resumed from any directory, its
source gone).  The checkpoint holds the start genome too, and the settings the
run was created with (``settings``: config.json's, less where episodes run),
so a resume refuses an edited config.json by name (:mod:`evobiped.evolution.fingerprint`).

``checkpoint.json`` is the run's one commit point per generation and its one
source of truth: ``history.csv``, ``best.json``, ``summary.json`` and
``evolution.rrd`` are derived from it and rebuilt from it on ``--resume``
whenever they are missing, stale or damaged.  ``generations/gen_NNNN.json``
is written just before the commit of generation NNNN (a resume deletes those
beyond the last commit).
"""

from __future__ import annotations

import csv
import errno
import fcntl
import io
import math
import os
from pathlib import Path
from typing import Any

import numpy as np

from .errors import UserError
from .fileio import WriteError, atomic_write

CONFIG = "config.json"
START = "start.json"
CHECKPOINT = "checkpoint.json"
HISTORY = "history.csv"
BEST = "best.json"
SUMMARY = "summary.json"
RECORDING = "evolution.rrd"
GENERATIONS = "generations"
LOCK = ".lock"
#: a study's result for the run (evobiped study), with the long re-check
OUTCOME = "outcome.json"

HISTORY_COLUMNS = ("generation", "best", "mean", "median", "worst", "evaluations", "falls", "unstable", "wall_seconds")
#: history.csv's further columns: the best individual's task terms (``best_distance``, ...; the mean over its
#: presentations), one per term; nan where undefined, or for generations of a checkpoint written before terms were kept
TERM_PREFIX = "best_"
#: columns holding counts (whole numbers >= 0) and fitness values (a number or -inf)
_COUNTS = ("generation", "evaluations", "falls", "unstable")
_FITNESS = ("best", "mean", "median", "worst")


def generation_file(directory: Path, generation: int) -> Path:
    """``DIR/generations/gen_NNNN.json``: the best genome of generation ``generation``."""
    return Path(directory) / GENERATIONS / f"gen_{generation:04d}.json"


def generation_files(directory: Path) -> list[Path]:
    """The generation files present, in file-name order."""
    return sorted((Path(directory) / GENERATIONS).glob("gen_*.json"))


def generation_of(path: Path) -> int | None:
    """The generation a ``gen_NNNN.json`` file holds (None: not such a name)."""
    digits = Path(path).stem[4:]
    return int(digits) if Path(path).stem.startswith("gen_") and digits.isdigit() else None


def label(genome_path: Path) -> str:
    """``best`` / ``gen_0007``: how replay and robustness name what they write about a run's genome file."""
    return Path(genome_path).stem


def replay_file(directory: Path, label: str) -> Path:
    """The default recording of a replay: ``DIR/replay_<label>.rrd``."""
    return Path(directory) / f"replay_{label}.rrd"


def figures_dir(directory: Path, label: str) -> Path:
    """The default folder of a replay's figures: ``DIR/figures_<label>``."""
    return Path(directory) / f"figures_{label}"


#: where replay and robustness write about a lone genome file when no --out is given, relative to the current
#: directory (never beside the file, which may sit in a repository)
GENOME_OUTPUTS = Path("runs")


def genome_outputs(genome_path: Path) -> Path:
    """The default folder for what replay and robustness write about a lone genome file: ``runs/<stem>``."""
    return GENOME_OUTPUTS / Path(genome_path).stem


def robustness_stem(label: str) -> str:
    """File stem of the robustness battery's results in a run directory: ``robustness`` for the best, ``robustness_<label>``."""
    return "robustness" if label == "best" else f"robustness_{label}"


# ---- history.csv
def _term_names(terms: list[dict] | None) -> list[str]:
    return list(dict.fromkeys(k for t in terms or () for k in t))


def history_columns(rows: list[list], terms: list[dict] | None = None, extra: list[dict] | None = None) -> dict[str, np.ndarray]:
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
    """``history.csv`` -> ``{column: (n_generations,) float array}``; needs generation/best/mean (UserError otherwise)."""
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
        bad = np.isnan(values) | (values == np.inf) if name in _FITNESS else ~np.isfinite(values) if name in HISTORY_COLUMNS else None
        if name in _COUNTS:
            bad = bad | (values < 0) | (values != np.round(values))
        if bad is not None and bad.any():
            row = int(np.flatnonzero(bad)[0])
            raise UserError(f"{path}: {name} of row {row + 1} is {values[row]:g}, not a {'count' if name in _COUNTS else 'fitness' if name in _FITNESS else 'number'}")
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
    w.writerows([*r, *("nan" if t.get(n) is None else t[n] for n in names), *("nan" if x.get(n) is None else x[n] for n in more)]
                for r, t, x in zip(rows, padded, padded_more))
    return buf.getvalue()


def write_history(path: Path, rows: list[list]) -> None:
    atomic_write(path, history_text(rows))


def remove_stale_temporaries(directory: Path) -> list[Path]:
    """Delete the ``.NAME.*.tmp`` files a killed :func:`~evobiped.fileio.atomic_write` left; returns them."""
    found = [p for d in (Path(directory), Path(directory) / GENERATIONS) if d.is_dir() for p in d.glob(".*.tmp")]
    for p in found:
        p.unlink(missing_ok=True)
    return found


def is_unused(directory: Path) -> bool:
    """True for a directory that holds no run: nothing, or only what a run killed before writing its config leaves
    (the lock, an empty generations folder, temporaries, the start genome); a directory that cannot be listed is a WriteError."""
    try:
        configured = (Path(directory) / CONFIG).exists()
        for p in Path(directory).iterdir():
            temporary = p.name.startswith(".") and p.name.endswith(".tmp")
            start = p.name == START and not configured
            if not (p.name == LOCK or temporary or start or (p.name == GENERATIONS and p.is_dir() and not any(p.iterdir()))):
                return False
    except OSError as exc:
        raise WriteError(exc.filename or directory, exc) from None
    return True


# ---- the lock
_held: dict[Path, list] = {}  # resolved run directory -> [fd, count] (re-entrant within a process)


def lock(directory: str | Path) -> None:
    """Take the exclusive lock of a run directory (``flock`` on ``DIR/.lock``, which holds the owner's pid).

    The kernel releases it when the process ends, however it ends, so a lock is
    never stale.  A second process gets a UserError; the same process may lock again.
    A pid that cannot be written (disk full) is a WriteError, and an empty lock file
    is removed again: a lock file is never left empty.
    """
    key = Path(directory).resolve()
    if key in _held:
        _held[key][1] += 1
        return
    path = key / LOCK
    while True:
        try:
            fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
        except OSError as exc:
            raise WriteError(path, exc) from None
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as exc:
            owner = os.pread(fd, 32, 0).decode(errors="replace").strip() or "unknown"
            os.close(fd)
            if exc.errno in (errno.EWOULDBLOCK, errno.EAGAIN, errno.EACCES):
                raise UserError(f"run directory {directory} is in use by process {owner}") from None
            raise WriteError(path, exc) from None
        if _same_file(fd, path):
            break
        os.close(fd)  # the file was removed (by a writer that failed) after we opened it: lock the one there now
    pid = f"{os.getpid()}\n".encode()
    try:
        if os.pread(fd, 32, 0) != pid:  # the owner's pid, for the message a second writer gets
            os.pwrite(fd, pid, 0)  # over the old pid, then cut: the file is never empty
            os.ftruncate(fd, len(pid))
    except OSError as exc:
        if os.fstat(fd).st_size == 0:
            path.unlink(missing_ok=True)  # still holding the lock: nobody else can be using it
        os.close(fd)
        raise WriteError(path, exc) from None
    _held[key] = [fd, 1]


def _same_file(fd: int, path: Path) -> bool:
    """True while ``path`` still names the open file ``fd``."""
    try:
        a, b = os.fstat(fd), os.stat(path)
    except OSError:
        return False
    return (a.st_dev, a.st_ino) == (b.st_dev, b.st_ino)


def unlock(directory: str | Path) -> None:
    """Release one :func:`lock` of this process (the last one frees the directory)."""
    key = Path(directory).resolve()
    if key not in _held:
        return
    _held[key][1] -= 1
    if _held[key][1] == 0:
        os.close(_held.pop(key)[0])


# ---- the checkpoint
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
    if not isinstance(outcome, dict) or not set(outcome) <= {"fell", "unstable", "end_time", "terms", "walk"}:
        raise _bad("outcome", "must be a table of fell, unstable and end_time lists (and tables of terms and walk)")
    nested = {f"{k}.{n}": v for k in ("terms", "walk") if isinstance(outcome.get(k), dict) for n, v in outcome[k].items()}
    for key in ("terms", "walk"):
        if key in outcome and not isinstance(outcome[key], dict):
            raise _bad(f"outcome.{key}", "must be a table of lists")
    plain = {k: v for k, v in outcome.items() if k not in ("terms", "walk")}
    for key, vals in plain.items():
        if not isinstance(vals, list) or not all(isinstance(v, (bool, int, float)) for v in vals):
            raise _bad(f"outcome.{key}", "must be a list of numbers or booleans")
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
