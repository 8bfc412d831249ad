"""What a run tells its listeners at each commit: a derived file another part keeps (the Rerun recording of the run's
fitness, evolution.rrd, is :class:`evobiped.record.recordings.evolution_log.RecordingFile`), attached by the evolve use
case.  A listener is told inside the commit, after the run directory's own files (a stop signal waits for it, so
a run killed at any moment leaves it as the checkpoint says), and by a resume's rebuild."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Protocol

import numpy as np


@dataclass(frozen=True)
class Commit:
    """A committed state of a run, as its listeners see it."""

    #: the run directory
    directory: Path
    #: the history's columns (name -> ``(generations,)``, :func:`evobiped.files.rundir.history_columns`); None: no
    #: generation is committed yet
    columns: dict[str, np.ndarray] | None
    #: the run's recording id (the same for every session of the run)
    recording_id: str
    #: the optimizer's own numbers per committed generation (name -> ``(generations,)``; empty when none)
    series: dict[str, np.ndarray]
    #: a resume's repairs, where a listener notes a file it had to rebuild (one sentence each); None: a commit
    repairs: list[str] | None


class RunListener(Protocol):
    """Told of each commit of a run (and of the state a resume rebuilds)."""

    def committed(self, commit: Commit) -> None: ...
