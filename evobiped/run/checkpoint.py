"""A run's commit point and the files derived from it: reading and checking checkpoint.json, writing it, and
bringing every derived file (history.csv, best.json, evolution.rrd, summary.json, individuals.jsonl, the
generation files) back to what it says.

The formats are :mod:`evobiped.files.rundir`'s; :class:`~.run.Run` calls these at creation, after each generation and
on a resume.
"""

from __future__ import annotations

from pathlib import Path
from typing import Protocol

import numpy as np

from .. import __version__
from ..files import rundir
from ..core.errors import UserError, signals_deferred
from ..core.fileio import atomic_write, json_text, read_json, write_json
from ..files.genome_file import genome_text, load_genome
from . import fingerprint
from ..optimizers import Optimizer
from .individuals import Individuals
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
    """Commit the generation (checkpoint.json), then derive history.csv, best.json and evolution.rrd;
    Ctrl-C (SIGTERM, SIGHUP) waits until all are written."""
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


def _sync(run: CommittedRun, name: str, text: str | None, *, repair: bool) -> None:
    """Give file ``name`` the content ``text`` (None: no such file) unless it has it; a repair says so."""
    path = run.dir / name
    try:
        current = path.read_text() if path.exists() else None
    except (OSError, UnicodeDecodeError):
        current = ""
    if current == text:
        return
    if repair:
        run.repairs.append(f"{name} {'rewritten from the checkpoint' if text is not None else 'removed (no generation is complete)'}")
    if text is None:
        path.unlink(missing_ok=True)
    else:
        atomic_write(path, text)


def derive(run: CommittedRun, *, repair: bool = False) -> None:
    """history.csv, best.json and evolution.rrd from the committed state."""
    from ..record.recordings.evolution_log import recording_matches, write_recording

    _sync(run, rundir.HISTORY, rundir.history_text(run.history, run.history_terms, run.context.history), repair=repair)
    _sync(run, rundir.BEST, _best_text(run), repair=repair)
    for name, text in run.optimizer.derived_files(bool(run.history)).items():  # e.g. MAP-Elites' archive.json
        _sync(run, name, text, repair=repair)
    rec = run.dir / rundir.RECORDING
    if not run.history:
        if rec.exists():
            _sync(run, rundir.RECORDING, None, repair=repair)
        return
    columns = rundir.history_columns(run.history, run.history_terms, run.context.history)
    if repair:
        if recording_matches(rec, columns):
            return
        run.repairs.append(f"{rundir.RECORDING} rebuilt from the checkpoint")
    write_recording(rec, columns, run.recording_id, run.optimizer.series())


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
    out = {
        "evobiped": __version__,
        "generations": run.optimizer.generation,
        "best": run.best,
        "wall_seconds": round(run.wall, 3),
        "evaluations": int(sum(rundir.column(run.history, "evaluations"))),
        "stable": run.best is not None and not run.best["fell"],
        "best_walk": best_walk,
    }
    if run.config.stop.active:  # the stopping rule's verdict (only in runs that have one: other summaries as before)
        out["stopped_early"] = run.context.stopped()
    return out


def write_summary(run: CommittedRun, *, repair: bool = False) -> dict:
    """summary.json of a complete run; a repair keeps one whose fields agree with the checkpoint (the best walk
    costs an episode).  Returns the summary."""
    path = run.dir / rundir.SUMMARY
    if repair:
        try:
            old = read_json(path, what="summary") if path.exists() else None
            if isinstance(old, dict) and "best_walk" in old and path.read_text() == json_text(_summary(run, old["best_walk"])):
                return old
        except UserError:
            pass
        run.repairs.append(f"{rundir.SUMMARY} {'rewritten' if path.exists() else 'written'} from the checkpoint")
    summary = _summary(run, _nominal_walk(run))
    write_json(path, summary)
    return summary

