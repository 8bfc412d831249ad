"""Many independent evolutionary runs per condition, and their statistics (Reil & Husbands Sect. III).

A study runs K seeds for each condition, a fitness criterion the run's task
declares (``Task.criteria``; the walk task's "plain" = eq. 4, "cyclic" = eq. 4
with the cyclic-activity criterion, "forward"), one whole run per task, spread
over local processes or a Ray cluster; the task must return the terms in
:data:`TERMS`.  Study directory::

    study.json                 the StudyConfig
    <condition>/seed_NNN/      an ordinary run directory (evobiped evolve's)
        outcome.json           the run's result, with the long re-check
    runs.csv                   one row per run (these results: :mod:`.study_results`)
    table.csv table.md table.json   per condition: success rate (Wilson 95 %),
                               distances of stable / unstable best walkers, wall time
    distances.png              Fig. 5: distance histograms, stable and unstable apart
    fitness_graphs.png         best fitness per generation of every run

Distances are eq. 4's (for the cyclic condition the fitness is larger), read
from each run's summary (its best walker on the nominal episode).
"Stable" is the paper's: the run's best walker did not fall within the
episode (50 s).  Each stable walker is re-simulated for ``recheck_seconds``
(200 s by default); "walks indefinitely" counts those still up at the end.

Interrupting a study loses at most the generation each run was in: running
the same command again skips finished runs and resumes the others from their
checkpoints.
"""

from __future__ import annotations

import dataclasses
import os
from concurrent.futures import as_completed
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

from ... import __version__
from ...files import rundir
from ...core.errors import ConfigError, UserError
from ...core.options import given
from ...evaluation.ray_backend import init_ray
from ...evaluation.pool import spawn_pool, stop_pool
from ...controllers import CONTROLLERS
from ...tasks import TASKS
from ...optimizers import OPTIMIZERS
from ...run import RunConfig
from ...core.fileio import read_json, write_json
from ...files.genome_file import load_genome
from ...core.progress import Progress
from ...usecases.evolving import evolve

#: the fitness terms a study needs of the run's task (besides the criteria its conditions name, ``Task.criteria``)
TERMS = ("distance",)
#: a walker in the sense of the walker targets: up for the whole re-check, at least this far (m) in
#: the episode, within this angle (degrees) of the direction it faced at the start
WALKER_DISTANCE, WALKER_ANGLE = 20.0, 30.0


@dataclass(frozen=True, kw_only=True)
class StudyConfig:
    """K runs per condition of one base run config; seeds first_seed .. first_seed + K - 1."""

    run: RunConfig = field(default_factory=RunConfig)
    runs: int = 10
    conditions: tuple[str, ...] = ("plain", "cyclic")
    #: controller and optimizer axes (empty: the base run's); conditions are their product with ``conditions``
    controllers: tuple[str, ...] = ()
    optimizers: tuple[str, ...] = ()
    first_seed: int = 0
    recheck_seconds: float = 200.0

    def __post_init__(self):
        if not (isinstance(self.runs, int) and self.runs >= 1):
            raise ConfigError(f"study runs must be an integer >= 1, got {self.runs!r}")
        task = TASKS[self.run.episode.task]
        if not task.criteria or any(t not in task.term_names for t in TERMS):
            raise ConfigError(f"a study compares fitness criteria by the terms {', '.join(TERMS)}; the run's task "
                              f"{task.name!r} declares criteria {list(task.criteria)} and terms "
                              f"{list(task.term_names)}")
        unknown = [c for c in self.conditions if c not in task.criteria]
        if unknown or not self.conditions or len(set(self.conditions)) != len(self.conditions):
            raise ConfigError(f"study conditions must be distinct names from {', '.join(task.criteria)}, got "
                              f"{list(self.conditions)}")
        for axis, names, registry in (("controllers", self.controllers, CONTROLLERS),
                                      ("optimizers", self.optimizers, OPTIMIZERS)):
            if any(n not in registry for n in names) or len(set(names)) != len(names):
                raise ConfigError(f"study {axis} must be distinct names from {', '.join(registry)}, got {list(names)}")
        if not (isinstance(self.first_seed, int) and self.first_seed >= 0):
            raise ConfigError(f"first seed must be an integer >= 0, got {self.first_seed!r}")
        if not self.recheck_seconds > 0:
            raise ConfigError(f"recheck seconds must be > 0, got {self.recheck_seconds!r}")

    @property
    def cells(self) -> dict[str, tuple[str, str, str]]:
        """Condition name -> (controller, optimizer, criterion), in order.  Without axes the names are
        the criteria (plain, cyclic, forward); with them ``controller-optimizer-criterion``."""
        ctrls = self.controllers or (self.run.episode.controller,)
        opts = self.optimizers or (self.run.optimizer,)
        axes = bool(self.controllers or self.optimizers)
        return {(f"{c}-{o}-{k}" if axes else k): (c, o, k) for c in ctrls for o in opts for k in self.conditions}

    @property
    def condition_names(self) -> tuple[str, ...]:
        return tuple(self.cells)

    def run_config(self, condition: str, k: int) -> RunConfig:
        """The run of seed ``first_seed + k`` in ``condition`` (evaluated serially: one run per task).

        A controller on the axis other than the base run's gets its default options."""
        controller, optimizer, criterion = self.cells[condition]
        ep = self.run.episode
        options = ep.controller_options if controller == ep.controller else {}
        episode = dataclasses.replace(ep, controller=controller, controller_options=options,
                                      task_options={**given(ep.task_options), **TASKS[ep.task].criteria[criterion]})
        return dataclasses.replace(self.run, episode=episode, optimizer=optimizer, seed=self.first_seed + k,
                                   backend="serial", workers=None, address=None)

    def identity(self) -> dict:
        """What must match for a directory to be resumed as this study (K may grow or shrink)."""
        d = self.to_dict()
        d.pop("runs")
        for k in ("backend", "workers", "address"):
            d["run"].pop(k)
        return d

    def to_dict(self) -> dict:
        return {"run": self.run.to_dict(), "runs": self.runs, "conditions": list(self.conditions),
                "controllers": list(self.controllers),
                "optimizers": list(self.optimizers), "first_seed": self.first_seed,
                "recheck_seconds": self.recheck_seconds}

    @classmethod
    def from_dict(cls, d: dict, *, where: str = "study") -> "StudyConfig":
        d = dict(d)
        run = RunConfig.from_dict(d.pop("run", {}), where=where)
        try:
            axes = {k: tuple(d.pop(k, ())) for k in ("controllers", "optimizers")}
            return cls(run=run, conditions=tuple(d.pop("conditions", ("plain", "cyclic"))), **axes, **d)
        except TypeError as exc:
            raise ConfigError(f"{where}: {exc}") from None


def run_dir(study: Path, condition: str, k: int, cfg: StudyConfig) -> Path:
    return study / condition / f"seed_{cfg.first_seed + k:03d}"


# ---------------------------------------------------------------- one run (in a worker)
def run_one(directory: str, config: dict, condition: str, recheck_seconds: float) -> dict:
    """Create, resume or skip the run in ``directory``; re-check a stable best walker.  Returns the outcome."""
    d = Path(directory)
    if (d / rundir.OUTCOME).is_file():
        return read_json(d / rundir.OUTCOME, what="run outcome")
    run_cfg = RunConfig.from_dict(config)  # evaluated serially (StudyConfig.run_config): one run per worker
    summary = evolve(d if (d / rundir.CONFIG).is_file() else run_cfg, out=d)  # a finished run: its summary as it is
    best = summary["best"]
    walk = summary["best_walk"]  # eq. 4's distance and the direction, of the nominal episode (the run's summary)
    outcome = {
        "condition": condition,
        "seed": run_cfg.seed,
        "fitness": best["fitness"],
        "distance": walk["distance"],
        "heading_deg": walk["heading_deg"],
        "fell": best["fell"],
        "end_time": best["end_time"],
        "generation": best["generation"],
        "wall_seconds": summary["wall_seconds"],
        "recheck_seconds": recheck_seconds,
        "walks_indefinitely": None,
        "recheck_end_time": None,
    }
    if not best["fell"]:  # the long re-check (up for it: up for the nominal episode too, its first part)
        genome, ep_cfg, _ = load_genome(d / rundir.BEST)
        r = dataclasses.replace(ep_cfg.nominal(), seconds=float(recheck_seconds)).build().run(genome)
        outcome["walks_indefinitely"] = not bool(r.fell[0])
        outcome["recheck_end_time"] = float(r.end_time[0])
    outcome["forward_walker"] = bool(outcome["walks_indefinitely"] and outcome["distance"] >= WALKER_DISTANCE
                                     and outcome["heading_deg"] is not None
                                         and abs(outcome["heading_deg"]) <= WALKER_ANGLE)
    write_json(d / rundir.OUTCOME, outcome)
    return outcome


# ---------------------------------------------------------------- the study
def open_study(directory: str | Path, config: StudyConfig) -> Path:
    """A new study directory, or an existing one holding the same study (resume); UserError otherwise."""
    d = Path(directory)
    saved = d / "study.json"
    if saved.is_file():
        old = read_json(saved, what="study config")
        old.pop("evobiped", None)
        if StudyConfig.from_dict(old, where=str(saved)).identity() != config.identity():
            raise UserError(f"{d} holds a different study (compare {saved}); use another --out")
    elif d.exists() and (not d.is_dir() or any(d.iterdir())):
        raise UserError(f"{d} exists and is not a study directory; use another --out")
    d.mkdir(parents=True, exist_ok=True)
    write_json(saved, {"evobiped": __version__, **config.to_dict()})
    return d


def run_study(
    directory: str | Path,
    config: StudyConfig,
    *,
    backend: str = "process",
    workers: int | None = None,
    address: str | None = None,
    progress: Callable[[str], None] | None = None,
) -> list[dict]:
    """Run (or finish) every run of the study; returns the outcomes, condition by condition."""
    say = progress or (lambda msg: None)
    if backend not in ("process", "serial", "ray"):
        raise ConfigError(f"unknown study backend {backend!r} (choose from process, serial, ray)")
    d = open_study(directory, config)
    tasks = [
        (str(run_dir(d, c, k, config)), config.run_config(c, k).to_dict(), c, config.recheck_seconds)
        for c in config.condition_names
        for k in range(config.runs)
    ]
    todo = [t for t in tasks if not (Path(t[0]) / rundir.OUTCOME).is_file()]
    say(f"study {d}: {len(config.condition_names)} condition(s) x {config.runs} runs, {len(tasks) - len(todo)} already "
        f"done, {config.run.generations} generations, {config.run.episode.seconds:g} s episodes")
    line = Progress("study", len(todo), "runs", emit=say)
    done = 0

    def report(o: dict) -> None:
        nonlocal done
        done += 1
        state = "stayed up" if not o["fell"] else f"fell at {o['end_time']:.1f} s"
        way = "" if o["heading_deg"] is None else f" at {o['heading_deg']:+.0f} deg"
        line.report(done, f"last: {o['condition']} seed {o['seed']}, best fitness {o['fitness']:.2f}, "
                          f"{o['distance']:.1f} m{way} ({state})")

    if todo and backend == "serial":
        for t in todo:
            report(run_one(*t))
    elif todo and backend == "process":
        n = min(workers or os.cpu_count() or 1, len(todo))
        pool = spawn_pool(n)
        try:
            for f in as_completed([pool.submit(run_one, *t) for t in todo]):
                report(f.result())
        finally:
            stop_pool(pool)
    elif todo:
        ray, owns = init_ray(address, workers)
        try:
            remote = ray.remote(num_cpus=1)(run_one)
            pending = [remote.remote(*t) for t in todo]
            while pending:
                ready, pending = ray.wait(pending, num_returns=1)
                report(ray.get(ready[0]))
        finally:
            if owns:
                ray.shutdown()
    return [read_json(Path(t[0]) / rundir.OUTCOME, what="run outcome") for t in tasks]
