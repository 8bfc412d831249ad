"""individuals.jsonl: an append-only record of every individual of a run, one JSON line per population row per
generation.

Each line is a table (keys in this order, :data:`INDIVIDUAL_KEYS`)::

    generation  the generation (0, 1, ...)
    row         the individual's row in that generation's population
    evaluated   true: evaluated in this generation; false: kept from the previous one with its outcome (a GA's survivor)
    previous    the row of generation - 1 this same individual held (null: new in this generation)
    parents     the rows of generation - 1 it was bred from (null: not known, e.g. CMA-ES samples a distribution)
    fitness     its fitness (higher is better; -Infinity: an unstable simulation; null: not known)
    fell, unstable, end_time (s)   its evaluation's outcome (null: not known)
    terms       the task's terms (name -> a number, or a list over its presentations; null: undefined)

Unknown is null, never 0.  A generation's lines are appended (and flushed to disk) after the individuals are told
and before the generation's commit (checkpoint.json), like its generation file; a resume cuts the file back to the
lines of the committed generations (:func:`committed_size`), so a crash never duplicates nor loses a row of a
committed generation.  The file cannot be rebuilt from the checkpoint (which holds only the current population):
a resume that finds committed generations missing says so.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

from ...core.errors import UserError
from ...core.fileio import WriteError

INDIVIDUALS = "individuals.jsonl"
INDIVIDUAL_KEYS = ("generation", "row", "evaluated", "previous", "parents", "fitness", "fell", "unstable", "end_time",
                   "terms")


def individuals_text(rows: list[dict]) -> str:
    """The lines of ``rows`` (tables with :data:`INDIVIDUAL_KEYS`), one JSON object each, in that key order."""
    return "".join(json.dumps({k: r[k] for k in INDIVIDUAL_KEYS}, separators=(",", ":")) + "\n" for r in rows)


def append_individuals(path: str | Path, rows: list[dict]) -> None:
    """Append ``rows``' lines to ``path`` and make them durable (fsync); :class:`~evobiped.core.fileio.WriteError` if it
    cannot."""
    try:
        with open(path, "a") as f:
            f.write(individuals_text(rows))
            f.flush()
            os.fsync(f.fileno())
    except OSError as exc:
        raise WriteError(path, exc) from None


def committed_size(path: str | Path, generations: int) -> tuple[int, int]:
    """``(bytes, covered)``: the length of the longest start of the file made of whole, well-formed lines of the
    generations below ``generations``, in order with rows 0, 1, ... each (what a resume keeps; the first generation
    may be any: a run made before the file was kept starts it where it was resumed), and how many generations those
    lines reach (the last one's number + 1; 0: none).  A missing file: ``(0, 0)``."""
    try:
        data = Path(path).read_bytes()
    except FileNotFoundError:
        return 0, 0
    except OSError as exc:
        raise WriteError(path, exc) from None
    size, last, next_row = 0, -1, 0
    for line in data.splitlines(keepends=True):
        try:
            r = json.loads(line) if line.endswith(b"\n") else None
        except ValueError:
            r = None
        if not (isinstance(r, dict) and isinstance(r.get("generation"), int) and isinstance(r.get("row"), int)):
            break
        g = r["generation"]
        if g >= generations or r["row"] != (next_row if g == last else 0) or (last >= 0 and g not in (last, last + 1)):
            break
        last, next_row, size = g, r["row"] + 1, size + len(line)
    return size, last + 1


def cut_individuals(path: str | Path, size: int) -> None:
    """Cut ``path`` back to its first ``size`` bytes (a resume's: the committed generations' lines)."""
    try:
        os.truncate(path, size)
    except OSError as exc:
        raise WriteError(path, exc) from None


def read_individuals(path: str | Path) -> list[dict]:
    """Every line of ``path`` as a table; UserError naming the first line that is not one of :data:`INDIVIDUAL_KEYS`."""
    try:
        lines = Path(path).read_text().splitlines()
    except FileNotFoundError:
        raise UserError(f"individuals file not found: {path}") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise UserError(f"cannot read {path}: {exc}") from None
    out = []
    for n, line in enumerate(lines, 1):
        try:
            r = json.loads(line)
        except ValueError:
            r = None
        if not isinstance(r, dict) or tuple(r) != INDIVIDUAL_KEYS:
            raise UserError(f"{path}: line {n} is not a record of an individual ({', '.join(INDIVIDUAL_KEYS)})")
        out.append(r)
    return out
