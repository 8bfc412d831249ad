"""What every optimizer shares: the ask/tell seam over a population.

An optimizer holds ``population`` ``(P, G)`` and ``fitness`` ``(P,)`` (NaN: not yet
evaluated).  ``ask()`` gives the population and the rows to evaluate; ``tell(result)``
takes their :class:`~evobiped.episode.EpisodeResult` (or their fitness alone);
``next_generation()`` moves the fitness along with the individuals it keeps and
returns, for each new row, the previous row it is (-1: a new individual), so that the
run carries each individual's outcome (:mod:`evobiped.evolution.individuals`) and
never reorders anything.  Fitness: higher is better.
"""

from __future__ import annotations

import numpy as np


class Optimizer:
    """Base of the optimizers (``ga``, ``cma``); subclasses set ``population`` and ``fitness`` and make the next generation."""

    name = ""
    population: np.ndarray
    fitness: np.ndarray
    generation: int

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

    def ranking(self) -> np.ndarray:
        """Indices best first; ties keep population order (stable)."""
        return np.argsort(-self.fitness, kind="stable")
