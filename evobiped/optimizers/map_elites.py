"""MAP-Elites (Mouret & Clune 2015): a repertoire of gaits, one elite per cell of a grid over two measures.

The archive is pyribs' :class:`ribs.archives.GridArchive` (``pip install 'evobiped[qd]'``): each
evaluated genome lands in the cell of its measures (two task terms, e.g. the walk task's ``speed``
m/s and ``turning`` deg/s; values beyond the bounds fall in the edge cells) and stays there if its
objective beats the cell's elite; of a batch's genomes in one cell the best, the first on a tie.  The
objective is the task's fitness plus ``objective_terms`` (task terms, weighted): a fitness that
saturates (the time up of a walker that never falls) keeps a cell's first survivor for ever, where
e.g. ``{distance = 0.05}`` keeps the one that went furthest.  Each elite keeps its task fitness beside
(``task_fitness``, what archive.json calls its ``objective`` and a replay compares).  The QD score is
the sum over the elites of (objective - ``qd_offset``) (pyribs' ``qd_score_offset``): it grows with
every cell filled or improved only if ``qd_offset`` is at or below every objective the task can give.  Each generation
asks ``batch`` new genomes: a uniformly drawn elite plus Gaussian noise of ``sigma`` times each gene's range (``parents
= "up"``: an elite that did not fall), and with ``line_sigma`` > 0 a step along the line to a second drawn elite
(Vassiliades & Mouret 2018's iso+line variation), clipped to the genes' bounds.  The first batch, while the archive is
empty, is the start genome (``--from``: it and its mutants) or the layout's initial distribution.

Why not pyribs' emitters: they draw parents from the archive's private random generator, whose
state the public API cannot give a checkpoint; here parents and noise come from (run seed,
generation) only, elites taken in cell order, so a run resumed from its checkpoint (the elites as
data: :class:`MapElitesState`) continues bit for bit on any number of workers.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..core.errors import ConfigError, UserError
from ..core.fileio import packed_floats, unpacked_floats
from ..core.options import check_fields, option
from ..files.rundir.archive_file import ArchiveContents
from .base import MAX_POPULATION, Optimizer, OptimizerState, frozen_array

#: what an elite keeps beside its genome, objective and measures (its outcome, and the task's fitness)
OUTCOME = ("fell", "end_time", "task_fitness")


def _names(v) -> None:
    if not (isinstance(v, list) and len(v) == 2 and all(isinstance(x, str) and x for x in v) and v[0] != v[1]):
        raise ConfigError(f"must be two different term names, got {v!r}")


def _resolution(v) -> None:
    if not (isinstance(v, list) and len(v) == 2 and all(isinstance(x, int) and not isinstance(x, bool) for x in v)):
        raise ConfigError(f"must be two whole numbers of cells, got {v!r}")
    if min(v) < 1 or max(v) > 1000:
        raise ConfigError(f"cells per measure must be 1 to 1000, got {v!r}")


def _bounds(v) -> None:
    if not (isinstance(v, list) and len(v) == 2
            and all(isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)
                                                       for x in v)):
        raise ConfigError(f"must be two finite numbers, got {v!r}")


def _weights(v) -> None:
    if not (isinstance(v, dict) and all(isinstance(k, str) and isinstance(x, (int, float)) and not isinstance(x, bool)
                                        and math.isfinite(x) for k, x in v.items())):
        raise ConfigError(f"must be a table of finite weights by term name, got {v!r}")


@dataclass(frozen=True, kw_only=True)
class MapElitesOptions:
    """MAP-Elites settings (``[map_elites]``): the grid over two task terms and the variation."""

    measures: list = option(["speed", "turning"], "the two task terms each cell is measured by (walk task with "
                            "gait_measures: speed m/s, turning deg/s)", check=_names, span="two term names")
    resolution: list = option([30, 30], "cells along each measure", check=_resolution,
                              span="two whole numbers, 1 to 1000")
    low: list = option([0.0, -30.0], "each measure's lower bound, in its term's unit", check=_bounds,
                       span="two numbers")
    high: list = option([1.0, 30.0], "each measure's upper bound, in its term's unit", check=_bounds,
                        span="two numbers")
    batch: int = option(32, "genomes asked per generation", low=1, high=MAX_POPULATION, integer=True)
    sigma: float = option(0.02, "Gaussian step, a fraction of each gene's range", above=0, high=1)
    line_sigma: float = option(0.0, "step along the line to a second elite (0: Gaussian only)", low=0, high=2)
    parents: str = option("all", "`all`: parents drawn among every elite (Mouret & Clune); `up`: among the elites that "
                                 "did not fall, while any did not", choices=("all", "up"))
    qd_offset: float = option(0.0, "the QD score sums each elite's objective minus this (at or below every objective "
                                   "the task gives, the score only grows)", unit="objective units")
    objective_terms: dict = option({}, "task terms added, weighted, to the fitness as a cell's objective, {term = "
                                       "weight} (e.g. {distance = 0.05}: where the fitness saturates, the walker that "
                                       "went furthest keeps the cell; {}: the fitness alone)", check=_weights,
                                   span="a table of weights")

    def __post_init__(self):
        check_fields(self, "map_elites")
        for k, (lo, hi) in enumerate(zip(self.low, self.high)):
            if not lo < hi:
                raise ConfigError(f"measure {self.measures[k]!r}: low {lo:g} must be below high {hi:g}")

    def check_terms(self, terms: tuple[str, ...], task: str) -> None:
        """ConfigError unless both measures are terms of the task (``terms``: its ``term_names``)."""
        for name, asked in (("measures", self.measures), ("objective_terms", list(self.objective_terms))):
            unknown = [m for m in asked if m not in terms]
            if unknown:
                raise ConfigError(f"map_elites.{name}: {', '.join(unknown)} names no term of the {task} task "
                                  f"(its terms: {', '.join(terms)})")


@dataclass(frozen=True, kw_only=True, eq=False)
class MapElitesState(OptimizerState):
    """MAP-Elites between generations: the elites in cell order (``index`` ``(E,)`` cell numbers, ``genome`` ``(E, G)``,
    ``objective`` ``(E,)``, ``measures`` ``(E, 2)``, ``fell`` ``(E,)`` 0/1, ``end_time`` ``(E,)`` s), the evaluations so
    far, ``progress`` ``(generations, 3)``: after each generation the evaluations so far, cells filled and QD score (the
    sum of the elites' objectives less ``qd_offset``); and the current batch's fitness (NaN: not yet evaluated).
    ``task_fitness`` ``(E,)``: each elite's fitness (its objective but the ``objective_terms``; checkpoints written
    before it: the objective)."""

    name = "map-elites"
    index: np.ndarray
    genome: np.ndarray
    objective: np.ndarray
    measures: np.ndarray
    fell: np.ndarray
    end_time: np.ndarray
    task_fitness: np.ndarray
    progress: np.ndarray

    def __post_init__(self):
        for k in ("index", "genome", "objective", "measures", "fell", "end_time", "task_fitness", "progress",
                  "fitness"):
            object.__setattr__(self, k, frozen_array(getattr(self, k)))

    def to_dict(self) -> dict:
        plain = lambda a: np.where(np.isfinite(a), a, None).tolist() if a.size else a.tolist()  # noqa: E731
        return {"name": self.name, "generation": self.generation, "fitness": plain(self.fitness),
                "index": [int(i) for i in self.index], "genome": packed_floats(self.genome),
                **{k: getattr(self, k).tolist()
                   for k in ("objective", "measures", "fell", "end_time", "task_fitness", "progress")}}


def ribs_archives():
    """pyribs' archives module (UserError, one line, where the optional extra is not installed)."""
    try:
        from ribs import archives
    except ImportError:
        raise UserError("the map-elites optimizer needs pyribs: pip install -c constraints.txt -e '.[qd]'") from None
    return archives


class MapElites(Optimizer):
    """Ask/tell MAP-Elites over a :class:`GenomeLayout`; ``population`` is the batch being evaluated ``(batch, G)``."""

    name, Options, table = "map-elites", MapElitesOptions, "map_elites"
    about = "a repertoire: one elite per cell of two measures; needs the qd extra"
    docs_note = "A gait repertoire, and what is done with one: docs/repertoire.md."

    def __init__(self, layout, config: MapElitesOptions, **start):
        """As every optimizer (:meth:`Optimizer.__init__`); the first batch is the start genome and its mutants, or
        samples of the layout's initial distribution."""
        super().__init__(layout, config, **start)
        c = config
        self.archive = ribs_archives().GridArchive(
            solution_dim=layout.size, dims=c.resolution, ranges=list(zip(c.low, c.high)), seed=self.seed,
            qd_score_offset=c.qd_offset, extra_fields={k: ((), np.float64) for k in OUTCOME})
        self.generation, self.evaluations, self.progress = 0, 0, []
        self._sample()

    @classmethod
    def population_size(cls, options: MapElitesOptions, n_genes: int) -> int:
        return options.batch

    @classmethod
    def population_setting(cls, population: int) -> tuple[str, int]:
        return "batch", population

    @classmethod
    def check_episode(cls, options: MapElitesOptions, episode) -> None:
        """ConfigError unless the measures and objective terms are terms of the episode's task."""
        task = episode.parts()[2]
        options.check_terms(tuple(task.term_names), task.name)

    # ---- the archive
    def elites(self) -> dict[str, np.ndarray]:
        """The archive's elites in cell order: ``index`` ``(E,)``, ``genome`` ``(E, G)``, ``objective``, ``measures``
        ``(E, 2)``, ``fell``, ``end_time``, ``task_fitness``."""
        d = self.archive.data()
        order = np.argsort(d["index"], kind="stable")
        out = {"index": d["index"][order].astype(int), "genome": d["solution"][order],
               "objective": d["objective"][order], "measures": d["measures"][order]}
        return {**out, **{k: d[k][order] for k in OUTCOME}}

    def cells(self, index: np.ndarray) -> np.ndarray:
        """Grid coordinates ``(E, 2)`` of cell numbers ``index`` ``(E,)``."""
        return np.asarray(self.archive.int_to_grid_index(np.asarray(index, int)), int).reshape(-1, 2)

    def _sample(self) -> None:
        c, G = self.config, self.layout.size
        rng = self.rng(self.generation)
        span = (self.high - self.low) * self.mutable
        if len(self.archive) == 0:
            if self.initial is None:
                rows = self.layout.sample(rng, c.batch)
            else:  # the start genome and its mutants
                rows = self.initial[0] + c.sigma * span * rng.standard_normal((c.batch, G))
                rows[0] = self.initial[0]
        else:
            e = self.elites()
            up = e["fell"] == 0
            genomes = e["genome"][up] if c.parents == "up" and up.any() else e["genome"]
            parents = genomes[rng.integers(len(genomes), size=c.batch)]
            rows = parents + c.sigma * span * rng.standard_normal((c.batch, G))
            if c.line_sigma:
                other = genomes[rng.integers(len(genomes), size=c.batch)]
                rows = rows + c.line_sigma * rng.standard_normal((c.batch, 1)) * (other - parents) * self.mutable
        self.population = np.clip(rows, self.low, self.high)
        self.fitness = np.full(len(self.population), np.nan)

    def tell(self, result) -> None:
        """Fitness and terms (an :class:`~evobiped.episode.result.EpisodeResult`) of the batch; each genome with finite
        fitness and measures goes to its cell if it beats the elite there."""
        unknown = np.isnan(self.fitness)
        super().tell(result)
        terms = getattr(result, "terms", {})
        missing = [m for m in (*self.config.measures, *self.config.objective_terms) if m not in terms]
        if missing:
            raise UserError(f"map-elites: the episodes give no term {', '.join(missing)} (a measure or objective term "
                            "names no term of the task)")
        per_genome = lambda a: np.asarray(a, float).reshape(len(self.fitness[unknown]), -1).mean(axis=1)  # noqa: E731
        measures = np.stack([per_genome(terms[m]) for m in self.config.measures], axis=1)
        f = self.fitness[unknown]
        objective = f + sum(w * per_genome(terms[t]) for t, w in self.config.objective_terms.items())
        ok = np.isfinite(objective) & np.isfinite(measures).all(axis=1)
        if ok.any():
            self.archive.add(self.population[unknown][ok], objective[ok], measures[ok],
                             fell=np.asarray(result.fell, float)[ok],
                             end_time=np.asarray(result.end_time, float)[ok], task_fitness=f[ok])
        self.evaluations += int(unknown.sum())
        objective = self.elites()["objective"]
        self.progress.append([self.evaluations, len(objective), float(np.sum(objective - self.config.qd_offset))])

    def next_generation(self) -> np.ndarray:
        """Ask the next batch; every row is new (all -1)."""
        if np.isnan(self.fitness).any():
            raise RuntimeError("next_generation before every individual was evaluated")
        self.generation += 1
        self._sample()
        return np.full(len(self.population), -1)

    keeps_archive = True

    def archive_contents(self) -> ArchiveContents:
        """The archive as archive.json keeps it (:mod:`evobiped.files.rundir.archive_file`): its elites, their
        objective the task's fitness (what a replay of an elite compares)."""
        e, c = self.elites(), self.config
        e["objective"] = e["task_fitness"]
        return ArchiveContents(c.measures, c.low, c.high, c.resolution, self.cells(e["index"]), e, self.progress)

    def series(self) -> dict[str, np.ndarray]:
        """The archive's growth per generation: evaluations so far, cells filled, coverage (fraction of the grid's
        cells) and QD score (the sum of the elites' objectives less ``qd_offset``)."""
        p = np.array(self.progress, float).reshape(-1, 3)
        return {"evaluations": p[:, 0], "cells": p[:, 1], "coverage": p[:, 1] / np.prod(self.config.resolution),
                "qd_score": p[:, 2]}

    # ---- its state as a value
    def state(self) -> MapElitesState:
        e = self.elites()
        return MapElitesState(generation=self.generation, fitness=self.fitness,
                              progress=np.array(self.progress, float).reshape(-1, 3), **e)

    def restore(self, state: MapElitesState) -> None:
        G, cells = self.layout.size, int(np.prod(self.config.resolution))
        E = len(state.index)
        if state.genome.shape != (E, G) or state.measures.shape != (E, 2) or any(len(getattr(state, k)) != E for k in
                                                                                ("objective", *OUTCOME)):
            raise UserError(f"checkpoint: the map-elites state's elites must each have {G} genes, 2 measures, an "
                            "objective and outcome")
        if E and (state.index.min() < 0 or state.index.max() >= cells or len(np.unique(state.index)) != E):
            raise UserError(f"checkpoint: map-elites.index must be different cells 0 to {cells - 1}")
        if len(state.progress) != state.generation:
            raise UserError(f"checkpoint: map-elites.progress must have a row per generation ({state.generation})")
        self.archive.clear()
        if E:
            self.archive.add(state.genome, state.objective, state.measures, fell=state.fell, end_time=state.end_time,
                             task_fitness=state.task_fitness)
            if not np.array_equal(self.elites()["index"], state.index):
                raise UserError("checkpoint: map-elites.measures do not lie in the cells map-elites.index names")
        self.generation = state.generation
        self.progress = state.progress.tolist()
        self.evaluations = int(self.progress[-1][0]) if self.progress else 0
        self._resample_with_fitness(state.fitness, "map-elites")

    def _state_from(self, table: dict) -> MapElitesState:
        gen = MapElitesState.generation_of(table)
        widths = {"genome": self.layout.size, "measures": 2, "progress": 3}
        out = {k: MapElitesState.numbers_of(table, k, null=np.nan if k == "fitness" else None, rows=widths.get(k))
               for k in ("fitness", "index", "objective", "measures", "fell", "end_time", "progress")}
        out["task_fitness"] = (MapElitesState.numbers_of(table, "task_fitness") if "task_fitness" in table
                               else out["objective"].copy())  # written before it: the objective was the fitness
        packed = table.get("genome")  # packed; a list of rows in checkpoints written before packing
        out["genome"] = (unpacked_floats(packed, "checkpoint: map-elites.genome") if isinstance(packed, dict)
                         else MapElitesState.numbers_of(table, "genome", rows=widths["genome"]))
        if not np.isfinite(out["genome"]).all():
            raise UserError("checkpoint: map-elites.genome must hold finite numbers")
        return MapElitesState(generation=gen, **out)
