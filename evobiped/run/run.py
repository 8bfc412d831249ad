"""An evolutionary run: a run directory and the optimizer that lives in it, generation by generation (its settings:
:mod:`.run_config`; its commit point and derived files: :mod:`.checkpoint`).

The run directory's files, names and columns are :mod:`evobiped.files.rundir`'s;
every file is written atomically, individuals.jsonl appended.  ``resume``
continues from checkpoint.json and yields exactly the files an uninterrupted
run with the same config writes (wall times aside).
"""

from __future__ import annotations

import contextlib
import time
import uuid
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from .. import __version__
from ..core import provenance
from ..files import rundir
from ..core.errors import UserError
from ..core.fileio import WriteError, atomic_write, json_text, write_json
from ..files.genome_file import genome_text
from . import checkpoint as commit_point
from ..evaluation import Evaluator
from ..optimizers import Optimizer
from .individuals import Individuals
from .listeners import RunListener
from .run_config import RunConfig, episodes_per_genome, make_optimizer, start_genome
from .generation_stats import GenerationStats
from .run_context import RunContext
from .start_genome import keep_start, start_episode


def _check_unused(directory: Path) -> None:
    """UserError unless ``directory`` holds no run and nothing else (:func:`~evobiped.files.rundir.is_unused`)."""
    if rundir.is_unused(directory):
        return
    if (directory / rundir.CONFIG).is_file():
        raise UserError(f"run directory {directory} already holds a run (continue it with --resume {directory}, or give another --out)")
    raise UserError(f"run directory {directory} exists and holds other files, not a run: give a new or empty directory as --out")


class Run:
    """A run directory and the optimizer that lives in it; holds the directory's lock until :meth:`close`."""

    #: the start genome ``(G,)`` as a list (None: the run has none), read once when the run was created
    start: list[float] | None = None
    #: the numerical environment config.json says the run started in (None: none recorded)
    started_in: dict | None = None
    #: :meth:`create` made the run directory (it did not exist before)
    made_directory: bool = False

    def __init__(self, directory: Path, config: RunConfig, optimizer: Optimizer, history: list[list], best: dict | None, wall: float,
                 best_genome: list[float] | None = None, individuals: Individuals | None = None,
                 history_terms: list[dict] | None = None, best_walk: dict | None = None, context: RunContext | None = None,
                 generation_digests: list[str | None] | None = None):
        self.dir, self.config, self.optimizer = directory, config, optimizer
        self.history, self.best, self.wall = history, best, wall
        #: the best genome of the run so far ``(G,)`` as stored in the checkpoint (None before generation 0)
        self.best_genome = best_genome
        #: the outcome of each individual of the optimizer's population (rows as its population)
        self.individuals = individuals if individuals is not None else Individuals()
        #: the best individual's terms per generation (name -> mean over its presentations), history.csv's term columns
        self.history_terms = history_terms if history_terms is not None else []
        #: each committed generation file's digest (None: a checkpoint written before they were kept)
        self.generation_digests = generation_digests if generation_digests is not None else [None] * len(history)
        #: where the best walker went in its evaluation (``EpisodeResult.walk``; None: not known)
        self.best_walk = best_walk
        #: what a resume found damaged and rebuilt from the checkpoint, one sentence each
        self.repairs: list[str] = []
        #: how this process's numerical environment differs from the one the run started in (a resume's; empty:
        #: the resumed run is bit-identical to an uninterrupted one)
        self.environment_differences: list[str] = []
        self.recording_id = str(uuid.uuid5(uuid.NAMESPACE_OID, json_text(config.to_dict())))
        #: what the run sets per generation beyond its config: the running normaliser, the curriculum's phase
        self.context = context if context is not None else RunContext(config)
        #: told of each commit, after the run directory's own files (:mod:`.listeners`; the evolve use case's recording)
        self.listeners: list[RunListener] = []

    # ---- creating and resuming
    @classmethod
    def create(cls, directory: str | Path, config: RunConfig, listeners: Sequence[RunListener] = ()) -> "Run":
        """Validate everything first; only then create the (new or empty) directory and lock it.  ``listeners``: told
        of each commit (:mod:`.listeners`)."""
        directory = Path(directory)
        if directory.exists() and not directory.is_dir():
            raise UserError(f"run directory {directory} exists and is a file; give another --out")
        start = start_genome(config)
        opt = make_optimizer(config, start)
        made = not directory.exists()
        if not made and not (directory / rundir.CONFIG).is_file():  # a run's: the lock says whether it runs now
            _check_unused(directory)  # before the lock: a refused directory is left as it was (no .lock in it)
        try:
            directory.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise WriteError(directory, exc) from None
        had_lock = (directory / rundir.LOCK).exists()
        rundir.lock(directory)
        try:
            try:
                _check_unused(directory)  # again, locked: another process may have made a run there meanwhile
            except UserError:
                if not had_lock:
                    (directory / rundir.LOCK).unlink(missing_ok=True)
                raise
            try:
                (directory / rundir.GENERATIONS).mkdir(exist_ok=True)
            except OSError as exc:
                raise WriteError(directory / rundir.GENERATIONS, exc) from None
            rundir.remove_stale_temporaries(directory)
            if start is not None:  # before the config: a run whose config names a start genome has it
                keep_start(directory, start, config)
            environment = provenance.current()
            write_json(directory / rundir.CONFIG, {"evobiped": __version__, **config.to_dict(), "environment": environment})
            run = cls(directory, config, opt, [], None, 0.0, context=RunContext(config, start_episode(directory, config)))
            run.started_in = environment
            run.start = None if start is None else [float(x) for x in start]
            run.made_directory = made
            run.listeners = list(listeners)
            rundir.write_history(directory / rundir.HISTORY, [])
        except BaseException:
            rundir.unlock(directory)
            raise
        return run

    @classmethod
    def resume(cls, directory: str | Path, listeners: Sequence[RunListener] = ()) -> "Run":
        """Lock the directory, validate its checkpoint, rebuild every derived file from it (see :attr:`repairs`), the
        ``listeners``' too (told of each commit from here on, :mod:`.listeners`)."""
        directory = Path(directory)
        if not directory.is_dir():
            raise UserError(f"run directory not found: {directory}")
        rundir.lock(directory)
        try:
            run = cls._load(directory)
            run.listeners = list(listeners)
            commit_point.rebuild(run)
        except BaseException:
            rundir.unlock(directory)
            raise
        return run

    @classmethod
    def _load(cls, directory: Path) -> "Run":
        """The run in ``directory`` as its checkpoint says (:func:`.checkpoint.load`), nothing repaired yet."""
        parts = commit_point.load(directory)
        start, started_in = parts.pop("start"), parts.pop("started_in")
        run = cls(**parts)
        run.start = None if start is None else [float(x) for x in start]
        run.started_in = started_in
        run.environment_differences = provenance.differences(started_in)
        return run

    @property
    def done(self) -> bool:
        """Every generation evolved, the episodes evaluated reached the config's budget (if any), or the stopping rule
        held (:mod:`.stopping`)."""
        budget = self.config.budget
        return (self.optimizer.generation >= self.config.generations or (budget is not None and self.episodes() >= budget)
                or self.context.stopped())

    def episodes(self) -> int:
        """Episodes evaluated by the committed generations (history.csv's evaluations, each genome's presentations)."""
        return int(sum(rundir.column(self.history, "evaluations"))) * episodes_per_genome(self.config)

    # ---- the loop
    def evolve(self, evaluator: Evaluator, on_generation: Callable[[GenerationStats], None] | None = None) -> dict:
        """Run the remaining generations; commit after each.  Returns the summary."""
        while not self.done:
            t0 = time.perf_counter()
            stats = self.step(evaluator)
            stats.wall_seconds = round(time.perf_counter() - t0, 4)
            self.wall += stats.wall_seconds
            stats.evals_per_second = stats.evaluations / max(stats.wall_seconds, 1e-9)
            self.history[-1] = stats.row()
            self.checkpoint()
            if on_generation:
                on_generation(stats)
        return self.finish()

    def step(self, evaluator: Evaluator) -> GenerationStats:
        """Evaluate the unknown individuals of this generation and write its generation file (not yet committed).
        The run's best is the fittest individual so far; while the perturbations' schedules still change (before
        :attr:`~evobiped.physics.perturb.PerturbationOptions.settled_from`) or the pelvis assistance is on, generations are not
        comparable, so the run's best is the latest generation's, then the fittest since."""
        opt = self.optimizer
        pop, unknown = opt.ask()
        context = self.context.now()
        # a plain run's evaluations take no context (an evaluator written before contexts still serves it)
        more = {} if context.empty else {"context": context}
        result = evaluator.evaluate(pop[unknown], key=self._key(opt.generation), **more)
        opt.tell(result)
        self.individuals.told(unknown, result)
        f, outcome = opt.fitness, self.individuals.outcome
        b = int(opt.ranking()[0])
        g = opt.generation
        stats = GenerationStats(
            generation=g,
            best=float(f[b]),
            mean=float(f.mean()),
            median=float(np.median(f)),
            worst=float(f.min()),
            evaluations=int(unknown.sum()),
            falls=int(outcome["fell"].sum()),
            unstable=int(outcome["unstable"].sum()),
            wall_seconds=0.0,
            best_fell=bool(outcome["fell"][b]),
            generations_total=self.config.generations,
            simulated_seconds=float(np.sum((result.rows if result.rows is not None else result).end_time)),
            longest_seconds=float(np.max(result.end_time, initial=0.0)),
        )
        terms = self.individuals.terms_of(b)
        meta = dict(fitness=float(f[b]), fell=bool(outcome["fell"][b]), end_time=float(outcome["end_time"][b]), seed=self.config.seed,
                    generation=g, terms=terms)
        episode = self.context.episode(context)
        text = genome_text(pop[b], episode, **meta)
        atomic_write(rundir.generation_file(self.dir, g), text)
        self.generation_digests.append(rundir.digest(text))
        rundir.append_individuals(self.dir / rundir.INDIVIDUALS, self.individuals.records(g, f, unknown))
        # while schedules still change or the assistance holds the walker up, generations are not comparable (nor
        # the unassisted walker's): the run's best is the latest generation's until then, then the fittest since
        if self.best is None or not self._held(g) and (self._unsettled(g) or self._unsettled(self.best["generation"])
                                                       or meta["fitness"] > self.best["fitness"]):
            self.best, self.best_genome, self.best_walk = meta, [float(x) for x in pop[b]], self.individuals.walk_of(b)
            self.context.best = context
        self.history.append(stats.row())
        means = {k: float(np.mean(np.array(v, dtype=float))) for k, v in terms.items()}
        self.history_terms.append({k: v if np.isfinite(v) else None for k, v in means.items()})
        self.context.after(result, unknown, opt.evaluation_rows(), f)
        carried = opt.next_generation()
        if self.context.restart_due:  # the lost-run rule: the search starts over (every individual new)
            self.individuals.carry(opt.start_over(), None)
        else:
            self.individuals.carry(carried, opt.parent_rows())  # the individuals it keeps keep their outcome
        return stats

    def _key(self, generation: int) -> tuple[int, ...]:
        """What generation ``generation``'s perturbed presentations are drawn from (:meth:`PerturbationOptions.key`)."""
        return self.config.episode.perturbations.key(self.config.seed, generation, rundir.column(self.history, "best"))

    def _unsettled(self, generation: int) -> bool:
        """Generation ``generation`` is not comparable with later ones: a schedule still changed, the assistance was on,
        or it was scored in an earlier phase of the curriculum than the last."""
        return (self.config.episode.perturbations.unsettled(generation, rundir.column(self.history, "best"))
                or self.context.early_phase(generation))

    def _held(self, generation: int) -> bool:
        """After a restart, a generation of an early phase leaves a best scored in the last phase as it is."""
        return bool(self.context.attempts and self.context.attempts.attempt and self.best is not None
                    and self.context.early_phase(generation) and not self.context.early_phase(self.best["generation"]))

    # ---- files
    def checkpoint(self) -> None:
        """Commit the generation and derive the files that follow from it (:func:`.checkpoint.commit`)."""
        commit_point.commit(self)

    def finish(self) -> dict:
        """Write summary.json (the run is complete); returns it."""
        return commit_point.write_summary(self)

    def abandon(self) -> None:
        """Undo :meth:`create` of a run that never evolved (its evaluator could not start): remove the files it wrote,
        and the directory when it made it; release the lock."""
        for name in (rundir.CONFIG, rundir.START, rundir.HISTORY):
            (self.dir / name).unlink(missing_ok=True)
        with contextlib.suppress(OSError):
            (self.dir / rundir.GENERATIONS).rmdir()
        self.close()
        if self.made_directory:
            (self.dir / rundir.LOCK).unlink(missing_ok=True)
            with contextlib.suppress(OSError):
                self.dir.rmdir()

    def close(self) -> None:
        """Release the run directory's lock."""
        rundir.unlock(self.dir)

    def __enter__(self) -> "Run":
        return self

    def __exit__(self, *exc) -> None:
        self.close()
