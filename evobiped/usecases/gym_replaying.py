"""The replay of a genome evolved in a Gymnasium environment: the same episode again (its reset seed from the run
seed and the generation it was scored in, :func:`~evobiped.episode.gym_episode.reset_seeds`), recorded into Rerun
(:mod:`evobiped.record.recordings.gym_recording`), its return compared with the stored fitness."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from ..core.provenance import differences
from ..record.source import Source


@dataclass
class GymReplay:
    """What a replay of an environment's episode did: its return, steps and whether the environment ended it."""

    fitness: float
    #: the fitness the source stored (None: none)
    stored_fitness: float | None
    steps: int
    terminated: bool
    recording: Path
    #: how this process's numerical environment differs from the stored one (empty: the same)
    environment_differences: list[str]

    @property
    def matches(self) -> bool:
        """The replayed return equals the stored fitness bit for bit."""
        return self.stored_fitness is not None and self.fitness == self.stored_fitness


def replay_env(source: Source, target: Path) -> GymReplay:
    """Re-run ``source`` (a genome of an environment's episode) once, recorded to ``target``; the reset key is
    (its run seed, its generation) where the file names them, else the genome alone."""
    from ..record.recordings.gym_recording import GymRecorder, write_gym_recording

    from .replaying import _history

    episode = source.config.build()
    seed, generation = source.meta.get("seed"), source.meta.get("generation")
    key = (int(seed), int(generation)) if isinstance(seed, int) and isinstance(generation, int) else None
    recorder = GymRecorder()
    result = episode.run(source.genome[None, :], trials=episode.trials_for(key), listener=recorder)
    write_gym_recording(target, recorder, name=f"{source.config.env}/{source.config.controller}: {source.genome_path}",
                        history=_history(source))
    stored = source.meta.get("fitness")
    return GymReplay(fitness=float(result.fitness[0]),
                     stored_fitness=float(stored) if isinstance(stored, (int, float)) else None,
                     steps=int(result.terms["length"][0]), terminated=bool(result.terms["terminated"][0]),
                     recording=target, environment_differences=differences(source.environment))
