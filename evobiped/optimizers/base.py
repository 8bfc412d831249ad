"""What every optimizer shares: the ask/tell seam over a population.

An optimizer holds ``population`` ``(P, G)`` and ``fitness`` ``(P,)`` (NaN: not yet
evaluated).  ``ask()`` gives the population and the rows to evaluate; ``tell(result)``
takes their :class:`~evobiped.episode.result.EpisodeResult` (or their fitness alone);
``next_generation()`` moves the fitness along with the individuals it keeps and
returns, for each new row, the previous row it is (-1: a new individual), so that the
run carries each individual's outcome (:mod:`evobiped.run.individuals`) and
never reorders anything.  Fitness: higher is better.

Between generations an optimizer is a value: :meth:`Optimizer.state` gives a frozen
:class:`OptimizerState` (its subclass per optimizer), which the checkpoint stores as
``state.to_dict()`` under the key ``optimizer``; :meth:`Optimizer.restore` puts an
optimizer in that state, and a run resumed from it continues exactly as an
uninterrupted one.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from ..core.errors import UserError


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
        """The optimizer that wrote a checkpoint's table (``name``; a checkpoint of before the state had a name: ``optimizer``,
        and one older still none: the GA)."""
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
    def numbers_of(cls, table: dict, key: str, *, nulls: bool = False, rows: int | None = None) -> np.ndarray:
        """``table[key]`` of a checkpoint as an array: a list of finite numbers ``(n,)`` (with ``nulls``, null reads
        NaN: a value not yet known), or with ``rows`` = W a list of rows of W finite numbers ``(n, W)``; UserError,
        one line naming ``<optimizer>.<key>``, for anything else."""
        vals = table.get(key)

        def number(x) -> bool:
            return (x is None and nulls) or (isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x))

        if rows is None:
            ok = isinstance(vals, list) and all(map(number, vals))
            wanted = "finite numbers" + (" or nulls" if nulls else "")
        else:
            ok = isinstance(vals, list) and all(isinstance(r, list) and len(r) == rows and all(map(number, r)) for r in vals)
            wanted = f"rows of {rows} finite numbers"
        if not ok:
            raise UserError(f"checkpoint: {cls.name}.{key} must be a list of {wanted}")
        if rows is None:
            return np.array([np.nan if x is None else float(x) for x in vals])
        return np.array([[np.nan if x is None else float(x) for x in r] for r in vals]).reshape(-1, rows)


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

    def state(self) -> OptimizerState:
        """This optimizer between generations, as a frozen value (what the checkpoint stores)."""
        raise NotImplementedError

    def restore(self, state: OptimizerState) -> None:
        """Put the optimizer in ``state`` (UserError, one line, when it does not fit this run)."""
        raise NotImplementedError

    def state_from(self, table: Any) -> OptimizerState:
        """The state a checkpoint's table holds (UserError naming the field when it is malformed, or when
        another optimizer wrote it)."""
        got = OptimizerState.written_by(table)
        if got != self.name:
            raise UserError(f"the checkpoint was written by the {got!r} optimizer; this run's config uses {self.name!r}")
        return self._state_from(table)

    def _state_from(self, table: dict) -> OptimizerState:
        raise NotImplementedError

    def derived_files(self, generation_committed: bool) -> dict[str, str | None]:
        """Files of the run directory this optimizer derives from its state (name -> text; None: no such file yet),
        written at each commit and rebuilt on a resume; default none.  ``generation_committed``: a generation is."""
        return {}

    def series(self) -> dict[str, np.ndarray]:
        """This optimizer's own numbers per committed generation (name -> ``(generations,)``), recorded in the run's
        evolution.rrd beside the history (``evolution/optimizer/<name>``); default none."""
        return {}

    def ranking(self) -> np.ndarray:
        """Indices best first; ties keep population order (stable)."""
        return np.argsort(-self.fitness, kind="stable")

    def parent_rows(self) -> np.ndarray | None:
        """After ``next_generation()``: for each new row, the previous generation's row it was bred from (-1: none,
        e.g. a survivor); None (this default): the optimizer does not say (it samples a distribution).  Optional:
        the run writes it into individuals.jsonl only."""
        return None
