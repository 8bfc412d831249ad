"""A repertoire adapting to damage: trials of its walking elites on the damaged body, chosen by intelligent trial and
error."""

from __future__ import annotations

import dataclasses
import itertools

import numpy as np

from ..analysis.retest import FRESH_GENERATION
from .damage import Damage, damaged_episode
from .elites import Repertoire
from .trial_error import Attempt, TrialAndError, prior_distance

#: m in 50 s without a fall: a gait that walks on the damaged body
WALKS = (10.0, 50.0)


def candidates(rep: Repertoire, seconds: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The walking elites' rows ``(E,)``, their measures scaled to [0, 1] by the archive's bounds ``(E, 2)`` and their
    prior distance in ``seconds`` s ``(E,)`` m."""
    rows = np.flatnonzero(rep.walking())
    a = rep.archive
    x = np.clip((a.values[rows] - a.low) / (a.high - a.low), 0, 1)
    return rows, x, prior_distance(rep.measure("speed")[rows], rep.measure("turning")[rows], seconds)


def adapt(rep: Repertoire, damage: Damage | None, *, seconds: float = WALKS[1], search: TrialAndError = TrialAndError(),
          pose_noise: float = 0.0, seed: int = 0) -> tuple[list[Attempt], np.ndarray]:
    """Intelligent trial and error on the body with ``damage``, each trial ``seconds`` s, nominal, or with
    ``pose_noise`` > 0 each trial's initial joint angles off by Gaussian noise of that sd (rad), the n-th trial of a
    search drawn under the key (``seed``, 10⁷ + n) whichever elite it tries (a generation no run reaches: no schedule
    or assistance of the archive's run applies); only a trial that walks (:func:`walks`) ends the
    search early.  Returns the trials (``Attempt.elite``: a row of the archive) and the prior distances of the
    candidates ``(E,)``."""
    perturbations = {"presentations": 1, "pose_noise": float(pose_noise)} if pose_noise > 0 else {}
    episode = dataclasses.replace(rep.episode, seconds=seconds, perturbations=perturbations)
    ep = damaged_episode(episode, damage)
    rows, x, prior = candidates(rep, seconds)
    drawn = itertools.count(FRESH_GENERATION)  # the n-th trial's key: (seed, 10^7 + n)

    def trial(k: int) -> tuple[float, bool, float, float]:
        key = (seed, next(drawn))
        r = ep.run(rep.archive.genome[rows[k]][None], trials=ep.trials_for(key) if perturbations else None)
        return float(r.walk()["distance"]), bool(r.fell[0]), float(r.end_time[0]), seconds

    trials = search.run(x, prior, trial, acceptable=walks)
    return [dataclasses.replace(t, elite=int(rows[t.elite])) for t in trials], prior


def walks(t: Attempt) -> bool:
    """The trial walked: at least 10 m without a fall (in a 50 s trial)."""
    return not t.fell and t.distance >= WALKS[0]
