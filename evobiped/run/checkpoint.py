"""A run's commit point: its record read from checkpoint.json (:class:`~evobiped.files.rundir.RunRecord`, every
older format upgraded), committed to it, and every derived file (history.csv, best.json, archive.json,
summary.json, individuals.jsonl, the generation files: the run directory's writers; evolution.rrd: the run's
listeners, :mod:`.listeners`) brought back to what it says.

The formats and writers are :mod:`evobiped.files.rundir`'s; :class:`~.run.Run` calls these at creation, after each
generation and on a resume.  The derived files are functions of the run's config and record (read through the
optimizer and context the record's state is restored into: MAP-Elites' archive, the best's frozen context).
"""

from __future__ import annotations

import uuid
from pathlib import Path
from typing import Sequence

import numpy as np

from .. import __version__
from ..files import rundir
from ..core.errors import UserError, signals_deferred
from ..core.fileio import atomic_write, json_text, read_json, write_json
from ..files.genome_file import genome_text, load_genome
from ..optimizers import Optimizer
from . import fingerprint
from .generation_stats import GenerationFiles
from .individuals import Individuals
from .listeners import Commit, RunListener
from .run_config import RunConfig, make_optimizer, start_genome
from .run_context import RunContext
from .start_genome import kept_start, start_episode, start_file


def load(directory: Path) -> dict:
    """What ``directory``'s config.json and checkpoint.json say, checked field by field before anything is built:
    the :class:`~.run.Run` constructor's arguments and ``started_in`` (the numerical environment config.json
    records, or None).  A run killed before its first commit starts over."""
    if not (directory / rundir.CONFIG).exists() and rundir.is_unused(directory):
        raise UserError(f"{directory} holds no run yet (stopped before its config was written): start it again with "
                        f"evobiped evolve --out {directory}")
    cfg = read_json(directory / rundir.CONFIG, what="run config")
    if not isinstance(cfg, dict):
        raise UserError(f"run config {directory / rundir.CONFIG} is not a table of settings")
    cfg.pop("evobiped", None)
    started_in = cfg.pop("environment", None)
    config = RunConfig.from_dict(cfg, where=str(directory / rundir.CONFIG))
    path = directory / rundir.CHECKPOINT
    ck = read_json(path, what="checkpoint", file_format=rundir.FORMAT) if path.exists() else None
    if path.exists() and ck is None:
        raise UserError(f"checkpoint {path} is null, not a checkpoint: the run cannot be resumed; start a new run")
    settings = fingerprint.settings(config, started_in)
    parts = dict(directory=directory, config=config, started_in=started_in)
    if ck is None:
        committed = committed_files(directory)
        if committed:
            raise UserError(f"{path} is missing but the run has committed generations ({committed[0]}): it cannot be "
                            "resumed; start a new run")
        # killed before its first commit: start over (the normaliser from the start genome's file again)
        start = kept_start(directory, config, None)
        record = rundir.RunRecord(settings, _listed(start))
        return {**parts, "optimizer": make_optimizer(config, start), "record": record,
                "context": RunContext(config, start_episode(directory, config))}
    try:
        ck = rundir.upgrade(ck, directory, settings=settings, start=lambda: _listed(_older_start(directory, config)))
    except UserError as exc:
        raise UserError(f"checkpoint {path} is malformed: {exc}") from None
    if isinstance(ck, dict) and rundir.SETTINGS_KEY in ck:  # before anything is built
        fingerprint.check(ck[rundir.SETTINGS_KEY], config, started_in, directory / rundir.CONFIG)
    opt = make_optimizer(config, kept_start(directory, config, ck))
    try:
        record = rundir.RunRecord.from_dict(ck, generations=config.generations, low=opt.low, high=opt.high)
    except UserError as exc:
        raise UserError(f"checkpoint {path} is malformed: {exc}") from None
    state = opt.state_from(record.optimizer)
    if len(record.history) != state.generation:  # before the state is restored: an older CMA-ES state is replayed
        raise UserError(f"checkpoint {path} is inconsistent (history has {len(record.history)} rows for generation "
                        f"{state.generation})")
    opt.restore(state)
    context = RunContext(config)  # its state is the record's
    context.restore(record.context)
    individuals = Individuals.from_dict(record.outcome, len(opt.population))
    # the record as this code writes it: the settings as read now (checked above), each part's state as restored
    record = record.replace(settings=settings, optimizer=opt.state().to_dict(), outcome=individuals.to_dict(),
                            context=context.to_dict())
    return {**parts, "optimizer": opt, "record": record, "individuals": individuals, "context": context}


def _older_start(directory: Path, config: RunConfig) -> np.ndarray | None:
    """The start genome of a run whose record is older than its ``start``: start.json's, else its source's."""
    kept = start_file(directory, config)
    return kept if kept is not None else start_genome(config)


def _listed(genome: np.ndarray | None) -> list[float] | None:
    return None if genome is None else [float(x) for x in genome]


def committed_files(directory: Path) -> list[str]:
    """Files that exist only after a first commit (gen_0000.json is written just before it)."""
    found = [n for n in (rundir.BEST, rundir.SUMMARY, rundir.RECORDING) if (directory / n).exists()]
    hist = directory / rundir.HISTORY
    if hist.is_file() and hist.read_bytes().count(b"\n") > 1:
        found.append(rundir.HISTORY)
    found += [f"{rundir.GENERATIONS}/{p.name}" for p in rundir.generation_files(directory)
              if rundir.generation_of(p) != 0]
    return found


def recording_id(config: RunConfig) -> str:
    """The run's recording id: its config's (the same for every session of the run)."""
    return str(uuid.uuid5(uuid.NAMESPACE_OID, json_text(config.to_dict())))


def commit(directory: Path, config: RunConfig, record: rundir.RunRecord, files: GenerationFiles | None, *,
           optimizer: Optimizer, context: RunContext, listeners: Sequence[RunListener]) -> None:
    """Write the generation's ``files`` (its generation file, its individuals.jsonl lines; None: none), then commit
    ``record`` (checkpoint.json) and derive history.csv, best.json, archive.json and the ``listeners``' files
    (:func:`derive`); Ctrl-C (SIGTERM, SIGHUP) waits from checkpoint.json until all are written.  A kill before
    checkpoint.json leaves the generation uncommitted: a resume removes its files."""
    if files is not None:
        atomic_write(rundir.generation_file(directory, files.generation), files.text)
        rundir.append_individuals(directory / rundir.INDIVIDUALS, files.individuals)
    with signals_deferred():
        write_json(directory / rundir.CHECKPOINT, record.to_dict())
        derive(directory, config, record, optimizer=optimizer, context=context, listeners=listeners)


def rebuild(directory: Path, config: RunConfig, record: rundir.RunRecord, *, optimizer: Optimizer, context: RunContext,
            listeners: Sequence[RunListener], individuals: Individuals, done: bool) -> list[str]:
    """Make every derived file what ``record`` says it is (``done``: the run is complete); returns each repair, one
    sentence each."""
    d, g, repairs = directory, len(record.history), []
    for p in rundir.remove_stale_temporaries(d):
        repairs.append(f"{p.relative_to(d)} removed (a write cut short)")
    (d / rundir.GENERATIONS).mkdir(exist_ok=True)
    for p in rundir.generation_files(d):
        if rundir.generation_of(p) is None or rundir.generation_of(p) >= g:
            p.unlink()
            repairs.append(f"{p.relative_to(d)} removed (after the last checkpoint)")
    repairs += _cut_individuals(d, g, individuals)
    derive(d, config, record, optimizer=optimizer, context=context, listeners=listeners, repairs=repairs)
    repairs += rundir.check_generation_files(d, record.to_dict())
    if done:
        write_summary(d, config, record, context=context, repairs=repairs)
    elif (d / rundir.SUMMARY).exists():
        (d / rundir.SUMMARY).unlink()
        repairs.append(f"{rundir.SUMMARY} removed (the run is not complete)")
    return repairs


def _cut_individuals(directory: Path, g: int, individuals: Individuals) -> list[str]:
    """individuals.jsonl back to the ``g`` committed generations' lines; say which committed generations it lacks."""
    path, repairs = directory / rundir.INDIVIDUALS, []
    size, covered = rundir.committed_size(path, g)
    if path.exists() and path.stat().st_size != size:
        rundir.cut_individuals(path, size)
        repairs.append(f"{rundir.INDIVIDUALS} cut back to its committed generations (lines after them removed)")
    if covered < g and individuals.previous is not None:  # (a run made before the file was kept has no lineage)
        repairs.append(f"{rundir.INDIVIDUALS} lacks generations {covered}..{g - 1} (not in the checkpoint: lost)")
    return repairs


def derive(directory: Path, config: RunConfig, record: rundir.RunRecord, *, optimizer: Optimizer, context: RunContext,
           listeners: Sequence[RunListener], repairs: list[str] | None = None) -> None:
    """The derived files of ``record``, in this order: the run directory's own (history.csv, best.json, a
    MAP-Elites run's archive.json, each by :func:`~evobiped.files.rundir.sync_file`), then the ``listeners``' (the
    evolve use case's recording, evolution.rrd).  ``optimizer`` and ``context``: the record's state restored (the
    archive, the best's frozen context).  ``repairs`` (a resume's; None: a commit) notes each file it changed."""
    extra = record.context.get("history_extra", [])
    history = rundir.history_text(record.history, record.history_terms, extra)
    rundir.sync_file(directory, rundir.HISTORY, history, repairs)
    best = record.best
    text = None if best is None else genome_text(np.array(record.best_genome), context.best_episode(), **best)
    rundir.sync_file(directory, rundir.BEST, text, repairs)
    committed = bool(record.history)
    if optimizer.keeps_archive:
        archive = rundir.archive_text(optimizer.archive_contents()) if committed else None
        rundir.sync_file(directory, rundir.ARCHIVE, archive, repairs)
    columns = rundir.history_columns(record.history, record.history_terms, extra) if committed else None
    commit = Commit(directory, columns, recording_id(config), optimizer.series() if committed else {}, repairs)
    for listener in listeners:
        listener.committed(commit)


def _nominal_walk(directory: Path, config: RunConfig, record: rundir.RunRecord) -> dict | None:
    """Distance and walking direction of the best walker in the nominal episode (``EpisodeResult.walk``): kept from
    its evaluation.  A perturbed run's evaluation has no nominal presentation (its walks are perturbed), so its
    best is walked once, nominally, for the summary (what a replay checks); so is a best whose walk is not known
    (the record of a format before walks were kept)."""
    if record.best is None or not (directory / rundir.BEST).is_file():
        return None
    if record.best_walk is not None and not config.episode.perturbed:
        return record.best_walk
    genome, cfg, _ = load_genome(directory / rundir.BEST)
    return cfg.nominal().build().run(genome).walk()


def _summary(config: RunConfig, record: rundir.RunRecord, context: RunContext, best_walk: dict | None) -> dict:
    # the stopping rule's verdict only in runs that have one (other summaries as before)
    stopped_early = (context.stopped() and not context.lost_stop()) if config.stop.active else None
    return rundir.summary_table(version=__version__, generations=len(record.history), best=record.best,
                                wall_seconds=record.wall_seconds, history=record.history, best_walk=best_walk,
                                stopped_early=stopped_early,
                                lost=None if context.attempts is None else context.attempts.lost)


def write_summary(directory: Path, config: RunConfig, record: rundir.RunRecord, *, context: RunContext,
                  repairs: list[str] | None = None) -> dict:
    """summary.json of a complete run (:mod:`evobiped.files.rundir.summary_file`); a repair (``repairs``: a
    resume's, noted there) keeps one whose fields agree with the record (the best walk costs an episode).  Returns
    the summary."""
    if repairs is not None:
        old = rundir.agreeing_summary(directory, lambda walk: _summary(config, record, context, walk))
        if old is not None:
            return old
        how = "rewritten" if (directory / rundir.SUMMARY).exists() else "written"
        repairs.append(f"{rundir.SUMMARY} {how} from the checkpoint")
    summary = _summary(config, record, context, _nominal_walk(directory, config, record))
    rundir.write_summary_file(directory, summary)
    return summary
