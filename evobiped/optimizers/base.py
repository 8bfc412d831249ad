"""What every optimizer shares: the ask/tell seam over a population, its construction and its random stream.

An optimizer holds ``population`` ``(P, G)`` and ``fitness`` ``(P,)`` (NaN: not yet
evaluated).  ``ask()`` gives the population and the rows to evaluate; ``tell(result)``
takes their :class:`~evobiped.episode.result.EpisodeResult` (or their fitness alone);
``next_generation()`` moves the fitness along with the individuals it keeps and
returns, for each new row, the previous row it is (-1: a new individual), so that the
run carries each individual's outcome (:mod:`evobiped.run.individuals`) and
never reorders anything.  Fitness: higher is better; an unstable row (a fitness that is not a finite number)
ranks last (-inf).

Every optimizer is made alike, ``cls(layout, options, seed=, initial=, mutable=)`` (:meth:`Optimizer.__init__`: the
genome layout, its settings, the run seed, a start genome, the genes it may change), draws generation g's random
numbers from (run seed, g) alone (:meth:`Optimizer.rng`), and registers (:data:`evobiped.optimizers.OPTIMIZERS`) its
name, its ``Options`` and the config table they are read from.

Between generations an optimizer is a value: :meth:`Optimizer.state` gives a frozen
:class:`OptimizerState` (its subclass per optimizer), which the checkpoint stores as
``state.to_dict()`` under the key ``optimizer``; :meth:`Optimizer.restore` puts an
optimizer in that state, and a run resumed from it continues exactly as an
uninterrupted one.  A checkpoint's lists of numbers are read by one reader, :meth:`OptimizerState.numbers_of`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Callable, ClassVar

import numpy as np

from ..core.errors import ConfigError, UserError
from ..interface.genome import GenomeLayout

#: the largest population any optimizer accepts (memory is checked against the machine too: ``run_config.check_memory``)
MAX_POPULATION = 10**7


def generation_rng(seed: int, generation: int) -> np.random.Generator:
    """The random stream of one generation, from (run seed, generation) only."""
    return np.random.default_rng([int(seed), int(generation), 0x6A])


def frozen_array(values: Any) -> np.ndarray:
    """A read-only float copy of ``values`` (a state's arrays never change after it is made)."""
    a = np.array(values, float)
    a.setflags(write=False)
    return a


@dataclass(frozen=True, kw_only=True, eq=False)
class OptimizerState:
    """An optimizer between generations: which one, its generation and the fitness of its population ``(P,)``
    (NaN: not yet evaluated, -inf: unstable).  Subclasses add what their optimizer needs."""

    #: the optimizer's registry name (``ga``, ``cma``)
    name: ClassVar[str] = ""
    generation: int
    fitness: np.ndarray

    def to_dict(self) -> dict:
        """The checkpoint's JSON table (its ``optimizer`` key)."""
        raise NotImplementedError

    @staticmethod
    def written_by(table: Any) -> str:
        """The optimizer that wrote a checkpoint's table (``name``; a checkpoint of before the state had a name:
        ``optimizer``, and one older still none: the GA)."""
        if not isinstance(table, dict):
            raise UserError(f"checkpoint: the optimizer's state must be a table, got {type(table).__name__}")
        return table.get("name", table.get("optimizer", "ga"))

    @classmethod
    def generation_of(cls, table: dict) -> int:
        gen = table.get("generation")
        if isinstance(gen, bool) or not isinstance(gen, int) or gen < 0:
            raise UserError(f"checkpoint: {cls.name}.generation must be a whole number >= 0, got {gen!r}")
        return gen

    @classmethod
    def numbers_of(cls, table: dict, key: str, *, null: float | None = None, rows: int | None = None,
                   length: int | None = None, minus_infinity: bool = False, non_empty: bool = False) -> np.ndarray:
        """``table[key]`` of a checkpoint as an array: a list of finite numbers ``(n,)`` (``null``: the value a null
        reads as, e.g. NaN for a value not yet known; None: no nulls), of ``length`` entries when given, or with
        ``rows`` = W a list of rows of W finite numbers ``(n, W)``; ``minus_infinity``: -Infinity (an unstable row) is a
        number too; ``non_empty``: at least one entry.  UserError, one line naming ``<optimizer>.<key>``, for anything
        else."""
        vals = table.get(key)

        def number(x) -> bool:
            if x is None:
                return null is not None
            return isinstance(x, (int, float)) and not isinstance(x, bool) and (math.isfinite(x)
                                                                                or (minus_infinity and x == -math.inf))

        wanted = ("finite numbers" + (", -Infinity" if minus_infinity else "")
                  + (" or nulls" if null is not None else "")
                  if rows is None else f"rows of {rows} finite numbers")
        if rows is None:
            ok = isinstance(vals, list) and all(map(number, vals))
        else:
            ok = isinstance(vals, list) and all(isinstance(r, list) and len(r) == rows and all(map(number, r))
                                                for r in vals)
        ok = ok and (length is None or len(vals) == length) and (not non_empty or len(vals) > 0)
        if not ok:
            raise UserError(f"checkpoint: {cls.name}.{key} must be a {'non-empty ' if non_empty else ''}list of "
                            f"{'' if length is None else f'{length} '}{wanted}")
        value = lambda x: null if x is None else float(x)  # noqa: E731
        if rows is None:
            return np.array([value(x) for x in vals], float)
        return np.array([[value(x) for x in r] for r in vals], float).reshape(-1, rows)


@dataclass(frozen=True, kw_only=True, eq=False)
class PopulationState(OptimizerState):
    """An optimizer whose state is its population ``(P, G)`` and their fitness ``(P,)`` (read-only arrays; the GA's,
    an extension's): written as ``name``, ``generation``, ``population`` and ``fitness`` (null: not yet evaluated)."""

    population: np.ndarray

    def __post_init__(self):
        object.__setattr__(self, "population", frozen_array(self.population))
        object.__setattr__(self, "fitness", frozen_array(self.fitness))

    def to_dict(self) -> dict:
        return {"name": self.name, "generation": self.generation, "population": self.population.tolist(),
                "fitness": [None if np.isnan(f) else float(f) for f in self.fitness]}

    @classmethod
    def from_table(cls, table: dict, genes: int):
        """The state a checkpoint's table holds, each field checked (one UserError naming the first bad one) for
        genomes of ``genes`` genes."""
        pop = cls.numbers_of(table, "population", rows=genes, non_empty=True)
        return cls(generation=cls.generation_of(table), population=pop,
                   fitness=cls.numbers_of(table, "fitness", null=np.nan, length=len(pop), minus_infinity=True))


class Optimizer:
    """Base of the optimizers: what they are made from, their random stream and the ask/tell seam.  A subclass registers
    (:data:`evobiped.optimizers.OPTIMIZERS`) with ``name``, ``Options`` (its settings' frozen dataclass), ``table`` (the
    run config's table they are read from) and ``about``; it sets ``population`` and ``fitness`` and makes the next
    generation."""

    #: the registry name (``--optimizer``, config ``optimizer``, a checkpoint state's ``name``)
    name: ClassVar[str] = ""
    #: its settings: a frozen dataclass of ``option`` fields
    Options: ClassVar[type]
    #: the run config's table its settings are read from (``[ga]``) and written to (config.json)
    table: ClassVar[str] = ""
    #: what it is, in a few words (the ``optimizer`` option's and ``--optimizer``'s help)
    about: ClassVar[str] = ""
    #: a paragraph docs/usage.md gives above its generated option table (markdown; "": none)
    docs_note: ClassVar[str] = ""
    #: config.json holds this table in every run (the GA's and CMA-ES's, as it always has), not only in this
    #: optimizer's runs when its settings differ from the defaults
    always_written: ClassVar[bool] = False
    #: its ``evaluation_rows()`` stand for the generation (ES's theta): history.csv reports how they did
    reports_evaluation_rows: ClassVar[bool] = False
    population: np.ndarray
    fitness: np.ndarray
    generation: int

    def __init__(self, layout: GenomeLayout, config: Any, *, seed: int, initial: np.ndarray | None = None,
                 mutable: np.ndarray | None = None):
        """``layout``: the genomes' layout (G genes); ``config``: its ``Options``; ``seed``: the run seed; ``initial``:
        a start genome ``(G,)`` or rows of them ``(n, G)`` (None: the layout's initial distribution or mean);
        ``mutable`` ``(G,)`` bool: the genes it may change (None: all).  ConfigError for a mask that changes nothing
        or does not fit, UserError for a start genome that does not fit the layout."""
        self.layout, self.config, self.seed = layout, config, int(seed)
        self.low, self.high = layout.low, layout.high
        self.mutable = np.ones(layout.size, bool) if mutable is None else np.asarray(mutable, bool)
        if self.mutable.shape != (layout.size,) or not self.mutable.any():
            raise ConfigError("the mutable-gene mask must have one entry per gene and at least one True")
        #: the start genomes ``(n, G)`` (None: none)
        self.initial = None if initial is None else layout.validate(initial, what="initial genome")

    def rng(self, generation: int) -> np.random.Generator:
        """Generation ``generation``'s random stream (:func:`generation_rng`: from the run seed and it alone)."""
        return generation_rng(self.seed, generation)

    def start_point(self) -> np.ndarray:
        """One point ``(G,)`` to start a search from: the first start genome, else the layout's ``init_mean``, within
        the genes' bounds."""
        return np.clip(self.layout.init_mean if self.initial is None else self.initial[0], self.low,
                       self.high).astype(float)

    # ---- what the run asks of the registered class before it makes one
    @classmethod
    def population_size(cls, options: Any, n_genes: int) -> int:
        """Walkers evaluated per generation with settings ``options`` for genomes of ``n_genes`` genes."""
        return int(options.population)

    @classmethod
    def population_setting(cls, population: int) -> tuple[str, int]:
        """The setting (name, value) of this optimizer's table that ``--population`` gives."""
        return "population", population

    @classmethod
    def resolved(cls, options: Any, scored_differently: Callable[[], bool]) -> Any:
        """``options`` with what depends on the run decided (``scored_differently()``: the run scores one generation
        differently from another); default: as given."""
        return options

    @classmethod
    def check_episode(cls, options: Any, episode) -> None:
        """ConfigError (one line) when ``options`` ask the episode config's task for what it has not (e.g. a term);
        default: nothing asked (its parts are not built here)."""

    def ask(self) -> tuple[np.ndarray, np.ndarray]:
        """The population ``(P, G)`` and a bool mask ``(P,)`` of the individuals whose fitness is unknown."""
        return self.population, np.isnan(self.fitness)

    def tell(self, result) -> None:
        """The results of the unknown individuals, in order: an EpisodeResult (fitness and outcome, ``(n_unknown,)``
        each) or their fitness alone ``(n_unknown,)``."""
        unknown = np.isnan(self.fitness)
        fitness = np.asarray(getattr(result, "fitness", result), float)
        if fitness.shape != (int(unknown.sum()),):
            raise ValueError(f"tell: expected {int(unknown.sum())} fitness values, got {fitness.shape}")
        # an undefined fitness (should not happen: unstable runs score as falls) ranks last
        self.fitness[unknown] = np.where(np.isfinite(fitness), fitness, -np.inf)

    def evaluation_rows(self) -> np.ndarray | None:
        """The rows that stand for the generation (ES's theta: the run's curriculum watches them, its running normaliser
        learns from their senses); None (this default): the fittest row does, and every evaluated row is learnt from."""
        return None

    def state(self) -> OptimizerState:
        """This optimizer between generations, as a frozen value (what the checkpoint stores)."""
        raise NotImplementedError

    def restore(self, state: OptimizerState) -> None:
        """Put the optimizer in ``state`` (UserError, one line, when it does not fit this run)."""
        raise NotImplementedError

    def _resample_with_fitness(self, fitness: Any, what: str) -> None:
        """Draw the restored generation's population again (``self._sample()``, from the restored random state) and
        take its stored ``fitness`` (one value per row, NaN where not yet evaluated); UserError naming ``what`` (the
        optimizer, as the checkpoint calls it) when the counts differ."""
        self._sample()
        if len(fitness) != len(self.population):
            raise UserError(f"checkpoint: the {what} state's fitness must have {len(self.population)} values (finite "
                            "or null)")
        self.fitness = np.array(fitness, float)

    def state_from(self, table: Any) -> OptimizerState:
        """The state a checkpoint's table holds (UserError naming the field when it is malformed, or when
        another optimizer wrote it)."""
        got = OptimizerState.written_by(table)
        if got != self.name:
            raise UserError(
                f"the checkpoint was written by the {got!r} optimizer; this run's config uses {self.name!r}")
        return self._state_from(table)

    def _state_from(self, table: dict) -> OptimizerState:
        raise NotImplementedError

    # : the optimizer keeps an archive of elites (:meth:`archive_contents`), which the run directory keeps as
    # archive.json
    keeps_archive = False

    def archive_contents(self) -> Any:
        """Its archive after a committed generation (an :class:`~evobiped.files.rundir.archive_file.ArchiveContents`),
        when :attr:`keeps_archive`; the run directory writes the file."""
        raise NotImplementedError

    def series(self) -> dict[str, np.ndarray]:
        """This optimizer's own numbers per committed generation (name -> ``(generations,)``), recorded in the run's
        evolution.rrd beside the history (``evolution/optimizer/<name>``); default none."""
        return {}

    def ranking(self) -> np.ndarray:
        """Indices best first; ties keep population order (stable)."""
        return np.argsort(-self.fitness, kind="stable")

    #: whether :meth:`start_over` starts the search over (the lost-run rule's ``action = "restart"``)
    starts_over: ClassVar[bool] = False

    def start_over(self) -> np.ndarray:
        """Start the search over at the current generation, after :meth:`next_generation`: the population drawn anew
        (this generation's random stream), what the search learnt forgotten; returns the new rows' previous rows (all
        -1: every individual is new).  Only where :attr:`starts_over` says so."""
        raise NotImplementedError(f"the {self.name} optimizer cannot start over")

    def parent_rows(self) -> np.ndarray | None:
        """After ``next_generation()``: for each new row, the previous generation's row it was bred from (-1: none,
        e.g. a survivor); None (this default): the optimizer does not say (it samples a distribution).  Optional:
        the run writes it into individuals.jsonl only."""
        return None
