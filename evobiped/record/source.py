"""What ``evobiped replay SOURCE`` reads: a run directory or a genome file.

A run directory (written by ``evobiped evolve``) holds ``best.json``,
``generations/gen_NNNN.json`` and ``history.csv``; a genome file is any
genome JSON (:mod:`evobiped.genome_file`).  Every problem is a
:class:`~evobiped.errors.UserError` raised before anything is written.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..episode import EpisodeConfig
from ..errors import UserError
from ..genome_file import load_genome


@dataclass
class Source:
    """A genome ready to replay, and where it came from."""

    genome: np.ndarray  # (G,)
    config: EpisodeConfig
    meta: dict
    genome_path: Path
    run_dir: Path | None  # None for a lone genome file

    @property
    def label(self) -> str:
        """``best`` / ``gen_0007`` for a run directory, the file stem otherwise."""
        return self.genome_path.stem


def generation_path(run_dir: Path, generation: int) -> Path:
    return Path(run_dir) / "generations" / f"gen_{generation:04d}.json"


def resolve(source: str | Path, generation: int | None = None) -> Source:
    """Load the genome named by ``source`` (``generation``: a run directory's best of that generation)."""
    path = Path(source)
    if not path.exists():
        raise UserError(f"no such run directory or genome file: {path}")
    if path.is_dir():
        if generation is None:
            gpath = path / "best.json"
            if not gpath.is_file():
                raise UserError(f"{path} is not a run directory (it has no best.json)")
        else:
            gpath = generation_path(path, generation)
            if not gpath.is_file():
                have = sorted((path / "generations").glob("gen_*.json"))
                span = f"{have[0].stem[4:]}..{have[-1].stem[4:]}" if have else "none"
                raise UserError(f"{path} has no generation {generation} (generations saved: {span})")
        run_dir = path
    else:
        if generation is not None:
            raise UserError("--generation needs a run directory, not a genome file")
        gpath, run_dir = path, None
    genome, cfg, meta = load_genome(gpath)
    try:
        layout = cfg.layout()  # from the declarations: the replay compiles the model once, later
    except UserError as exc:
        raise UserError(f"{gpath}: {exc}") from None
    layout.validate(genome, what=f"genome in {gpath}")
    return Source(genome=genome, config=cfg, meta=meta, genome_path=gpath, run_dir=run_dir)


def read_history(path: str | Path) -> dict[str, np.ndarray]:
    """``history.csv`` -> ``{column: (n_generations,) float array}``; needs generation/best/mean."""
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
        return {k: np.array([float(r[k]) for r in rows]) for k in rows[0] if k is not None}
    except (TypeError, ValueError) as exc:
        raise UserError(f"{path}: not a number in the history ({exc})") from None
