"""An evolutionary run: run directory, checkpoints, resume (its settings: :mod:`.run_config`).

The run directory's files, names and columns are :mod:`evobiped.rundir`'s;
every file is written atomically.  ``resume`` continues from checkpoint.json
and yields exactly the files an uninterrupted run with the same config writes
(wall times aside).
"""

from __future__ import annotations

import time
import uuid
from pathlib import Path
from typing import Callable

import numpy as np

from .. import __version__, provenance, rundir
from ..errors import UserError, signals_deferred
from ..fileio import WriteError, atomic_write, json_text, read_json, write_json
from ..genome_file import genome_text, load_genome, save_genome
from .evaluate import Evaluator
from .base import Optimizer
from .individuals import Individuals
from . import fingerprint
from .run_config import RunConfig, make_optimizer, start_genome
from .generation_stats import GenerationStats
from .run_context import RunContext
from .start_genome import keep_start, kept_start, start_episode


class Run:
    """A run directory and the optimizer that lives in it; holds the directory's lock until :meth:`close`."""

    #: the start genome ``(G,)`` as a list (None: the run has none), read once when the run was created
    start: list[float] | None = None
    #: the numerical environment config.json says the run started in (None: none recorded)
    started_in: dict | None = None

    def __init__(self, directory: Path, config: RunConfig, optimizer: Optimizer, history: list[list], best: dict | None, wall: float,
                 best_genome: list[float] | None = None, individuals: Individuals | None = None,
                 history_terms: list[dict] | None = None, best_walk: dict | None = None, context: RunContext | None = None):
        self.dir, self.config, self.optimizer = directory, config, optimizer
        self.history, self.best, self.wall = history, best, wall
        #: the best genome of the run so far ``(G,)`` as stored in the checkpoint (None before generation 0)
        self.best_genome = best_genome
        #: the outcome of each individual of the optimizer's population (rows as its population)
        self.individuals = individuals if individuals is not None else Individuals()
        #: the best individual's terms per generation (name -> mean over its presentations), history.csv's term columns
        self.history_terms = history_terms if history_terms is not None else []
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

    # ---- creating and resuming
    @classmethod
    def create(cls, directory: str | Path, config: RunConfig) -> "Run":
        """Validate everything first; only then create the (new or empty) directory and lock it."""
        directory = Path(directory)
        if directory.exists() and not directory.is_dir():
            raise UserError(f"run directory {directory} exists and is a file; give another --out")
        start = start_genome(config)
        opt = make_optimizer(config, start)
        try:
            directory.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise WriteError(directory, exc) from None
        rundir.lock(directory)
        try:
            if not rundir.is_unused(directory):
                raise UserError(f"run directory {directory} exists and is not empty (use --resume {directory} or another --out)")
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
            rundir.write_history(directory / rundir.HISTORY, [])
        except BaseException:
            rundir.unlock(directory)
            raise
        return run

    @classmethod
    def resume(cls, directory: str | Path) -> "Run":
        """Lock the directory, validate its checkpoint, rebuild every derived file from it (see :attr:`repairs`)."""
        directory = Path(directory)
        if not directory.is_dir():
            raise UserError(f"run directory not found: {directory}")
        rundir.lock(directory)
        try:
            run = cls._load(directory)
            run._rebuild()
        except BaseException:
            rundir.unlock(directory)
            raise
        return run

    @classmethod
    def _load(cls, directory: Path) -> "Run":
        run, started_in = cls._read(directory)
        run.environment_differences = provenance.differences(started_in)
        return run

    @classmethod
    def _read(cls, directory: Path) -> tuple["Run", dict | None]:
        """The run in ``directory`` and the numerical environment its config.json records (None: none)."""
        if not (directory / rundir.CONFIG).exists() and rundir.is_unused(directory):
            raise UserError(f"{directory} holds no run yet (stopped before its config was written): start it again with evobiped evolve --out {directory}")
        cfg = read_json(directory / rundir.CONFIG, what="run config")
        if not isinstance(cfg, dict):
            raise UserError(f"run config {directory / rundir.CONFIG} is not a table of settings")
        cfg.pop("evobiped", None)
        started_in = cfg.pop("environment", None)
        config = RunConfig.from_dict(cfg, where=str(directory / rundir.CONFIG))
        path = directory / rundir.CHECKPOINT
        ck = read_json(path, what="checkpoint") if path.exists() else None
        if path.exists() and ck is None:
            raise UserError(f"checkpoint {path} is null, not a checkpoint: the run cannot be resumed; start a new run")
        if isinstance(ck, dict) and rundir.SETTINGS_KEY in ck:  # what the run was created with, before anything is built
            fingerprint.check(ck[rundir.SETTINGS_KEY], config, started_in, directory / rundir.CONFIG)
        start = kept_start(directory, config, ck)
        opt = make_optimizer(config, start)
        if ck is None:
            committed = cls._committed_files(directory)
            if committed:
                raise UserError(f"{path} is missing but the run has committed generations ({committed[0]}): it cannot be resumed; start a new run")
            # killed before its first commit: start over (the normaliser from the start genome's file again)
            run = cls(directory, config, opt, [], None, 0.0, context=RunContext(config, start_episode(directory, config)))
        else:
            try:
                rundir.validate_checkpoint(ck, generations=config.generations, low=opt.low, high=opt.high)
            except UserError as exc:
                raise UserError(f"checkpoint {path} is malformed: {exc}") from None
            state, history, best = opt.state_from(rundir.optimizer_table(ck)), ck["history"], ck["best"]
            if len(history) != state.generation:  # before the state is restored: an older CMA-ES state is replayed
                raise UserError(f"checkpoint {path} is inconsistent (history has {len(history)} rows for generation {state.generation})")
            opt.restore(state)
            individuals = Individuals.from_dict(ck.get("outcome", {}), len(opt.population))
            context = RunContext(config)  # its state is the checkpoint's
            context.restore(ck)
            run = cls(directory, config, opt, history, best, float(ck["wall_seconds"]), ck.get("best_genome"), individuals,
                      ck.get("history_terms", []), ck.get("best_walk"), context)
        run.start = None if start is None else [float(x) for x in start]
        run.started_in = started_in
        return run, started_in

    @staticmethod
    def _committed_files(directory: Path) -> list[str]:
        """Files that exist only after a first commit (gen_0000.json is written just before it)."""
        found = [n for n in (rundir.BEST, rundir.SUMMARY, rundir.RECORDING) if (directory / n).exists()]
        hist = directory / rundir.HISTORY
        if hist.is_file() and hist.read_bytes().count(b"\n") > 1:
            found.append(rundir.HISTORY)
        found += [f"{rundir.GENERATIONS}/{p.name}" for p in rundir.generation_files(directory) if rundir.generation_of(p) != 0]
        return found

    def _rebuild(self) -> None:
        """Make every derived file what the checkpoint says it is; note each repair in :attr:`repairs`."""
        d, g = self.dir, self.optimizer.generation
        for p in rundir.remove_stale_temporaries(d):
            self.repairs.append(f"{p.relative_to(d)} removed (a write cut short)")
        (d / rundir.GENERATIONS).mkdir(exist_ok=True)
        for p in rundir.generation_files(d):
            if rundir.generation_of(p) is None or rundir.generation_of(p) >= g:
                p.unlink()
                self.repairs.append(f"{p.relative_to(d)} removed (after the last checkpoint)")
        self._derive(repair=True)
        if self.done:
            self._write_summary(repair=True)
        elif (d / rundir.SUMMARY).exists():
            (d / rundir.SUMMARY).unlink()
            self.repairs.append(f"{rundir.SUMMARY} removed (the run is not complete)")

    def _sync(self, name: str, text: str | None, *, repair: bool) -> None:
        """Give file ``name`` the content ``text`` (None: no such file) unless it has it; a repair says so."""
        path = self.dir / name
        try:
            current = path.read_text() if path.exists() else None
        except (OSError, UnicodeDecodeError):
            current = ""
        if current == text:
            return
        if repair:
            self.repairs.append(f"{name} {'rewritten from the checkpoint' if text is not None else 'removed (no generation is complete)'}")
        if text is None:
            path.unlink(missing_ok=True)
        else:
            atomic_write(path, text)

    def _derive(self, *, repair: bool = False) -> None:
        """history.csv, best.json and evolution.rrd from the committed state."""
        from ..record.evolution_log import recording_matches, write_recording

        self._sync(rundir.HISTORY, rundir.history_text(self.history, self.history_terms, self.context.history), repair=repair)
        self._sync(rundir.BEST, self._best_text(), repair=repair)
        for name, text in self.optimizer.derived_files(bool(self.history)).items():  # e.g. MAP-Elites' archive.json
            self._sync(name, text, repair=repair)
        rec = self.dir / rundir.RECORDING
        if not self.history:
            self._sync(rundir.RECORDING, None, repair=repair) if rec.exists() else None
            return
        columns = rundir.history_columns(self.history, self.history_terms, self.context.history)
        if repair:
            if recording_matches(rec, columns):
                return
            self.repairs.append(f"{rundir.RECORDING} rebuilt from the checkpoint")
        write_recording(rec, columns, self.recording_id)

    def _best_text(self) -> str | None:
        if self.best is None:
            return None
        genome = self.best_genome
        if genome is None:  # a checkpoint written before the best genome was part of it: its generation file
            src = rundir.generation_file(self.dir, self.best["generation"])
            return src.read_text() if src.is_file() else None
        return genome_text(np.array(genome), self.context.best_episode(), **self.best)

    @property
    def done(self) -> bool:
        return self.optimizer.generation >= self.config.generations

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
        :attr:`~evobiped.perturb.PerturbationOptions.settled_from`) or the pelvis assistance is on, generations are not
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
        save_genome(rundir.generation_file(self.dir, g), pop[b], episode, **meta)
        # while schedules still change or the assistance holds the walker up, generations are not comparable (nor
        # the unassisted walker's): the run's best is the latest generation's until then, then the fittest since
        if self.best is None or self._unsettled(g) or self._unsettled(self.best["generation"]) or meta["fitness"] > self.best["fitness"]:
            self.best, self.best_genome, self.best_walk = meta, [float(x) for x in pop[b]], self.individuals.walk_of(b)
            self.context.best = context
        self.history.append(stats.row())
        means = {k: float(np.mean(np.array(v, dtype=float))) for k, v in terms.items()}
        self.history_terms.append({k: v if np.isfinite(v) else None for k, v in means.items()})
        self.context.after(result, unknown, getattr(opt, "evaluation_rows", lambda: None)(), f)
        self.individuals.carry(opt.next_generation())  # the individuals it keeps keep their outcome
        return stats

    def _key(self, generation: int) -> tuple[int, ...]:
        """What generation ``generation``'s perturbed presentations are drawn from (:meth:`PerturbationOptions.key`)."""
        return self.config.episode.perturbations.key(self.config.seed, generation, rundir.column(self.history, "best"))

    def _unsettled(self, generation: int) -> bool:
        """Generation ``generation`` is not comparable with later ones: a schedule still changed, the assistance was on,
        or it was scored in an earlier phase of the curriculum than the last."""
        return (self.config.episode.perturbations.unsettled(generation, rundir.column(self.history, "best"))
                or self.context.early_phase(generation))

    # ---- files
    def checkpoint(self) -> None:
        """Commit the generation (checkpoint.json), then derive history.csv, best.json and evolution.rrd;
        Ctrl-C (SIGTERM, SIGHUP) waits until all are written."""
        with signals_deferred():
            write_json(
                self.dir / rundir.CHECKPOINT,
                {rundir.SETTINGS_KEY: fingerprint.settings(self.config, self.started_in), rundir.START_KEY: self.start,
                 "optimizer": self.optimizer.state().to_dict(), "history": self.history, "best": self.best, "best_genome": self.best_genome,
                 "wall_seconds": self.wall, "outcome": self.individuals.to_dict(), "history_terms": self.history_terms,
                 "best_walk": self.best_walk, **self.context.to_dict()},
            )
            self._derive()

    def _best_walk(self) -> dict | None:
        """Distance and walking direction of the best walker in the nominal episode (``EpisodeResult.walk``): kept from
        its evaluation.  A perturbed run's evaluation has no nominal presentation (its walks are perturbed), so its
        best is walked once, nominally, for the summary (what a replay checks); so is the best of a checkpoint
        written before walks were kept."""
        if self.best is None or not (self.dir / rundir.BEST).is_file():
            return None
        if self.best_walk is not None and not self.config.episode.perturbed:
            return self.best_walk
        genome, cfg, _ = load_genome(self.dir / rundir.BEST)
        return cfg.nominal().build().run(genome).walk()

    def _summary(self, best_walk: dict | None) -> dict:
        return {
            "evobiped": __version__,
            "generations": self.optimizer.generation,
            "best": self.best,
            "wall_seconds": round(self.wall, 3),
            "evaluations": int(sum(rundir.column(self.history, "evaluations"))),
            "stable": self.best is not None and not self.best["fell"],
            "best_walk": best_walk,
        }

    def _write_summary(self, *, repair: bool = False) -> dict:
        path = self.dir / rundir.SUMMARY
        if repair:  # the best walk costs an episode: keep a summary whose other fields agree with the checkpoint
            try:
                old = read_json(path, what="summary") if path.exists() else None
                if isinstance(old, dict) and "best_walk" in old and path.read_text() == json_text(self._summary(old["best_walk"])):
                    return old
            except UserError:
                pass
            self.repairs.append(f"{rundir.SUMMARY} {'rewritten' if path.exists() else 'written'} from the checkpoint")
        summary = self._summary(self._best_walk())
        write_json(path, summary)
        return summary

    def finish(self) -> dict:
        """Write summary.json (the run is complete); returns it."""
        return self._write_summary()

    def close(self) -> None:
        """Release the run directory's lock."""
        rundir.unlock(self.dir)

    def __enter__(self) -> "Run":
        return self

    def __exit__(self, *exc) -> None:
        self.close()
