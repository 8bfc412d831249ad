""""A run directory or a genome file": the one place that says which genome file such a name means, and reads it.

A run directory (written by ``evobiped evolve``) stands for its best genome (``best.json``) or, with
``generation``, that generation's best (``generations/gen_NNNN.json``); any other path is a genome file
(:mod:`evobiped.files.genome_file`).  Every problem is one :class:`~evobiped.core.errors.UserError` line.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ...episode import EpisodeConfig
from ...core.errors import UserError
from ...core.fileio import what_is_there
from ..genome_file import load_genome
from .generation_check import check_generation_files
from .layout import BEST, CHECKPOINT, CONFIG, generation_file, generation_files
from .locking import writer


@dataclass
class GenomeSource:
    """A genome read from a run directory or a genome file, and where it came from."""

    genome: np.ndarray  # (G,)
    config: EpisodeConfig
    meta: dict
    genome_path: Path  # the file read: a run directory's best.json or generation file, or the genome file itself
    run_dir: Path | None  # None for a lone genome file
    #: read from a run another process was writing (``--allow-unfinished``): its checkpoint's mark
    #: (:func:`checkpoint_mark`) and the writer's pid; None for a run at rest
    unfinished: dict | None = None


#: the metadata key of a genome chosen from a run (``select``): the run's checkpoint mark it was chosen from
FROM_CHECKPOINT = "from_checkpoint"


def checkpoint_mark(run_dir: Path) -> dict | None:
    """``{"generations": committed generations, "digest": the checkpoint file's}`` of ``run_dir``; None without one."""
    try:
        data = (Path(run_dir) / CHECKPOINT).read_bytes()
        history = json.loads(data).get("history", [])
    except (OSError, ValueError, AttributeError):
        return None
    return {"generations": len(history) if isinstance(history, list) else None,
            "digest": hashlib.sha256(data).hexdigest()[:16]}


def check_at_rest(run_dir: Path, allow_unfinished: bool = False,
                  how: str = "wait or pass --allow-unfinished") -> dict | None:
    """None when no other process writes ``run_dir``; else one line (UserError, ending in ``how``) unless
    ``allow_unfinished``, and then the checkpoint's mark and the writer's pid (what a reader records of the generation
    it read)."""
    pid = writer(run_dir)
    if pid is None:
        return None
    if not allow_unfinished:
        raise UserError(f"{run_dir} is being written by process {pid}; {how}")
    return {**(checkpoint_mark(run_dir) or {"generations": 0, "digest": None}), "writer": pid}


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


def resolve_genome(source: str | Path, generation: int | None = None, allow_unfinished: bool = False) -> GenomeSource:
    """The genome ``source`` names (:func:`genome_path`), read and checked against its episode's genome layout
    (known from the declarations: nothing is compiled).  A run that another process is writing (the run directory
    named, or the one a genome file lies in) is one line unless ``allow_unfinished`` (then :attr:`GenomeSource.
    unfinished` says which generation was read); a genome chosen from a run whose checkpoint has changed since is one
    line naming the command that chooses again."""
    given = Path(source)
    home = given if given.is_dir() else given.parent if given.is_file() and (given.parent / CONFIG).is_file() else None
    unfinished = check_at_rest(home, allow_unfinished) if home is not None else None  # before any file of it is read
    gpath, run_dir = genome_path(source, generation)
    genome, cfg, meta = load_genome(gpath)
    chosen = meta.get(FROM_CHECKPOINT)
    if isinstance(chosen, dict) and unfinished is None and home is not None:
        now = checkpoint_mark(home)
        if now is not None and now["digest"] != chosen.get("digest"):
            raise UserError(f"{gpath} was chosen when {home} had {chosen.get('generations')} generations; it has "
                            f"{now['generations']} now: choose again with evobiped select {home}")
    try:
        layout = cfg.layout()
    except UserError as exc:
        raise UserError(f"{gpath}: {exc}") from None
    layout.validate(genome, what=f"genome in {gpath}")
    return GenomeSource(genome=genome, config=cfg, meta=meta, genome_path=gpath, run_dir=run_dir, unfinished=unfinished)
