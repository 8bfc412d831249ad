"""The evolve use case: check everything, create or resume the run, then start the evaluator, then evolve.

Nothing is written and no worker starts before the settings, the start genome (``--from``), the episode's
timing and the run directory are checked; the evaluator (a process pool, threads, Ray actors) starts only once
the run is created or resumed and locked, and a new run whose evaluator fails to start is removed again.
:func:`open_run` and :func:`start_evaluator` are the two steps (a command prints between them: the repairs a
resume made, a complete run); :func:`evolve` is the whole use case in one call, the one entry point of the
``evolve`` command, a study's runs and a comparison's, with hooks for what a caller shows as the run goes (the run
opened, the generations begun, every evaluated batch, each generation, the end, a stop signal).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Sequence

from ..files import rundir
from ..episode.result import EpisodeResult
from ..evaluation import backends as evaluate
from ..evaluation import Evaluator
from ..run import Run
from ..run.listeners import RunListener
from ..run.run_config import RunConfig, check_run
from ..core.fileio import read_json


@dataclass
class OpenRun:
    """A created or resumed run (its directory locked) and where its episodes run."""

    run: Run
    backend: str
    workers: int | None
    address: str | None
    resumed: bool


def open_run(config: RunConfig | None = None, *, out: str | Path | None = None, resume: str | Path | None = None,
             backend: str | None = None, workers: int | None = None, address: str | None = None,
             check: Callable[[str, int | None, str | None], None] | None = None,
             listeners: Sequence[RunListener] | None = None) -> OpenRun:
    """A new run of ``config`` in ``out``, or the run in ``resume`` (its saved config; ``backend``, ``workers`` and
    ``address``, when given, replace where its episodes run).  ``check(backend, workers, address)`` (optional, e.g.
    the command's flag checks) refuses where the episodes would run.  Everything is checked before anything is
    written; a resume locks the directory and rebuilds its derived files first (``run.repairs``).  ``listeners``:
    told of each commit (default :func:`run_listeners`: the run's recording, evolution.rrd)."""
    listeners = run_listeners() if listeners is None else listeners
    if (config is None) == (resume is None) or (config is not None and out is None):
        raise ValueError("open_run: give a config and its run directory (out), or a run directory to resume")
    if resume is not None:
        run = Run.resume(resume, listeners)
        try:
            c = run.config
            where = (backend or c.backend, workers or c.workers, address or c.address)
            if check is not None:
                check(*where)
            c.episode.check()  # what a worker would refuse, before any starts
        except BaseException:
            run.close()
            raise
        return OpenRun(run, *where, resumed=True)
    where = (config.backend, config.workers, config.address)
    if check is not None:
        check(*where)
    check_run(config)  # memory, the start genome
    config.episode.check()  # the episode's timing: what a worker would refuse
    return OpenRun(Run.create(out, config, listeners), *where, resumed=False)


def run_listeners() -> list[RunListener]:
    """What a run evolved by this use case tells of each commit: the recording of its fitness per generation
    (evolution.rrd, :class:`~evobiped.record.recordings.evolution_log.RecordingFile`)."""
    from ..record.recordings.evolution_log import RecordingFile  # Rerun itself only once a recording is written

    return [RecordingFile()]


def start_evaluator(opened: OpenRun, on_retry: Callable[[int, int], None] | None = None) -> Evaluator:
    """Start the evaluator of an opened run (``on_retry(n, limit)``: a dead worker's batch is evaluated again).  When
    it cannot start, the run's lock is released, and a new run's directory is removed again (nothing half-made)."""
    try:
        return evaluate.make_evaluator(opened.run.config.episode, opened.backend, opened.workers, opened.address,
                                       on_retry=on_retry)
    except BaseException:
        if opened.resumed:
            opened.run.close()
        else:
            opened.run.abandon()
        raise


def default_run_dir(config: RunConfig) -> str:
    """Where a new run goes when no directory is named: ``runs/<body>_<controller>_seed<seed>``, or the first of
    ``..._2``, ``..._3``, ... that does not exist yet."""
    where = config.episode.body if config.episode.env is None else config.episode.env.replace("/", "_")
    base = Path("runs") / f"{where}_{config.episode.controller}_seed{config.seed}"
    path, i = base, 1
    while path.exists():
        i += 1
        path = base.with_name(f"{base.name}_{i}")
    return str(path)


def stop_report(run: Run) -> str:
    """What a stop signal left of ``run``: the generations committed and whether the run is complete (one line)."""
    g = run.optimizer.generation
    if g == 0:
        return (f"evobiped: interrupted before its first generation was committed (no checkpoint yet); "
                f"evobiped evolve --resume {run.dir} starts it from the beginning")
    if not run.done:
        return (f"evobiped: interrupted after generation {g - 1} (numbered from 0, as in {rundir.HISTORY}); checkpoint "
                f"saved; continue with: evobiped evolve --resume {run.dir}")
    if (run.dir / rundir.SUMMARY).is_file():
        return (f"evobiped: interrupted after the run completed: all {g} generations and {rundir.SUMMARY} are written "
                f"in {run.dir}")
    return (f"evobiped: interrupted after the last of {g} generations was committed, before {rundir.SUMMARY} was "
            f"written; the run is complete once evobiped evolve --resume {run.dir} writes it")


class _Watched:
    """An evaluator that hands every evaluated batch's rows (one per episode: each walker's presentations) to a hook."""

    def __init__(self, evaluator: Evaluator, on_evaluated: Callable[[EpisodeResult], None]):
        self.evaluator, self.on_evaluated = evaluator, on_evaluated

    def evaluate(self, genomes, key=None, **context):
        # the run's context, if any (normaliser, phase weights)
        result = self.evaluator.evaluate(genomes, key=key, **context)
        self.on_evaluated(result.rows if result.rows is not None else result)
        return result

    def __getattr__(self, name):
        return getattr(self.evaluator, name)


def evolve(config: RunConfig | str | Path, *, out: str | Path | None = None, backend: str | None = None,
           workers: int | None = None, address: str | None = None, check=None, on_opened=None, on_started=None,
           on_evaluated=None, on_generation=None, on_retry=None, on_done=None, on_stop=None) -> dict:
    """The whole use case: a new run of ``config`` (a :class:`RunConfig`) in ``out`` (default :func:`default_run_dir`),
    or the run directory ``config`` (a path) resumed (``backend``, ``workers``, ``address``: where its episodes run
    now), evolved to its last generation; returns its summary (summary.json).  ``check``: as :func:`open_run`'s.

    Hooks, each optional: ``on_opened(run)`` once the run is created or resumed and locked, before any worker starts
    (a resume's ``run.repairs``; a complete run, ``run.done``, evolves no further and its summary is returned as it
    is); ``on_started(run, backend)`` once the evaluator has started; ``on_evaluated(rows)`` with the
    :class:`~evobiped.episode.result.EpisodeResult` of every evaluated batch's episodes (``end_time`` (N,) s, one row
    per walker and presentation); ``on_generation(stats)`` with each generation's
    :class:`~evobiped.run.generation_stats.GenerationStats` after its commit; ``on_retry(n, limit)`` when a dead
    worker's batch is evaluated again; ``on_done(run, summary)`` once the last generation is committed and the
    workers are closed.  A stop signal (KeyboardInterrupt) from the evaluator's start until ``on_done`` returns
    calls ``on_stop(line)`` with :func:`stop_report`'s line, then goes on up."""
    opened = (open_run(config, out=out or default_run_dir(config), check=check) if isinstance(config, RunConfig)
              else open_run(resume=config, backend=backend, workers=workers, address=address, check=check))
    with opened.run as run:
        if on_opened is not None:
            on_opened(run)
        if run.done:  # a resume of a complete run: its summary as it is
            return read_json(run.dir / rundir.SUMMARY, what="run summary")
        evaluator = start_evaluator(opened, on_retry)  # last: the workers start once the run is created or resumed
        try:
            with evaluator:
                if on_started is not None:
                    on_started(run, opened.backend)
                summary = run.evolve(evaluator if on_evaluated is None else _Watched(evaluator, on_evaluated),
                                     on_generation)
            if on_done is not None:
                on_done(run, summary)
            return summary
        # Ctrl-C, SIGTERM, SIGHUP, at any moment (closing the workers, the caller's last line)
        except KeyboardInterrupt:
            if on_stop is not None:
                on_stop(stop_report(run))
            raise
