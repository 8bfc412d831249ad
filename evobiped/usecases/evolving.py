"""The evolve use case: check everything, create or resume the run, then start the evaluator, then evolve.

Nothing is written and no worker starts before the settings, the start genome (``--from``), the episode's
timing and the run directory are checked; the evaluator (a process pool, threads, Ray actors) starts only once
the run is created or resumed and locked, and a new run whose evaluator fails to start is removed again.
:func:`open_run` and :func:`start_evaluator` are the two steps (a command prints between them: the repairs a
resume made, a complete run); :func:`evolve` is the whole use case in one call.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from ..files import rundir
from ..evaluation import backends as evaluate
from ..evaluation import Evaluator
from ..run import Run
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
             check: Callable[[str, int | None, str | None], None] | None = None) -> OpenRun:
    """A new run of ``config`` in ``out``, or the run in ``resume`` (its saved config; ``backend``, ``workers`` and
    ``address``, when given, replace where its episodes run).  ``check(backend, workers, address)`` (optional, e.g.
    the command's flag checks) refuses where the episodes would run.  Everything is checked before anything is
    written; a resume locks the directory and rebuilds its derived files first (``run.repairs``)."""
    if (config is None) == (resume is None) or (config is not None and out is None):
        raise ValueError("open_run: give a config and its run directory (out), or a run directory to resume")
    if resume is not None:
        run = Run.resume(resume)
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
    return OpenRun(Run.create(out, config), *where, resumed=False)


def start_evaluator(opened: OpenRun, on_retry: Callable[[int, int], None] | None = None) -> Evaluator:
    """Start the evaluator of an opened run (``on_retry(n, limit)``: a dead worker's batch is evaluated again).  When
    it cannot start, the run's lock is released, and a new run's directory is removed again (nothing half-made)."""
    try:
        return evaluate.make_evaluator(opened.run.config.episode, opened.backend, opened.workers, opened.address, on_retry=on_retry)
    except BaseException:
        opened.run.abandon() if not opened.resumed else opened.run.close()
        raise


def evolve(config: RunConfig | str | Path, *, out: str | Path | None = None, backend: str | None = None,
           workers: int | None = None, address: str | None = None, on_generation=None, on_retry=None) -> dict:
    """The whole use case: a new run of ``config`` (a :class:`RunConfig`) in ``out``, or the run directory ``config``
    (a path) resumed, evolved to its last generation; returns its summary (summary.json).  ``on_generation``: called
    with each generation's :class:`~evobiped.evolution.generation_stats.GenerationStats` after its commit."""
    opened = open_run(config, out=out) if isinstance(config, RunConfig) else open_run(resume=config, backend=backend,
                                                                                     workers=workers, address=address)
    with opened.run as run:
        if run.done:  # a resume of a complete run: its summary as it is
            return read_json(run.dir / rundir.SUMMARY, what="run summary")
        with start_evaluator(opened, on_retry) as evaluator:
            return run.evolve(evaluator, on_generation)
