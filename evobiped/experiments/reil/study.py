"""Many independent evolutionary runs per condition, and their statistics (Reil & Husbands Sect. III).

A study runs K seeds for each condition, a fitness criterion the run's task
declares (``Task.criteria``; the walk task's "plain" = eq. 4, "cyclic" = eq. 4
with the cyclic-activity criterion, "forward"), one whole run per task, spread
over local processes or a Ray cluster; the task must return the terms in
:data:`TERMS`.  Study directory::

    study.json                 the StudyConfig
    <condition>/seed_NNN/      an ordinary run directory (evobiped evolve's)
        outcome.json           the run's result, with the long re-check
    runs.csv                   one row per run
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

import csv
import dataclasses
import io
import os
from concurrent.futures import as_completed
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

from ... import __version__, rundir
from ...errors import ConfigError, UserError
from ...options import given
from ...evolution.evaluate import SerialEvaluator
from ...evolution.ray_backend import init_ray
from ...evolution.pool import spawn_pool, stop_pool
from ...controllers import CONTROLLERS
from ...tasks import TASKS
from ...evolution.run import Run
from ...evolution.run_config import OPTIMIZERS, RunConfig
from ...fileio import atomic_write, read_json, write_json
from ...genome_file import load_genome
from ...progress import Progress
from .stats import histogram_edges, mean_std, wilson_interval

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
                              f"{task.name!r} declares criteria {list(task.criteria)} and terms {list(task.term_names)}")
        unknown = [c for c in self.conditions if c not in task.criteria]
        if unknown or not self.conditions or len(set(self.conditions)) != len(self.conditions):
            raise ConfigError(f"study conditions must be distinct names from {', '.join(task.criteria)}, got {list(self.conditions)}")
        for axis, names, registry in (("controllers", self.controllers, CONTROLLERS), ("optimizers", self.optimizers, OPTIMIZERS)):
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
        return {"run": self.run.to_dict(), "runs": self.runs, "conditions": list(self.conditions), "controllers": list(self.controllers),
                "optimizers": list(self.optimizers), "first_seed": self.first_seed, "recheck_seconds": self.recheck_seconds}

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
    run_cfg = RunConfig.from_dict(config)
    run = Run.resume(d) if (d / rundir.CONFIG).is_file() else Run.create(d, run_cfg)
    with run, SerialEvaluator(run_cfg.episode) as ev:  # the run's lock is released when it ends
        summary = run.evolve(ev)  # a finished run only writes its summary again
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
                                     and outcome["heading_deg"] is not None and abs(outcome["heading_deg"]) <= WALKER_ANGLE)
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
    say(f"study {d}: {len(config.condition_names)} condition(s) x {config.runs} runs, {len(tasks) - len(todo)} already done, "
        f"{config.run.generations} generations, {config.run.episode.seconds:g} s episodes")
    line = Progress("study", len(todo), "runs", emit=say)
    done = 0

    def report(o: dict) -> None:
        nonlocal done
        done += 1
        state = "stayed up" if not o["fell"] else f"fell at {o['end_time']:.1f} s"
        way = "" if o["heading_deg"] is None else f" at {o['heading_deg']:+.0f} deg"
        line.report(done, f"last: {o['condition']} seed {o['seed']}, best fitness {o['fitness']:.2f}, {o['distance']:.1f} m{way} ({state})")

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


# ---------------------------------------------------------------- statistics and files
def summarize(outcomes: list[dict], conditions: tuple[str, ...]) -> list[dict]:
    """One row per condition: counts, success rate with Wilson 95 % interval, distances, wall time."""
    rows = []
    for c in conditions:
        runs = [o for o in outcomes if o["condition"] == c]
        stable = [o["distance"] for o in runs if not o["fell"]]
        unstable = [o["distance"] for o in runs if o["fell"]]
        n, k = len(runs), len(stable)
        lo, hi = wilson_interval(k, n)
        sm, ss = mean_std(stable)
        um, us = mean_std(unstable)
        rows.append({
            "condition": c,
            "runs": n,
            "stable": k,
            "success_rate": k / n if n else float("nan"),
            "ci95_low": lo,
            "ci95_high": hi,
            "stable_mean_m": sm,
            "stable_std_m": ss,
            "unstable_mean_m": um,
            "unstable_std_m": us,
            "walks_indefinitely": sum(1 for o in runs if o["walks_indefinitely"]),
            "forward_walkers": sum(1 for o in runs if o.get("forward_walker")),
            "wall_seconds": float(sum(o["wall_seconds"] for o in runs)),
        })
    return rows


RUN_COLUMNS = ("condition", "seed", "distance", "heading_deg", "fitness", "fell", "end_time", "generation", "wall_seconds",
               "walks_indefinitely", "recheck_end_time", "forward_walker")


def _csv(rows: list[dict], columns) -> str:
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=list(columns), lineterminator="\n", extrasaction="ignore")
    w.writeheader()
    w.writerows(rows)
    return buf.getvalue()


def _fmt(x: float, spec: str = ".2f") -> str:
    return "–" if x != x else format(x, spec)


def table_markdown(rows: list[dict], recheck_seconds: float) -> str:
    lines = [
        f"| condition | runs | stable (no fall in the episode) | success rate [95 % Wilson CI] | stable: distance (m) mean ± σ | unstable: distance (m) mean ± σ | walks {recheck_seconds:g} s | forward walkers | wall time, runs summed (s) |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['condition']} | {r['runs']} | {r['stable']} | {100 * r['success_rate']:.0f} % [{100 * r['ci95_low']:.0f}, {100 * r['ci95_high']:.0f}] | "
            f"{_fmt(r['stable_mean_m'])} ± {_fmt(r['stable_std_m'])} | {_fmt(r['unstable_mean_m'])} ± {_fmt(r['unstable_std_m'])} | "
            f"{r['walks_indefinitely']} | {r['forward_walkers']} | {r['wall_seconds']:.0f} |"
        )
    return "\n".join(lines) + "\n"


def write_results(directory: str | Path, config: StudyConfig, outcomes: list[dict]) -> list[Path]:
    """runs.csv, table.csv/.md/.json and the two figures; returns the paths written."""
    from .study_figures import distance_histograms, fitness_graphs

    d = Path(directory)
    rows = summarize(outcomes, config.condition_names)
    atomic_write(d / "runs.csv", _csv(outcomes, RUN_COLUMNS))
    atomic_write(d / "table.csv", _csv(rows, rows[0].keys()))
    atomic_write(d / "table.md", table_markdown(rows, config.recheck_seconds))
    write_json(d / "table.json", {"evobiped": __version__, "conditions": rows})
    edges = histogram_edges([o["distance"] for o in outcomes])
    histories = {c: [rundir.read_history(run_dir(d, c, k, config) / rundir.HISTORY) for k in range(config.runs)] for c in config.condition_names}
    return [d / "runs.csv", d / "table.csv", d / "table.md", d / "table.json",
            distance_histograms(outcomes, config.condition_names, edges, d / "distances.png"),
            fitness_graphs(histories, d / "fitness_graphs.png", seeds=[config.first_seed + k for k in range(config.runs)])]

