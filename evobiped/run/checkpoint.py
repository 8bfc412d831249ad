"""A run's commit point: reading and checking checkpoint.json, writing it, and having every derived file (history.csv,
best.json, archive.json, summary.json, individuals.jsonl, the generation files: the run directory's writers; evolution.rrd:
the run's listeners, :mod:`.listeners`) brought back to what it says.

The formats and writers are :mod:`evobiped.files.rundir`'s; :class:`~.run.Run` calls these at creation, after each
generation and on a resume.
"""

from __future__ import annotations

from pathlib import Path
from typing import Protocol

import numpy as np

from .. import __version__
from ..files import rundir
from ..core.errors import UserError, signals_deferred
from ..core.fileio import read_json, write_json
from ..files.genome_file import genome_text, load_genome
from . import fingerprint
from ..optimizers import Optimizer
from .individuals import Individuals
from .listeners import Commit, RunListener
from .run_config import RunConfig, make_optimizer
from .run_context import RunContext
from .start_genome import kept_start, start_episode


class CommittedRun(Protocol):
    """What the commit point reads of a run (:class:`~.run.Run` is one; named here, not imported, so that the run and
    its checkpoint do not import each other): its directory and config, the optimizer, the committed record
    (history, best, outcomes, context) and where the repairs of a resume are noted."""

    dir: Path
    config: RunConfig
    optimizer: Optimizer
    history: list[list]
    best: dict | None
    best_genome: list[float] | None
    best_walk: dict | None
    wall: float
    individuals: Individuals
    history_terms: list[dict]
    generation_digests: list[str | None]
    context: RunContext
    start: list[float] | None
    started_in: dict | None
    recording_id: str
    repairs: list[str]
    listeners: list[RunListener]

    @property
    def done(self) -> bool: ...


def load(directory: Path) -> dict:
    """What ``directory``'s config.json and checkpoint.json say, checked field by field before anything is built:
    the :class:`~.run.Run` constructor's arguments, ``start`` (the start genome ``(G,)`` or None) and ``started_in``
    (the numerical environment config.json records, or None).  A run killed before its first commit starts over."""
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
    parts = dict(directory=directory, config=config, optimizer=opt, start=start, started_in=started_in)
    if ck is None:
        committed = committed_files(directory)
        if committed:
            raise UserError(f"{path} is missing but the run has committed generations ({committed[0]}): it cannot be resumed; start a new run")
        # killed before its first commit: start over (the normaliser from the start genome's file again)
        return {**parts, "history": [], "best": None, "wall": 0.0, "context": RunContext(config, start_episode(directory, config))}
    try:
        rundir.validate_checkpoint(ck, generations=config.generations, low=opt.low, high=opt.high)
        rundir.generation_check.check_digests(ck)
    except UserError as exc:
        raise UserError(f"checkpoint {path} is malformed: {exc}") from None
    state, history, best = opt.state_from(rundir.optimizer_table(ck)), ck["history"], ck["best"]
    if len(history) != state.generation:  # before the state is restored: an older CMA-ES state is replayed
        raise UserError(f"checkpoint {path} is inconsistent (history has {len(history)} rows for generation {state.generation})")
    opt.restore(state)
    context = RunContext(config)  # its state is the checkpoint's
    context.restore(ck)
    return {**parts, "history": history, "best": best, "wall": float(ck["wall_seconds"]), "best_genome": ck.get("best_genome"),
            "individuals": Individuals.from_dict(ck.get("outcome", {}), len(opt.population)),
            "history_terms": ck.get("history_terms", []), "best_walk": ck.get("best_walk"), "context": context,
            "generation_digests": ck.get(rundir.DIGESTS_KEY)}


def committed_files(directory: Path) -> list[str]:
    """Files that exist only after a first commit (gen_0000.json is written just before it)."""
    found = [n for n in (rundir.BEST, rundir.SUMMARY, rundir.RECORDING) if (directory / n).exists()]
    hist = directory / rundir.HISTORY
    if hist.is_file() and hist.read_bytes().count(b"\n") > 1:
        found.append(rundir.HISTORY)
    found += [f"{rundir.GENERATIONS}/{p.name}" for p in rundir.generation_files(directory) if rundir.generation_of(p) != 0]
    return found


def commit(run: CommittedRun) -> None:
    """Commit the generation (checkpoint.json), then derive history.csv, best.json, archive.json and the listeners'
    files (:func:`derive`); Ctrl-C (SIGTERM, SIGHUP) waits until all are written."""
    with signals_deferred():
        write_json(
            run.dir / rundir.CHECKPOINT,
            {rundir.SETTINGS_KEY: fingerprint.settings(run.config, run.started_in), rundir.START_KEY: run.start,
             "optimizer": run.optimizer.state().to_dict(), "history": run.history, "best": run.best, "best_genome": run.best_genome,
             "wall_seconds": run.wall, "outcome": run.individuals.to_dict(), "history_terms": run.history_terms,
             "best_walk": run.best_walk, rundir.DIGESTS_KEY: run.generation_digests, **run.context.to_dict()},
        )
        derive(run)


def rebuild(run: CommittedRun) -> None:
    """Make every derived file what the checkpoint says it is; note each repair in ``run.repairs``."""
    d, g = run.dir, run.optimizer.generation
    for p in rundir.remove_stale_temporaries(d):
        run.repairs.append(f"{p.relative_to(d)} removed (a write cut short)")
    (d / rundir.GENERATIONS).mkdir(exist_ok=True)
    for p in rundir.generation_files(d):
        if rundir.generation_of(p) is None or rundir.generation_of(p) >= g:
            p.unlink()
            run.repairs.append(f"{p.relative_to(d)} removed (after the last checkpoint)")
    _cut_individuals(run)
    derive(run, repair=True)
    run.repairs += rundir.check_generation_files(d, {"history": run.history, "best": run.best, "best_genome": run.best_genome,
                                                     rundir.DIGESTS_KEY: run.generation_digests})
    if run.done:
        write_summary(run, repair=True)
    elif (d / rundir.SUMMARY).exists():
        (d / rundir.SUMMARY).unlink()
        run.repairs.append(f"{rundir.SUMMARY} removed (the run is not complete)")


def _cut_individuals(run: CommittedRun) -> None:
    """individuals.jsonl back to the committed generations' lines; say which committed generations it lacks."""
    path, g = run.dir / rundir.INDIVIDUALS, run.optimizer.generation
    size, covered = rundir.committed_size(path, g)
    if path.exists() and path.stat().st_size != size:
        rundir.cut_individuals(path, size)
        run.repairs.append(f"{rundir.INDIVIDUALS} cut back to its committed generations (lines after them removed)")
    if covered < g and run.individuals.previous is not None:  # (a run made before the file was kept has no lineage)
        run.repairs.append(f"{rundir.INDIVIDUALS} lacks generations {covered}..{g - 1} (not in the checkpoint: lost)")


def derive(run: CommittedRun, *, repair: bool = False) -> None:
    """The derived files from the committed state, in this order: the run directory's own (history.csv, best.json,
    a MAP-Elites run's archive.json, each by :func:`~evobiped.files.rundir.sync_file`), then the run's listeners
    (the evolve use case's recording, evolution.rrd).  A repair notes each file it changed in ``run.repairs``."""
    repairs = run.repairs if repair else None
    rundir.sync_file(run.dir, rundir.HISTORY, rundir.history_text(run.history, run.history_terms, run.context.history), repairs)
    rundir.sync_file(run.dir, rundir.BEST, _best_text(run), repairs)
    if run.optimizer.keeps_archive:
        rundir.sync_file(run.dir, rundir.ARCHIVE, rundir.archive_text(run.optimizer.archive_contents()) if run.history else None, repairs)
    committed = bool(run.history)
    commit = Commit(run.dir, rundir.history_columns(run.history, run.history_terms, run.context.history) if committed else None,
                    run.recording_id, run.optimizer.series() if committed else {}, repairs)
    for listener in run.listeners:
        listener.committed(commit)


def _best_text(run: CommittedRun) -> str | None:
    if run.best is None:
        return None
    genome = run.best_genome
    if genome is None:  # a checkpoint written before the best genome was part of it: its generation file
        src = rundir.generation_file(run.dir, run.best["generation"])
        return src.read_text() if src.is_file() else None
    return genome_text(np.array(genome), run.context.best_episode(), **run.best)


def _nominal_walk(run: CommittedRun) -> dict | None:
    """Distance and walking direction of the best walker in the nominal episode (``EpisodeResult.walk``): kept from
    its evaluation.  A perturbed run's evaluation has no nominal presentation (its walks are perturbed), so its
    best is walked once, nominally, for the summary (what a replay checks); so is the best of a checkpoint
    written before walks were kept."""
    if run.best is None or not (run.dir / rundir.BEST).is_file():
        return None
    if run.best_walk is not None and not run.config.episode.perturbed:
        return run.best_walk
    genome, cfg, _ = load_genome(run.dir / rundir.BEST)
    return cfg.nominal().build().run(genome).walk()


def _summary(run: CommittedRun, best_walk: dict | None) -> dict:
    # the stopping rule's verdict only in runs that have one (other summaries as before)
    return rundir.summary_table(version=__version__, generations=run.optimizer.generation, best=run.best, wall_seconds=run.wall,
                                history=run.history, best_walk=best_walk,
                                stopped_early=(run.context.stopped() and not run.context.lost_stop()) if run.config.stop.active else None,
                                lost=None if run.context.attempts is None else run.context.attempts.lost)


def write_summary(run: CommittedRun, *, repair: bool = False) -> dict:
    """summary.json of a complete run (:mod:`evobiped.files.rundir.summary_file`); a repair keeps one whose fields agree
    with the checkpoint (the best walk costs an episode).  Returns the summary."""
    if repair:
        old = rundir.agreeing_summary(run.dir, lambda walk: _summary(run, walk))
        if old is not None:
            return old
        run.repairs.append(f"{rundir.SUMMARY} {'rewritten' if (run.dir / rundir.SUMMARY).exists() else 'written'} from the checkpoint")
    summary = _summary(run, _nominal_walk(run))
    rundir.write_summary_file(run.dir, summary)
    return summary
