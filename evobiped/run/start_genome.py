"""A run's start genome (``--from``), kept in its run directory: read once when the run is created, never again.

``start.json`` (genome-file format, ``source``: the path given) is written before config.json; the checkpoint
holds the genome too (``start``).  A resume takes the checkpoint's, else start.json's (a run cut before its first
commit); a checkpoint of a format before ``start`` (:mod:`evobiped.files.rundir.record`) is given start.json's,
or, made before the run directory kept it, the genome its source names, read once more.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..files import rundir
from ..core.errors import UserError
from ..files.genome_file import load_genome, save_genome
from .run_config import RunConfig


def keep_start(directory: Path, start: np.ndarray, config: RunConfig) -> None:
    """Write the run's start genome ``(G,)`` as ``directory/start.json``, with where it came from, in its source's
    episode config when that fits the genome (so what the source froze, e.g. its normaliser, is kept), else the
    run's."""
    episode = config.episode
    try:
        source = rundir.resolve_genome(config.initial).config
        if source.layout().size == len(start) and source.controller == episode.controller:
            episode = source
    except UserError:
        pass
    save_genome(directory / rundir.START, start, episode, source=config.initial,
                source_path=str(Path(config.initial).resolve()))


def start_episode(directory: Path, config: RunConfig):
    """The episode config the run's start genome was kept in (start.json; None: no start genome, or none kept)."""
    file = directory / rundir.START
    if not config.initial or not file.is_file():
        return None
    return load_genome(file)[1]


def kept_start(directory: Path, config: RunConfig, record: dict | None) -> np.ndarray | None:
    """The run's start genome: the record's (``record``: checkpoint.json's table, upgraded; None: no checkpoint),
    else start.json's (a run cut before its first commit)."""
    path, file = directory / rundir.CHECKPOINT, directory / rundir.START
    stored = record.get(rundir.START_KEY) if isinstance(record, dict) else None
    if not config.initial:
        if stored is not None or (record is None and file.exists()):
            raise UserError(f"{directory / rundir.CONFIG} names no start genome (initial) but the run was created with "
                            "one; restore it, or start a new run")
        return None
    if stored is not None:
        try:
            rundir.check_start(stored)
        except UserError as exc:
            raise UserError(f"checkpoint {path} is malformed: {exc}") from None
        return config.episode.layout().validate(stored, what=f"checkpoint {path}: start")[0]
    if isinstance(record, dict):
        raise UserError(f"checkpoint {path} is malformed: start is null although the run's config names a start genome")
    return start_file(directory, config)


def start_file(directory: Path, config: RunConfig) -> np.ndarray | None:
    """start.json's genome ``(G,)`` (None: the run's config names none, or a run made before its directory kept
    it: the resume reads it from its source, as then)."""
    file = directory / rundir.START
    if not config.initial or not file.exists():
        return None
    genome, _, meta = load_genome(file)
    if meta.get("source") != config.initial:
        raise UserError(f"{file} was made from {meta.get('source')!r} but {directory / rundir.CONFIG} names "
                        f"{config.initial!r} as the start genome; restore it, or start a new run")
    return genome
