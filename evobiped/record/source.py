"""What ``evobiped replay SOURCE`` reads: a run directory or a genome file (which one:
:func:`evobiped.files.rundir.resolve_genome`), with what a replay, a recording and the robustness battery ask of it
(its stored outcome, where its outputs go, its name).  Every problem is a :class:`~evobiped.core.errors.UserError`
raised before anything is written.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path

from ..core.errors import UserError
from ..core.fileio import read_json
from ..files import rundir


@dataclass
class Source(rundir.GenomeSource):
    """A genome ready to replay, and where it came from."""

    @property
    def environment(self) -> dict | None:
        """The numerical environment the genome's stored results were made in (:mod:`evobiped.core.provenance`);
        None for files written before it was recorded."""
        env = self.meta.get("environment")
        return env if isinstance(env, dict) else None

    def stored_outcome(self) -> dict | None:
        """What the walker did when it was stored, as :func:`evobiped.files.outcome.compare` reads it: the file's
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
        name = f"{self.run_dir.name} ({self.label})" if self.run_dir is not None else self.genome_path.stem
        return name.encode(errors="surrogateescape").decode(errors="replace")  # a path's undecodable bytes: shown as �


def resolve(source: str | Path, generation: int | None = None, allow_unfinished: bool = False) -> Source:
    """Load the genome named by ``source`` (``generation``: a run directory's best of that generation; a run another
    process is writing only with ``allow_unfinished``: :func:`evobiped.files.rundir.resolve_genome`)."""
    found = rundir.resolve_genome(source, generation, allow_unfinished)
    return Source(**{f.name: getattr(found, f.name) for f in dataclasses.fields(found)})
