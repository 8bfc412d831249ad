"""CMA-ES beside the paper's GA, behind the same ask/tell seam (pycma).

The library is ``cma`` (pycma, Hansen's reference implementation): maintained
by the method's author, pure Python + numpy, with bound handling, the standard
(mu/mu_w, lambda) update and its stopping rules.  Only the random numbers are
ours: every generation's samples come from (run seed, generation) through a
normal generator handed to pycma as its ``randn`` option.  The checkpoint
stores pycma's strategy itself as data (:mod:`.cma_state`: its mean, step
size, covariance, paths and counters, every bit; not a pickle, which a tampered
file could abuse), so a resume costs the same at any generation and asks
exactly the solutions an uninterrupted run asks.  A checkpoint of before
(``told``: the fitness told at every generation) is replayed from the run seed.

Search space.  CMA-ES runs in coordinates normalised to each gene's range,
z = (gene - low) / (high - low) in [0, 1]^G, bounded there by pycma's
``BoundTransform``; the initial mean is the layout's ``init_mean`` (for the
CTRNN: zero weights, mid time constants, zero biases) and the initial step
``sigma0`` is a fraction of every gene's range.

Restarts (``restarts`` > 0): when pycma's own stopping rules fire (e.g. the
step size collapsed or the fitness went flat), the strategy starts again from
the initial mean with twice the population (IPOP-CMA-ES, Auger & Hansen 2005).
The population size changes at a restart.

Fitness is higher-is-better, as everywhere in evobiped (pycma minimises -f).
"""

from __future__ import annotations

import importlib.util
import math
import warnings
from dataclasses import dataclass

import numpy as np

from ..core.errors import ConfigError, UserError
from ..core.options import check_fields, option
from . import cma_state
from .base import MAX_POPULATION, Optimizer, OptimizerState, frozen_array


def _population(p) -> None:
    if not (isinstance(p, int) and not isinstance(p, bool) and (p == 0 or 2 <= p <= MAX_POPULATION)):
        raise ConfigError(f"must be a whole number in [2, {MAX_POPULATION:.0e}] (or 0 for the default), got {p!r}")


@dataclass(frozen=True, kw_only=True)
class CMAOptions:
    """CMA-ES settings."""

    population: int = option(0, "lambda, offspring per generation; 0: pycma's default 4 + floor(3 ln G)",
                             check=_population, span=f"0, or 2 to {MAX_POPULATION:.0e}")
    sigma0: float = option(0.1, "initial step size, a fraction of every gene's range", above=0, high=1)
    restarts: int = option(0, "IPOP restarts allowed (the population doubles at each)", low=0, high=10, integer=True)
    diagonal: bool = option(False, "separable CMA-ES: a diagonal covariance (linear cost per gene: for thousands of "
                                   "genes, e.g. tuning a distilled network)")

    def __post_init__(self):
        check_fields(self, "cma")

    def lam(self, n_genes: int) -> int:
        """Offspring per generation for ``n_genes`` genes."""
        return self.population or 4 + int(3 * math.log(n_genes))


@dataclass(frozen=True, kw_only=True, eq=False)
class CMAState(OptimizerState):
    """CMA-ES between generations: pycma's strategy as data (``strategy``, :func:`.cma_state.encode`), the
    IPOP restarts so far (``restart``) and the current population's fitness ``(lam,)``.  A state read from a
    checkpoint of before has ``told`` instead (one read-only ``(lam,)`` array per generation, replayed from the run
    seed) and no strategy."""

    name = "cma"
    told: tuple[np.ndarray, ...] = ()
    strategy: dict | None = None
    restart: int = 0

    def __post_init__(self):
        object.__setattr__(self, "told", tuple(frozen_array(f) for f in self.told))
        object.__setattr__(self, "fitness", frozen_array(self.fitness))

    def to_dict(self) -> dict:
        plain = lambda a: [float(x) if np.isfinite(x) else None for x in a]  # noqa: E731
        return {"name": self.name, "generation": self.generation, "restart": self.restart,
                "fitness": plain(self.fitness), "strategy": self.strategy}


class GenerationNormal:
    """pycma's ``randn``: standard normal samples from a generator that the optimiser re-seeds every generation."""

    def __init__(self):
        self.rng = np.random.default_rng(0)

    def __call__(self, *shape):
        return self.rng.standard_normal(shape)


class CMAES(Optimizer):
    """Ask/tell CMA-ES over a :class:`GenomeLayout` with the GA's interface (:class:`~.base.Optimizer`).

    ``ask()`` -> ``(population (P, G), unknown (P,) bool)``; ``tell(result)`` of the unknown;
    ``ranking()`` best first; ``next_generation()`` (a fresh sample: no fitness or outcome is kept);
    ``state()`` / ``restore()``: its state as a frozen value (:class:`CMAState`) for the checkpoint.
    """

    name, Options, table, about, always_written = "cma", CMAOptions, "cma", "CMA-ES", True

    def __init__(self, layout, config: CMAOptions, **start):
        """As every optimizer (:meth:`Optimizer.__init__`); the initial mean is the start point (the start genome, else
        the layout's ``init_mean``)."""
        if importlib.util.find_spec("cma") is None:  # pragma: no cover - a core dependency
            raise UserError("the cma optimizer needs pycma: pip install cma")
        super().__init__(layout, config, **start)
        self.span = np.where(self.high > self.low, self.high - self.low, 1.0)
        self.x0 = self.start_point()
        self._rewind()

    @classmethod
    def population_size(cls, options: CMAOptions, n_genes: int) -> int:
        return options.lam(n_genes)

    def _rewind(self) -> None:
        self.generation = 0
        self.restart = 0
        self._start(self.restart)
        self._sample()

    # ---- pycma
    def _start(self, restart: int) -> None:
        import cma

        n = int(self.mutable.sum())
        self.normal = GenerationNormal()
        z0 = self._z(self.x0)[self.mutable]
        opts = {
            "bounds": [0.0, 1.0],
            "popsize": self.config.lam(n) * 2**restart,
            "randn": self.normal,
            "verbose": -9,
            "verb_disp": 0,
            "verb_log": 0,
        }
        if self.config.diagonal:
            opts["CMA_diagonal"] = True
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            self.es = cma.CMAEvolutionStrategy(z0, self.config.sigma0, opts)

    def _z(self, genes: np.ndarray) -> np.ndarray:
        return (genes - self.low) / self.span

    def _genes(self, z: np.ndarray) -> np.ndarray:
        """Normalised mutable coordinates ``(n, G_mutable)`` -> genomes ``(n, G)`` within bounds."""
        g = np.tile(self.x0, (len(z), 1))
        g[:, self.mutable] = self.low[self.mutable] + np.clip(z, 0.0, 1.0) * self.span[self.mutable]
        return np.clip(g, self.low, self.high)

    def _sample(self) -> None:
        self.normal.rng = self.rng(self.generation)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            self._asked = self.es.ask()
        self.population = self._genes(np.array(self._asked))
        self.fitness = np.full(len(self.population), np.nan)

    # ---- the next generation
    def next_generation(self) -> np.ndarray:
        """Tell pycma the generation and sample the next; every new row is a new individual (all -1)."""
        if np.isnan(self.fitness).any():
            raise RuntimeError("next_generation before every individual was evaluated")
        self._advance(self.fitness.copy())
        return np.full(len(self.population), -1)

    def _advance(self, f: np.ndarray) -> None:
        finite = np.isfinite(f)
        # pycma needs numbers: an unstable individual ranks below every finite one
        f = np.where(finite, f, (f[finite].min() if finite.any() else 0.0) - 1e6)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            self.es.tell(self._asked, list(-f))
        self.generation += 1
        if self.restart < self.config.restarts and self.es.stop():
            self.restart += 1
            self._start(self.restart)
        self._sample()

    def stop(self) -> list[str]:
        """The names of pycma's stopping rules that fired (e.g. ``tolfun``) with no restart left; empty while it goes
        on."""
        return sorted(self.es.stop())

    # ---- its state as a value
    def state(self) -> CMAState:
        return CMAState(generation=self.generation, fitness=self.fitness, restart=self.restart,
                        strategy=cma_state.encode(self.es, self._asked))

    def restore(self, state: CMAState) -> None:
        """Put the strategy in ``state``: pycma's stored strategy written into a fresh one (the same cost at any
        generation), or, for a checkpoint of before, the told fitness replayed from generation 0 (UserError when
        a generation's count does not fit this run)."""
        if state.strategy is None:
            self._replay(state.told)
        else:
            if state.restart > self.config.restarts:
                raise UserError(f"checkpoint: CMA-ES restart {state.restart} is beyond this run's "
                                f"{self.config.restarts} restarts")
            self.generation, self.restart = 0, state.restart
            self._start(self.restart)
            self._asked = cma_state.restore(self.es, state.strategy)
            if len(self._asked) != self.es.popsize:
                raise UserError(f"checkpoint: the CMA-ES strategy asked {len(self._asked)} solutions, its population "
                                f"is {self.es.popsize}")
            self.generation = state.generation
            self.population = self._genes(np.array(self._asked))
        # a restart may have happened after the last generation told: the population matches the state
        if len(state.fitness) != len(self.population):
            raise UserError(f"checkpoint: CMA-ES fitness must be a list of {len(self.population)} finite numbers or "
                            "nulls")
        self.fitness = np.array(state.fitness, float)

    def _replay(self, told) -> None:
        self._rewind()
        for g, f in enumerate(told):
            if len(f) != len(self.population):
                raise UserError(f"checkpoint: CMA-ES told[{g}] must be a list of {len(self.population)} finite numbers "
                                "or nulls")
            self._advance(np.array(f, float))

    def _state_from(self, table: dict) -> CMAState:
        fitness, generation = table.get("fitness"), CMAState.generation_of(table)
        if not isinstance(fitness, list):
            raise UserError("checkpoint: the CMA-ES state needs 'fitness' (a list)")
        if "strategy" in table:
            restart = table.get("restart")
            if not (isinstance(restart, int) and not isinstance(restart, bool) and restart >= 0):
                raise UserError(f"checkpoint: cma.restart must be a whole number >= 0, got {restart!r}")
            return CMAState(generation=generation, fitness=CMAState.numbers_of(table, "fitness", null=np.nan),
                            strategy=table["strategy"], restart=restart)
        told = table.get("told")
        if not (isinstance(told, list) and generation == len(told)):
            raise UserError("checkpoint: the CMA-ES state needs 'strategy' (or, from an older checkpoint, 'told': one "
                            "list per generation)")
        # a null told: an unstable individual (-inf); a null fitness: not yet evaluated
        return CMAState(generation=generation, told=tuple(CMAState.numbers_of({f"told[{g}]": f}, f"told[{g}]",
                                                                              null=-np.inf)
                                                          for g, f in enumerate(told)),
                        fitness=CMAState.numbers_of(table, "fitness", null=np.nan))
