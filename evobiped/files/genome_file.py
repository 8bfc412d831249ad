"""Genome JSON files: a genome with everything needed to re-simulate it.

Format (``genome`` and ``episode`` required on reading, a ``format`` other than this one refused; the episode config
names the body, controller and task with their options, which is all a replay
needs to rebuild the simulation)::

    {"format": "evobiped-genome/1", "genome": [...G floats...],
     "episode": {EpisodeConfig fields}, ...metadata..., "version": "0.1.0",
     "environment": {versions, numpy's SIMD kernels, machine: evobiped.core.provenance.current()}}

The metadata is whatever the writer passes: a run's generation files carry
``fitness``, ``fell``, ``end_time`` (s), ``seed`` and ``generation``;
``evobiped taga --save-genome`` carries ``preset``; a shipped walker carries ``outcome``
(:func:`evobiped.files.outcome.outcome`), what a replay in another numerical environment checks.  A reader returns the
metadata, ``environment`` included, as a dict.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from .. import __version__
from ..core import provenance
from ..episode import EpisodeConfig
from ..core.options import refuse_unknown
from ..core.errors import ConfigError, UserError
from ..core.fileio import atomic_write, json_text, read_json

FORMAT = "evobiped-genome/1"


def genome_text(genome: np.ndarray, episode: EpisodeConfig, **meta: Any) -> str:
    """The exact content of a genome file for one genome ``(G,)``, its episode config and metadata, with the
    numerical environment of this process (:func:`evobiped.core.provenance.current`)."""
    obj = {
        "format": FORMAT,
        "genome": [float(x) for x in np.asarray(genome, float).ravel()],
        "episode": episode.to_dict(),
        **{k: _plain(v) for k, v in meta.items()},
        "version": __version__,
        "environment": provenance.current(),
    }
    return json_text(obj)


def save_genome(path: str | Path, genome: np.ndarray, episode: EpisodeConfig, **meta: Any) -> None:
    """Write one genome ``(G,)`` with its episode config and metadata, atomically."""
    atomic_write(path, genome_text(genome, episode, **meta))


def load_genome(path: str | Path) -> tuple[np.ndarray, EpisodeConfig, dict]:
    """Read a genome file -> ``(genome (G,), EpisodeConfig, metadata)``; UserError (one line) if malformed: the genome
    must fit its episode's layout (length, finite, within bounds) and a stored ``outcome`` must be what
    :func:`evobiped.files.outcome.outcome` writes."""
    obj = read_json(path, what="genome file", file_format=FORMAT)
    if not isinstance(obj, dict) or "genome" not in obj or "episode" not in obj:
        raise UserError(f"{path} is not an evobiped genome file (needs 'genome' and 'episode')")
    if not isinstance(obj["genome"], list) or not all(isinstance(x, (int, float)) and not isinstance(x, bool)
                                                      for x in obj["genome"]):
        raise UserError(f"{path}: 'genome' must be a list of numbers")
    if not isinstance(obj["episode"], dict):
        raise UserError(f"{path}: 'episode' must be a table")
    try:
        cfg = EpisodeConfig(**refuse_unknown(EpisodeConfig, obj["episode"], "episode"))
        genome = cfg.layout().validate(obj["genome"], what=f"{path}: the genome")[0]
    except ConfigError as exc:
        raise ConfigError(f"{path}: {exc}") from None
    if "outcome" in obj:
        _check_outcome(obj["outcome"], path)
    meta = {k: v for k, v in obj.items() if k not in ("genome", "episode")}
    return genome, cfg, meta


def _check_outcome(stored: Any, path) -> None:
    """UserError unless ``stored`` has the shape of :func:`evobiped.files.outcome.outcome`'s table (any part of it)."""
    def number(v):
        return v is None or (isinstance(v, (int, float)) and not isinstance(v, bool) and np.isfinite(v))

    def row_ok(r):
        return (isinstance(r, dict) and ("fell" not in r or isinstance(r["fell"], bool))
                and all(number(r.get(k)) for k in ("end_time", "distance", "heading_deg", "to_target")))

    rows = stored.get("rows") if isinstance(stored, dict) else None
    if not (row_ok(stored) and (rows is None or (isinstance(rows, list) and all(map(row_ok, rows))))):
        raise UserError(f"{path}: 'outcome' must be a table of fell (true/false), end_time (s) and rows, each a table "
                        "of fell, end_time, distance, heading_deg and to_target (numbers)")


def _plain(v: Any) -> Any:
    if isinstance(v, np.generic):
        return v.item()
    if isinstance(v, np.ndarray):
        return v.tolist()
    return v
