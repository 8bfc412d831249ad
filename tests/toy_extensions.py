"""A toy body, optimizer and fitness term, written from outside the package as extensions are: each one declaration
here and one registration line (tests/test_extension_doors.py registers them and sees every derived thing follow).

* :class:`ToyBiped` (``toy``): Reil's body under another name, its own Gymnasium environment's declaration;
* :class:`RandomSearch` (``random``): keeps the best genome, draws the rest of each generation anew from the
  layout's initial distribution (generation g's stream);
* :data:`TOY_TERMS`: ``lateral``, the displacement to the left of the initial facing (m), per episode, and
  ``ticks_up``, the control ticks each row stepped healthy, kept per tick in the state's ``kept``; reported when
  the weights name ``lateral``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from evobiped.bodies.reil import ReilBiped
from evobiped.core.options import option
from evobiped.interface.contract import Environment
from evobiped.optimizers.base import Optimizer, PopulationState
from evobiped.tasks.terms import Term, TermGroup


class ToyBiped(ReilBiped):
    """Reil & Husbands' walker under another name."""

    name: ClassVar[str] = "toy"
    environment: ClassVar[Environment] = Environment("a toy: Reil's biped renamed", "PD target angles (rad)", 0.02)


@dataclass(frozen=True, kw_only=True)
class RandomOptions:
    """Options of the random search."""

    population: int = option(6, "genomes per generation", low=2, high=10**6, integer=True)


@dataclass(frozen=True, kw_only=True, eq=False)
class RandomState(PopulationState):
    """The random search between generations: generation, population ``(P, G)``, its fitness ``(P,)``."""

    name = "random"


class RandomSearch(Optimizer):
    """The best so far and ``population - 1`` fresh draws per generation."""

    name, Options, table, about = "random", RandomOptions, "random", "random search (a toy)"

    def __init__(self, layout, config: RandomOptions, **start):
        super().__init__(layout, config, **start)
        self.generation = 0
        self.population = self.layout.sample(self.rng(0), config.population)
        self.fitness = np.full(config.population, np.nan)

    def next_generation(self) -> np.ndarray:
        best = int(self.ranking()[0])
        self.generation += 1
        drawn = self.layout.sample(self.rng(self.generation), self.config.population - 1)
        self.population = np.concatenate([self.population[best:best + 1], drawn])
        self.fitness = np.concatenate([self.fitness[best:best + 1], np.full(len(drawn), np.nan)])
        return np.concatenate([[best], np.full(len(drawn), -1)])

    def state(self) -> RandomState:
        return RandomState(generation=self.generation, population=self.population, fitness=self.fitness)

    def restore(self, state: RandomState) -> None:
        self.population, self.fitness = np.array(state.population), np.array(state.fitness, float)
        self.generation = int(state.generation)

    def _state_from(self, table: dict) -> RandomState:
        return RandomState.from_table(table, self.layout.size)


def _lateral(task, state, out) -> dict[str, np.ndarray]:
    d, f = state.position - state.start, state.facing
    return {"lateral": f[:, 0] * d[:, 1] - f[:, 1] * d[:, 0], "ticks_up": state.kept["ticks_up"].copy()}


def _count(task, body, sims, state, ok, neurons) -> None:
    state.kept["ticks_up"][ok] += 1


TOY_TERMS = TermGroup(
    (Term("lateral", "m", "the displacement to the left of the initial facing"),
     Term("ticks_up", "", "control ticks stepped healthy")), "weights naming lateral",
    lambda task: "lateral" in task.weights, _lateral, tick=_count,
    start=lambda task, body, sims, state: {"ticks_up": np.zeros(sims.n)})
