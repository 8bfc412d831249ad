"""A MAP-Elites run's archive as a file: ``archive.json`` in the run directory, derived from the checkpoint at each
commit (from what the optimizer gives, :class:`ArchiveContents`; the optimizer writes no file).

::

    {"format": "evobiped-archive/1", "measures": ["speed", "turning"], "low": [...], "high": [...],
     "resolution": [30, 30],
     "elites": [{"cell": [i, j], "measures": [m0, m1], "objective": f, "fell": false, "end_time": 20.0,
                 "genome": [...]}, ...],                       # in cell order, one a line
     "progress": {"evaluations": [...], "cells": [...], "qd_score": [...]}}    # one entry per generation

``cell`` ``[i, j]``: the grid coordinates (i along the first measure); ``measures`` in the terms' units;
``objective``: the task's fitness; ``fell`` and ``end_time`` (s): the elite's evaluation.  The run's
config.json says which episode the genomes walk.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ...core.errors import UserError
from ...core.fileio import read_json

#: the file name in the run directory
ARCHIVE = "archive.json"
FORMAT = "evobiped-archive/1"


@dataclass(frozen=True)
class ArchiveContents:
    """What an optimizer that keeps an archive gives the run directory for archive.json: the measures' names, their
    bounds ``low``, ``high`` ``(2,)`` and ``resolution`` (cells per measure), the elites' grid ``cells`` ``(E, 2)``,
    the ``elites`` (arrays as :meth:`MapElites.elites` gives them; ``objective`` the task's fitness) and ``progress``
    ``(generations, 3)`` evaluations, cells, QD score."""

    measures: tuple[str, ...]
    low: np.ndarray
    high: np.ndarray
    resolution: tuple[int, ...]
    cells: np.ndarray
    elites: dict
    progress: np.ndarray


def archive_text(archive: ArchiveContents) -> str:
    """The text of archive.json, written by the run directory at each commit (:mod:`.derived_file`)."""
    cells, elites = archive.cells, archive.elites
    head = {"format": FORMAT, "measures": list(archive.measures), "low": [float(x) for x in archive.low],
            "high": [float(x) for x in archive.high], "resolution": [int(x) for x in archive.resolution]}
    rows = [json.dumps({"cell": [int(c) for c in cell], "measures": [float(x) for x in elites["measures"][k]],
                        "objective": float(elites["objective"][k]), "fell": bool(elites["fell"][k]),
                        "end_time": float(elites["end_time"][k]), "genome": [float(x) for x in elites["genome"][k]]})
            for k, cell in enumerate(cells)]
    p = np.asarray(archive.progress, float).reshape(-1, 3)
    prog = {"evaluations": [int(x) for x in p[:, 0]], "cells": [int(x) for x in p[:, 1]],
            "qd_score": [float(x) for x in p[:, 2]]}
    text = json.dumps(head, indent=2)[:-2] + ',\n  "elites": [\n' + ",\n".join("    " + r for r in rows)
    return text + ("\n  ],\n" if rows else "],\n") + '  "progress": ' + json.dumps(prog) + "\n}\n"


@dataclass(frozen=True)
class Archive:
    """A read archive.json: the measures' names, bounds and resolution, and the elites' arrays in cell order (``cell``
    ``(E, 2)``, ``measures`` ``(E, 2)``, ``objective``, ``fell``, ``end_time`` ``(E,)``, ``genome`` ``(E, G)``);
    ``progress`` ``(generations, 3)``."""

    path: Path
    measures: tuple[str, str]
    low: np.ndarray
    high: np.ndarray
    resolution: tuple[int, int]
    cell: np.ndarray
    values: np.ndarray
    objective: np.ndarray
    fell: np.ndarray
    end_time: np.ndarray
    genome: np.ndarray
    progress: np.ndarray

    def find(self, cell: tuple[int, int]) -> int:
        """The row of the elite in grid cell ``cell`` (UserError naming the filled range when the cell is empty)."""
        hit = np.flatnonzero((self.cell == np.asarray(cell)).all(axis=1))
        if not len(hit):
            lo, hi = self.cell.min(axis=0), self.cell.max(axis=0)
            raise UserError(f"{self.path}: cell {cell[0]},{cell[1]} holds no elite (of "
                            f"{self.resolution[0]}x{self.resolution[1]} cells {len(self.cell)} are filled, i "
                            f"{lo[0]}-{hi[0]}, j {lo[1]}-{hi[1]})")
        return int(hit[0])


def read_archive(source: str | Path) -> Archive:
    """The archive of a run directory (its archive.json) or an archive file; UserError, one line, when it is missing
    or malformed."""
    path = Path(source)
    path = path / ARCHIVE if path.is_dir() else path
    if not path.is_file():
        raise UserError(f"{path}: no archive (a map-elites run writes {ARCHIVE} after its first generation)")
    t = read_json(path, what="archive", file_format=FORMAT)
    try:
        if t["format"] != FORMAT:
            raise ValueError(f"format must be {FORMAT}")
        e = t["elites"]
        if not e:
            raise ValueError("holds no elite")
        col = lambda k, dtype=float: np.array([x[k] for x in e], dtype)  # noqa: E731
        a = Archive(path, tuple(t["measures"]), np.array(t["low"], float), np.array(t["high"], float),
                    tuple(t["resolution"]),
                    col("cell", int), col("measures"), col("objective"), col("fell", bool), col("end_time"),
                    col("genome"),
                    np.array([t["progress"][k] for k in ("evaluations", "cells", "qd_score")], float).T.reshape(-1, 3))
        if a.cell.shape != (len(e), 2) or a.values.shape != (len(e), 2) or a.genome.ndim != 2 or len(a.measures) != 2:
            raise ValueError("each elite needs a cell and two measures")
    except (KeyError, TypeError, ValueError, IndexError) as exc:
        raise UserError(f"{path}: not an archive ({exc})") from None
    return a
