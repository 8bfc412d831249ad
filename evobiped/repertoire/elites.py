"""A run's gait repertoire: its archive (archive.json) and the episode its genomes walk (the run's best.json).

A *walking* elite stayed up its whole evaluation and walked at least :data:`WALK_SPEED` m/s (the measure
``speed``, when the archive has it).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..files import rundir
from ..episode import EpisodeConfig
from ..core.errors import UserError
from ..files.rundir.archive_file import Archive, read_archive
from ..files.genome_file import load_genome
from ..record.source import Source

#: m/s: the least mean forward speed of a walking elite
WALK_SPEED = 0.2
#: how near a commanded speed (a fraction of it) and turning rate (deg/s) an elite must be to count as that gait
SPEED_TOLERANCE, TURNING_TOLERANCE = 0.05, 3.0


@dataclass(frozen=True)
class Repertoire:
    """The archive of a map-elites run directory and the episode (``EpisodeConfig``) its genomes were evaluated in."""

    run_dir: Path
    archive: Archive
    episode: EpisodeConfig
    #: the numerical environment the run evaluated its genomes in (best.json's; None: not recorded)
    environment: dict | None = None

    def measure(self, name: str) -> np.ndarray:
        """Every elite's value of measure ``name`` ``(E,)`` (UserError when the archive has no such measure)."""
        if name not in self.archive.measures:
            raise UserError(f"{self.archive.path}: the archive measures {' and '.join(self.archive.measures)}, not "
                            f"{name}")
        return self.archive.values[:, self.archive.measures.index(name)]

    def walking(self) -> np.ndarray:
        """Bool ``(E,)``: the elite stayed up its whole episode and (with a ``speed`` measure) walked >= WALK_SPEED
        m/s."""
        a = self.archive
        ok = ~a.fell & (a.end_time >= self.episode.seconds - 1e-9)
        return ok & (self.measure("speed") >= WALK_SPEED) if "speed" in a.measures else ok

    @property
    def outputs(self) -> Path:
        """Where commands write about this repertoire when not told: the run directory of a run evobiped made (it holds
        config.json); for an archive copied elsewhere (``docs/repertoire``, which may sit in a repository),
        ``runs/<its folder's name>`` under the current directory."""
        if (self.run_dir / rundir.CONFIG).is_file():
            return self.run_dir
        return rundir.GENOME_OUTPUTS / self.run_dir.resolve().name

    def source(self, cell: tuple[int, int]) -> Source:
        """The elite of grid cell ``cell`` as a genome to replay (its stored fitness: the archive's objective)."""
        k = self.archive.find(cell)
        a = self.archive
        meta = {"fitness": float(a.objective[k]), "fell": bool(a.fell[k]), "end_time": float(a.end_time[k]),
                **({"environment": self.environment} if self.environment else {})}
        path = self.outputs / f"cell_{cell[0]}_{cell[1]}.json"  # no such file: names what replay writes
        return Source(genome=a.genome[k].copy(), config=self.episode, meta=meta, genome_path=path, run_dir=self.outputs)

    def nearest(self, speed: float, turning: float = 0.0, like: int | None = None) -> int:
        """The walking elite whose (speed, turning) is nearest the commanded one, in cell widths; with ``like`` (an
        elite's row), among the walking elites within SPEED_TOLERANCE and TURNING_TOLERANCE of the command the one whose
        genome is nearest that elite's (the sum of gene differences over the archive's span of each gene: the gait most
        like the current one).  UserError naming the range the walking elites cover when the command is outside it."""
        walk = np.flatnonzero(self.walking())
        if not len(walk):
            raise UserError(f"{self.archive.path}: no elite walks yet")
        v, w = self.measure("speed")[walk], self.measure("turning")[walk]
        for name, x, have, unit in (("speed", speed, v, "m/s"), ("turning rate", turning, w, "deg/s")):
            if not have.min() <= x <= have.max():
                raise UserError(f"{name} {x:g} {unit} is outside the archive's walking gaits ({have.min():.3g} to "
                                f"{have.max():.3g} {unit})")
        near = (np.abs(v - speed) <= SPEED_TOLERANCE * speed) & (np.abs(w - turning) <= TURNING_TOLERANCE)
        if like is not None and near.any():
            g = self.archive.genome
            span = np.maximum(np.ptp(g, axis=0), 1e-12)
            return int(walk[near][np.argmin((np.abs(g[walk[near]] - g[like]) / span).sum(axis=1))])
        width = (self.archive.high - self.archive.low) / np.asarray(self.archive.resolution)
        d = ((v - speed) / width[0]) ** 2 + ((w - turning) / width[1]) ** 2
        return int(walk[np.argmin(d)])


def load_repertoire(run_dir: str | Path) -> Repertoire:
    """The repertoire of a map-elites run directory (UserError, one line, for anything else)."""
    path = Path(run_dir)
    if not path.is_dir():
        raise UserError(f"{path}: not a run directory (a map-elites run's directory holds archive.json)")
    archive = read_archive(path)
    if not (path / rundir.BEST).is_file():
        raise UserError(f"{path}: no {rundir.BEST}, so the episode its genomes walk is unknown")
    _, episode, meta = load_genome(path / rundir.BEST)
    return Repertoire(path, archive, episode, meta.get("environment") if isinstance(meta.get("environment"), dict)
                      else None)


def parse_cell(text: str) -> tuple[int, int]:
    """``"I,J"`` -> (I, J) (UserError otherwise)."""
    try:
        i, j = (int(x) for x in text.split(","))
    except ValueError:
        raise UserError(f"--cell: expected I,J (two whole numbers), got {text!r}") from None
    return i, j
