"""What ``evobiped replay SOURCE`` reads: a run directory or a genome file.

A run directory (written by ``evobiped evolve``; format in :mod:`evobiped.rundir`)
holds the best genome and each generation's; a genome file is any genome JSON
(:mod:`evobiped.genome_file`).  Every problem is a
:class:`~evobiped.errors.UserError` raised before anything is written.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..episode import EpisodeConfig
from ..errors import UserError
from ..fileio import read_json
from .. import rundir
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
    def environment(self) -> dict | None:
        """The numerical environment the genome's stored results were made in (:mod:`evobiped.provenance`);
        None for files written before it was recorded."""
        env = self.meta.get("environment")
        return env if isinstance(env, dict) else None

    def stored_outcome(self) -> dict | None:
        """What the walker did when it was stored, as :func:`evobiped.outcome.compare` reads it: the file's
        ``outcome`` (always of the nominal episode), else, for a run without perturbations, its ``fell`` and
        ``end_time`` with, for a run's best, the distance and direction in the run's summary.json; None when the
        file says nothing of it."""
        if isinstance(self.meta.get("outcome"), dict):
            return self.meta["outcome"]
        if self.config.perturbed:
            return None  # its fell and end time are of the perturbed presentations, not of the nominal replay
        stored = {k: self.meta[k] for k in ("fell", "end_time") if isinstance(self.meta.get(k), (bool, int, float))}
        summary = self.run_dir / rundir.SUMMARY if self.run_dir is not None and self.label == "best" else None
        if summary is not None and summary.is_file():
            try:
                walk = read_json(summary, what="run summary").get("best_walk") or {}
            except (UserError, AttributeError):
                walk = {}
            if isinstance(walk.get("distance"), (int, float)):
                stored["rows"] = [{"distance": walk["distance"], "heading_deg": walk.get("heading_deg")}]
        return stored or None

    @property
    def label(self) -> str:
        """``best`` / ``gen_0007`` for a run directory, the file stem otherwise."""
        return rundir.label(self.genome_path)

    @property
    def outputs(self) -> Path:
        """Where replay and robustness write about this genome when no ``--out`` is given: its run directory; for a
        genome file in a run directory or anywhere under ``runs/`` (a run's ``selected.json``, distill's
        ``student.json``), the file's own folder, so two runs' ``selected.json`` never share one; else
        ``runs/<stem>`` (never beside a file that may sit in a repository)."""
        if self.run_dir is not None:
            return self.run_dir
        folder = self.genome_path.parent
        if (folder / rundir.CONFIG).is_file() or folder.resolve().is_relative_to(rundir.GENOME_OUTPUTS.resolve()):
            return folder
        return rundir.genome_outputs(self.genome_path)

    @property
    def name(self) -> str:
        """What a figure or video calls the walker: ``reil_simbicon_seed5 (best)``, or the genome file's stem."""
        return f"{self.run_dir.name} ({self.label})" if self.run_dir is not None else self.genome_path.stem


def resolve(source: str | Path, generation: int | None = None) -> Source:
    """Load the genome named by ``source`` (``generation``: a run directory's best of that generation)."""
    path = Path(source)
    if not path.exists():
        raise UserError(f"no such run directory or genome file: {path}")
    if path.is_dir():
        if generation is None:
            gpath = path / rundir.BEST
            if not gpath.is_file():
                raise UserError(f"{path} is not a run directory (it has no {rundir.BEST})")
        else:
            gpath = rundir.generation_file(path, generation)
            if not gpath.is_file():
                have = rundir.generation_files(path)
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

