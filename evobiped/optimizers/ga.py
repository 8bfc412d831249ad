"""The genetic algorithm of Reil & Husbands 2002 (Sect. II-C, Table III), ask/tell.

* real-valued genes, initialised from per-type Gaussians (Table III) and
  clipped to their ranges;
* Gaussian mutation with per-type sigma and mean 0, at a per-locus rate that
  gives on average ``mutations_per_genome`` (1) changes per chromosome; values
  outside the range are clipped;
* rank-based truncation with fittest fraction 0.5: the top half survives
  unchanged, the bottom half is replaced by mutated copies of the top half;
* no crossover.

The GA knows nothing of neurons: it sees a :class:`GenomeLayout`'s bounds and
sigmas only.  Randomness for generation g comes from (seed, g) alone, so a run
resumed from a checkpoint continues exactly as an uninterrupted one.
Fitness: higher is better.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from ..core.errors import ConfigError, UserError
from ..core.options import check_fields, option
from .base import MAX_POPULATION, Optimizer, PopulationState


def _bool_or_none(v) -> None:
    if v is not None and not isinstance(v, bool):
        raise ConfigError(f"must be true or false, got {v!r}")


@dataclass(frozen=True, kw_only=True)
class GAOptions:
    """GA settings, the paper's values by default."""

    population: int = option(50, "individuals per generation", low=2, high=MAX_POPULATION, integer=True)
    fittest_fraction: float = option(0.5, "truncation: the fraction that survives unchanged", above=0, below=1)
    mutations_per_genome: float = option(1.0, "mean mutations per genome (per-locus rate = this / genome length)",
                                         above=0)
    reevaluate_survivors: bool | None = option(
        None, "evaluate the survivors again every generation; none: exactly when the run scores each generation "
              "differently (a running normaliser, a curriculum, disturbances or sources drawn per generation), so that "
              "survivors are not compared by a fitness scored under an earlier generation's context",
        check=_bool_or_none, span="`true`, `false`, none")

    def __post_init__(self):
        check_fields(self, "ga")
        if self.n_survivors < 1:
            raise ConfigError("ga.population * ga.fittest_fraction must keep at least one individual")

    @property
    def n_survivors(self) -> int:
        return int(round(self.population * self.fittest_fraction))


@dataclass(frozen=True, kw_only=True, eq=False)
class GAState(PopulationState):
    """The GA between generations: generation, population ``(P, G)`` and its fitness ``(P,)`` (read-only arrays)."""

    name = "ga"


class GA(Optimizer):
    """Ask/tell truncation GA (the optimizer named ``ga``; the seam is :class:`~.base.Optimizer`'s).

    ``ask()`` returns the current population ``(P, G)`` and a bool mask of the
    individuals whose fitness is unknown; ``tell(result)`` takes the results of
    those ``(n_unknown,)``; ``next_generation()`` builds the next generation, the
    survivors first (best first), keeping their fitness and outcome.
    """

    name, Options, table, about, always_written = "ga", GAOptions, "ga", "Reil & Husbands' GA", True

    def __init__(self, layout, config: GAOptions, **start):
        """As every optimizer (:meth:`Optimizer.__init__`); the population is ``config.population`` clones of the start
        genomes (repeated in order), or samples of the layout's initial distribution."""
        super().__init__(layout, config, **start)
        self.sigma = layout.mutation_sigma
        self.generation = 0
        self._first_population()

    def _first_population(self) -> None:
        """``population`` clones of the start genomes (repeated in order), or samples of the layout's initial
        distribution drawn from this generation's stream; fitness not yet known."""
        P = self.config.population
        if self.initial is None:
            self.population = self.layout.sample(self.rng(self.generation), P)
        else:  # clones of one genome (G,), or a population (n, G) repeated to size P
            self.population = self.initial[np.arange(P) % len(self.initial)].copy()
        self.fitness = np.full(P, np.nan)

    starts_over = True

    def start_over(self) -> np.ndarray:
        """Start over at this generation (:meth:`Optimizer.start_over`): a first population drawn anew."""
        self._first_population()
        return np.full(len(self.population), -1)

    @classmethod
    def resolved(cls, options: GAOptions, scored_differently) -> GAOptions:
        """``reevaluate_survivors`` none: the survivors are scored again exactly when the run scores each generation
        differently."""
        if options.reevaluate_survivors is None:
            return dataclasses.replace(options, reevaluate_survivors=scored_differently())
        return options

    @property
    def mutation_rate(self) -> float:
        """Per-locus probability: on average ``mutations_per_genome`` mutable genes change."""
        return min(1.0, self.config.mutations_per_genome / int(self.mutable.sum()))

    def next_generation(self) -> np.ndarray:
        """Truncation selection + mutation; call after the population is fully told.  Returns the previous row of
        each new individual (the survivors, best first), -1 for each child."""
        if np.isnan(self.fitness).any():
            raise RuntimeError("next_generation before every individual was evaluated")
        P, k = self.config.population, self.config.n_survivors
        order = self.ranking()
        parents = order[:k]
        children_of = parents[np.arange(P - k) % k]
        self.generation += 1
        rng = self.rng(self.generation)
        children = self.mutate(self.population[children_of], rng)
        self.population = np.concatenate([self.population[parents], children])
        fit = np.full(P, np.nan)
        if not self.config.reevaluate_survivors:
            fit[:k] = self.fitness[parents]
        self.fitness = fit
        self._bred_from = np.concatenate([np.full(k, -1), children_of])
        return np.concatenate([parents, np.full(P - k, -1)])

    def parent_rows(self) -> np.ndarray | None:
        """Each child's parent row in the previous generation (-1: a survivor), after :meth:`next_generation`."""
        return getattr(self, "_bred_from", None)

    def mutate(self, genomes: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """Gaussian mutation per locus with probability :attr:`mutation_rate`, clipped."""
        hit = (rng.random(genomes.shape) < self.mutation_rate) & self.mutable
        noise = rng.normal(0.0, 1.0, genomes.shape) * self.sigma
        return np.clip(np.where(hit, genomes + noise, genomes), self.low, self.high)

    # ---- its state as a value
    def state(self) -> GAState:
        return GAState(generation=self.generation, population=self.population, fitness=self.fitness)

    def restore(self, state: GAState) -> None:
        """Put the GA in ``state``: ConfigError when its population has another shape than this run's, UserError
        (naming the gene) when a gene lies outside its bounds."""
        pop = np.asarray(state.population, float)
        if pop.shape != self.population.shape:
            raise ConfigError(f"checkpoint population has shape {pop.shape}, the config needs {self.population.shape}")
        if not np.isfinite(pop).all() or (pop < self.low).any() or (pop > self.high).any():
            i, j = np.argwhere(~(np.isfinite(pop) & (pop >= self.low) & (pop <= self.high)))[0]
            raise UserError(f"checkpoint: ga.population[{i}][{j}] = {pop[i, j]!r} is outside the gene's bounds "
                            f"[{self.low[j]:g}, {self.high[j]:g}]")
        self.population, self.fitness, self.generation = pop.copy(), np.array(state.fitness,
                                                                              float), int(state.generation)

    def _state_from(self, table: dict) -> GAState:
        return GAState.from_table(table, self.layout.size)
