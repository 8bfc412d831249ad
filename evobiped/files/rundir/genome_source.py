""""A run directory or a genome file": the one place that says which genome file such a name means, and reads it.

A run directory (written by ``evobiped evolve``) stands for its best genome (``best.json``) or, with
``generation``, that generation's best (``generations/gen_NNNN.json``); any other path is a genome file
(:mod:`evobiped.files.genome_file`).  Every problem is one :class:`~evobiped.core.errors.UserError` line.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ...episode import EpisodeConfig
from ...core.errors import UserError
from ...core.fileio import what_is_there
from ..genome_file import load_genome
from .generation_check import check_generation_files
from .layout import BEST, generation_file, generation_files


@dataclass
class GenomeSource:
    """A genome read from a run directory or a genome file, and where it came from."""

    genome: np.ndarray  # (G,)
    config: EpisodeConfig
    meta: dict
    genome_path: Path  # the file read: a run directory's best.json or generation file, or the genome file itself
    run_dir: Path | None  # None for a lone genome file


def genome_path(source: str | Path, generation: int | None = None) -> tuple[Path, Path | None]:
    """``(the genome file, its run directory or None)`` that ``source`` names (``generation``: a run directory's
    best of that generation); UserError when there is none."""
    path = Path(source)
    if not path.is_dir() and not path.is_file():
        there = what_is_there(path)
        raise UserError(f"no such run directory or genome file: {path}" if there == "not found" else f"{path} {there}")
    if not path.is_dir():
        if generation is not None:
            raise UserError("--generation needs a run directory, not a genome file")
        return path, None
    check_generation_files(path)  # the committed generation files are the run's, or one line naming the one that is not
    if generation is None:
        if not (path / BEST).is_file():
            raise UserError(f"{path} is not a run directory (it has no {BEST})")
        return path / BEST, path
    gpath = generation_file(path, generation)
    if not gpath.is_file():
        have = generation_files(path)
        span = f"{have[0].stem[4:]}..{have[-1].stem[4:]}" if have else "none"
        raise UserError(f"{path} has no generation {generation} (generations saved: {span})")
    return gpath, path


def resolve_genome(source: str | Path, generation: int | None = None) -> GenomeSource:
    """The genome ``source`` names (:func:`genome_path`), read and checked against its episode's genome layout
    (known from the declarations: nothing is compiled)."""
    gpath, run_dir = genome_path(source, generation)
    genome, cfg, meta = load_genome(gpath)
    try:
        layout = cfg.layout()
    except UserError as exc:
        raise UserError(f"{gpath}: {exc}") from None
    layout.validate(genome, what=f"genome in {gpath}")
    return GenomeSource(genome=genome, config=cfg, meta=meta, genome_path=gpath, run_dir=run_dir)
