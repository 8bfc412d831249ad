"""What every optimizer shares: the ask/tell seam over a population, and each individual's outcome.

An optimizer holds ``population`` ``(P, G)``, ``fitness`` ``(P,)`` (NaN: not yet
evaluated) and ``outcome``, the evaluation result of each individual beside its
fitness (``fell``, ``unstable`` (bool) and ``end_time`` (s), ``(P,)`` each; empty
until a result carrying them is told).  ``ask()`` gives the population and the
rows to evaluate; ``tell(result)`` takes their :class:`~evobiped.episode.EpisodeResult`
(or their fitness alone); ``next_generation()`` moves fitness and outcome along with
the individuals it keeps, so a caller reads row ``i``'s fitness and outcome together
and never reorders anything.  Fitness: higher is better.
"""

from __future__ import annotations

import numpy as np

from ..errors import UserError

#: the outcome of an individual beside its fitness: name -> value before it is known
OUTCOME = {"fell": False, "unstable": False, "end_time": np.nan}


class Optimizer:
    """Base of the optimizers (``ga``, ``cma``); subclasses set ``population`` and ``fitness`` and make the next generation."""

    name = ""
    population: np.ndarray
    fitness: np.ndarray
    generation: int

    def __init__(self):
        #: name -> ``(P,)`` array, see :data:`OUTCOME`
        self.outcome: dict[str, np.ndarray] = {}

    def ask(self) -> tuple[np.ndarray, np.ndarray]:
        """The population ``(P, G)`` and a bool mask ``(P,)`` of the individuals whose fitness is unknown."""
        return self.population, np.isnan(self.fitness)

    def tell(self, result) -> None:
        """The results of the unknown individuals, in order: an EpisodeResult (fitness and outcome, ``(n_unknown,)`` each)
        or their fitness alone ``(n_unknown,)``."""
        unknown = np.isnan(self.fitness)
        fitness = np.asarray(getattr(result, "fitness", result), float)
        if fitness.shape != (int(unknown.sum()),):
            raise ValueError(f"tell: expected {int(unknown.sum())} fitness values, got {fitness.shape}")
        # an undefined fitness (should not happen: unstable runs score as falls) ranks last
        self.fitness[unknown] = np.where(np.isfinite(fitness), fitness, -np.inf)
        if not hasattr(result, "fitness"):
            return
        for key, default in OUTCOME.items():
            vals = np.asarray(getattr(result, key))
            known = self.outcome.get(key)
            arr = np.full(len(self.fitness), default, dtype=vals.dtype) if known is None else known.copy()
            arr[unknown] = vals
            self.outcome[key] = arr

    def ranking(self) -> np.ndarray:
        """Indices best first; ties keep population order (stable)."""
        return np.argsort(-self.fitness, kind="stable")

    def _carry(self, rows: np.ndarray) -> None:
        """The new population's outcome: row ``i`` keeps the previous row ``rows[i]``'s (-1: none, zeros until told)."""
        rows = np.asarray(rows)
        for key, arr in self.outcome.items():
            new = np.zeros(len(rows), dtype=arr.dtype)
            new[rows >= 0] = arr[rows[rows >= 0]]
            self.outcome[key] = new

    # ---- the outcome in the checkpoint
    def outcome_dict(self) -> dict[str, list]:
        """The outcome as plain lists, for the checkpoint."""
        return {k: v.tolist() for k, v in self.outcome.items()}

    def load_outcome(self, outcome: dict[str, list]) -> None:
        """Restore :meth:`outcome_dict` (types checked by :func:`evobiped.rundir.validate_checkpoint`); UserError
        unless each list has one entry per individual."""
        P = len(self.population)
        if any(len(v) != P for v in outcome.values()):
            raise UserError(f"checkpoint: outcome lists must have one entry per individual ({P})")
        self.outcome = {k: np.array(v, dtype=float if k == "end_time" else bool) for k, v in outcome.items()}
