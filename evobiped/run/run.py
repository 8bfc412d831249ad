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
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from .. import __version__
from ..core import provenance
from ..files import rundir
from ..core.errors import UserError
from ..core.fileio import WriteError, write_json
from ..files.genome_file import genome_text
from . import checkpoint as commit_point, fingerprint
from ..evaluation import Evaluator
from ..optimizers import Optimizer
from .individuals import Individuals
from .listeners import RunListener
from .run_config import RunConfig, episodes_per_genome, make_optimizer, start_genome
from .generation_stats import GenerationFiles, GenerationStats
from .run_context import RunContext
from .start_genome import keep_start, start_episode


def _check_unused(directory: Path) -> None:
    """UserError unless ``directory`` holds no run and nothing else (:func:`~evobiped.files.rundir.is_unused`)."""
    if rundir.is_unused(directory):
        return
    if (directory / rundir.CONFIG).is_file():
        raise UserError(f"run directory {directory} already holds a run (continue it with --resume {directory}, or "
                        "give another --out)")
    raise UserError(f"run directory {directory} exists and holds other files, not a run: give a new or empty directory "
                    "as --out")


class Run:
    """A run directory and the optimizer that lives in it; holds the directory's lock until :meth:`close`.

    What the run has committed is its :attr:`record` (checkpoint.json's, :class:`~evobiped.files.rundir.RunRecord`);
    the optimizer, the individuals' outcomes and the context are the search's working state, the record's parts
    restored.  A generation is evaluated (:meth:`step`: a new record, no file written), then committed
    (:meth:`checkpoint`)."""

    #: the numerical environment config.json says the run started in (None: none recorded)
    started_in: dict | None = None
    #: :meth:`create` made the run directory (it did not exist before)
    made_directory: bool = False

    def __init__(self, directory: Path, config: RunConfig, optimizer: Optimizer, record: rundir.RunRecord,
                 individuals: Individuals | None = None, context: RunContext | None = None,
                 listeners: Sequence[RunListener] = (), started_in: dict | None = None):
        """``record``: what the run has committed; ``optimizer``, ``individuals`` and ``context`` restored to its
        state (None: a new run's); ``started_in``: the numerical environment config.json records."""
        self.dir, self.config, self.optimizer, self.record = directory, config, optimizer, record
        #: told of each commit, after the run directory's own files (:mod:`.listeners`; the evolve use case's recording)
        self.listeners: list[RunListener] = list(listeners)
        #: the outcome of each individual of the optimizer's population (rows as its population)
        self.individuals = individuals if individuals is not None else Individuals()
        #: what the run sets per generation beyond its config: the running normaliser, the curriculum's phase
        self.context = context if context is not None else RunContext(config)
        self.started_in = started_in
        #: what a resume found damaged and rebuilt from the checkpoint, one sentence each
        self.repairs: list[str] = []
        #: how this process's numerical environment differs from the one the run started in (a resume's; empty:
        #: the resumed run is bit-identical to an uninterrupted one)
        self.environment_differences: list[str] = []
        #: the evaluated generation's files, written by its commit (None: nothing evaluated since the last commit)
        self.uncommitted: GenerationFiles | None = None

    @property
    def recording_id(self) -> str:
        """The run's recording id (the same for every session of the run: its config's)."""
        return commit_point.recording_id(self.config)

    def _readers(self) -> dict:
        """What the derived files read the record through (:func:`.checkpoint.derive`)."""
        return dict(optimizer=self.optimizer, context=self.context, listeners=self.listeners)

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
            write_json(directory / rundir.CONFIG,
                       {"evobiped": __version__, **config.to_dict(), "environment": environment})
            record = rundir.RunRecord(fingerprint.settings(config, environment),
                                      None if start is None else [float(x) for x in start])
            run = cls(directory, config, opt, record, context=RunContext(config, start_episode(directory, config)),
                      listeners=listeners, started_in=environment)
            run.made_directory = made
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
            run = cls(**commit_point.load(directory), listeners=listeners)
            run.environment_differences = provenance.differences(run.started_in)
            run.repairs = commit_point.rebuild(directory, run.config, run.record, individuals=run.individuals,
                                               done=run.done, **run._readers())
        except BaseException:
            rundir.unlock(directory)
            raise
        return run

    @property
    def done(self) -> bool:
        """Every generation evolved, the episodes evaluated reached the config's budget (if any), or the stopping rule
        held (:mod:`.stopping`)."""
        budget = self.config.budget
        return (self.optimizer.generation >= self.config.generations
                or (budget is not None and self.episodes() >= budget)
                or self.context.stopped())

    def episodes(self) -> int:
        """Episodes evaluated by the committed generations (history.csv's evaluations, each genome's presentations)."""
        return int(sum(rundir.column(self.record.history, "evaluations"))) * episodes_per_genome(self.config)

    # ---- the loop
    def evolve(self, evaluator: Evaluator, on_generation: Callable[[GenerationStats], None] | None = None) -> dict:
        """Run the remaining generations; commit after each.  Returns the summary."""
        while not self.done:
            t0 = time.perf_counter()
            stats = self.step(evaluator)
            stats.wall_seconds = round(time.perf_counter() - t0, 4)
            self.record = self.record.timed(stats.wall_seconds)
            stats.evals_per_second = stats.evaluations / max(stats.wall_seconds, 1e-9)
            self.checkpoint()
            if on_generation:
                on_generation(stats)
        return self.finish()

    def step(self, evaluator: Evaluator) -> GenerationStats:
        """Evaluate the unknown individuals of this generation and make the run's next record, a function of the
        last one and what the generation gave (the run's best: :meth:`_replaces_best`); no file is written here:
        :meth:`checkpoint` writes the generation's files and commits the record."""
        opt, g = self.optimizer, self.optimizer.generation
        pop, unknown = opt.ask()
        context = self.context.now()
        # a plain run's evaluations take no context (an evaluator written before contexts still serves it)
        result = evaluator.evaluate(pop[unknown], key=self._key(g), **({} if context.empty else {"context": context}))
        opt.tell(result)
        self.individuals.record_results(unknown, result)
        b = int(opt.ranking()[0])
        stats, terms = self._stats(g, b, unknown, result), self.individuals.terms_of(b)
        meta = dict(fitness=stats.best, fell=stats.best_fell, end_time=float(self.individuals.outcome["end_time"][b]),
                    seed=self.config.seed, generation=g, terms=terms)
        text = genome_text(pop[b], self.context.episode(context), **meta)
        self.uncommitted = GenerationFiles(g, text, self.individuals.records(g, opt.fitness, unknown))
        best = None
        if self._replaces_best(g, stats.best):
            best, self.context.best = (meta, [float(x) for x in pop[b]], self.individuals.walk_of(b)), context
        self._next_generation(result, unknown, self._helped(g))
        means = {k: float(np.mean(np.array(v, dtype=float))) for k, v in terms.items()}
        self.record = self.record.committed(
            stats.row(), {k: v if np.isfinite(v) else None for k, v in means.items()}, rundir.digest(text),
            optimizer=opt.state().to_dict(), outcome=self.individuals.to_dict(), context=self.context.to_dict(),
            best=best)
        return stats

    def _next_generation(self, result, unknown: np.ndarray, helped: bool) -> None:
        """The context learns from the generation (``result`` of the rows ``unknown`` ``(P,)``; ``helped``: its
        walkers were helped, :meth:`_helped`), the optimizer makes the next one, and each individual it keeps keeps
        its outcome."""
        opt = self.optimizer
        self.context.after(result, unknown, opt.evaluation_rows(), opt.fitness, helped=helped)
        carried = opt.next_generation()
        if self.context.restart_due:  # the lost-run rule: the search starts over (every individual new)
            self.individuals.carry(opt.start_over(), None)
        else:
            self.individuals.carry(carried, opt.parent_rows())

    def _stats(self, g: int, b: int, unknown: np.ndarray, result) -> GenerationStats:
        """Generation ``g``'s statistics: ``b`` its best row, ``unknown`` ``(P,)`` the rows ``result`` evaluated."""
        f, outcome = self.optimizer.fitness, self.individuals.outcome
        return GenerationStats(
            generation=g, best=float(f[b]), mean=float(f.mean()), median=float(np.median(f)), worst=float(f.min()),
            evaluations=int(unknown.sum()), falls=int(outcome["fell"].sum()), unstable=int(outcome["unstable"].sum()),
            wall_seconds=0.0, best_fell=bool(outcome["fell"][b]), generations_total=self.config.generations,
            simulated_seconds=float(np.sum((result.rows if result.rows is not None else result).end_time)),
            longest_seconds=float(np.max(result.end_time, initial=0.0)))

    def _replaces_best(self, g: int, fitness: float) -> bool:
        """Generation ``g``'s best (of ``fitness``) becomes the run's: while schedules still change or the assistance
        holds the walker up, generations are not comparable (nor the unassisted walker's): the run's best is the
        latest generation's until then, then the fittest since."""
        best = self.record.best
        return best is None or not self._held(g) and (self._incomparable(g) or self._incomparable(best["generation"])
                                                       or fitness > best["fitness"])

    def _key(self, generation: int) -> tuple[int, ...]:
        """What generation ``generation``'s perturbed presentations are drawn from (:meth:`PerturbationOptions.key`)."""
        bests = rundir.column(self.record.history, "best")
        return self.config.episode.perturbations.key(self.config.seed, generation, bests)

    def _helped(self, generation: int) -> bool:
        """Generation ``generation``'s walkers were helped: the pelvis assistance held them (its stiffness above 0),
        or they walked under less than the model's gravity."""
        return self.config.episode.perturbations.helps(generation, rundir.column(self.record.history, "best"))

    def _incomparable(self, generation: int) -> bool:
        """Generation ``generation`` is not comparable with later ones: a schedule still changed, the assistance was on,
        or it was scored in an earlier phase of the curriculum than the last."""
        return (self.config.episode.perturbations.incomparable(generation, rundir.column(self.record.history, "best"))
                or self.context.early_phase(generation))

    def _held(self, generation: int) -> bool:
        """After a restart, a generation of an early phase leaves a best scored in the last phase as it is."""
        best = self.record.best
        return bool(self.context.attempts and self.context.attempts.attempt and best is not None
                    and self.context.early_phase(generation) and not self.context.early_phase(best["generation"]))

    # ---- files
    def checkpoint(self) -> None:
        """Commit the evaluated generation: its files, then the record, then the files derived from it
        (:func:`.checkpoint.commit`)."""
        commit_point.commit(self.dir, self.config, self.record, self.uncommitted, **self._readers())
        self.uncommitted = None

    def finish(self) -> dict:
        """Write summary.json (the run is complete); returns it."""
        return commit_point.write_summary(self.dir, self.config, self.record, context=self.context)

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
