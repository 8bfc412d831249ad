"""The compare use case: run configurations for N seeds each at one budget of evaluated episodes, re-evaluate
every run's policy on fresh noise, and compare them (success rates, the measure, effect sizes, tests).

A comparison directory::

    comparison.json                 the configurations (their settings), seeds, budget, the test and its fingerprint
    runs/<name>/seed_NNN/           an ordinary run directory (``evobiped evolve --resume`` continues it)
    retests/<name>_seed_NNN.json    that run's checkpoints re-evaluated on fresh noise
    results.json results.md         the comparison (:mod:`.compare_report`)
    success.png                     success rate against episodes evaluated, Wilson 95 % bands

Each run is its configuration with ``seed``, ``budget`` (the run stops at the first generation boundary where
its evaluated episodes reach it; ``generations`` becomes the budget, a bound it cannot reach first) and the
serial backend: one process per run, at most ``workers`` at once.  Its policy at C checkpoints (the first
generation whose evaluated episodes reach budget x i / C, i = 1..C; the last is the run's last generation)
is the genome of that generation's file: for ES the evaluation walker (theta, the mean), for the GA and
CMA-ES the best of that generation.  Each is re-evaluated on K fresh presentations
(:mod:`evobiped.analysis.retest`), the same for every configuration's run of one seed.  Nothing depends on
which process ran what or when: the same seeds give the same results.json and results.md, bit for bit.
"""

from __future__ import annotations

import dataclasses
import hashlib
import os
from concurrent.futures import as_completed
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from .. import __version__
from ..analysis.retest import Success, check_measure, check_walker_test, fresh_noise, parse_success, retest
from ..core.errors import UserError
from ..core.fileio import json_text, read_json, write_json
from ..run.fingerprint import settings
from ..run.run_config import RunConfig, check_run, episodes_per_genome, population_of
from ..files import rundir
from ..files.genome_file import load_genome
from .evolving import evolve

FILE, RUNS, RETESTS = "comparison.json", "runs", "retests"


@dataclass(frozen=True, kw_only=True)
class Comparison:
    """What a comparison computes: named configurations, seeds, the budget and the test of the final policies."""

    names: tuple[str, ...]
    configs: tuple[RunConfig, ...]
    seeds: tuple[int, ...]
    budget: int
    trials: int = 8
    checkpoints: int = 4
    noise: dict | None = None
    measure: str = "fitness"
    success: str = "walker"

    def check(self) -> None:
        """UserError (one line) for a comparison that cannot run; nothing is written."""
        if not self.configs or len(self.names) != len(self.configs):
            raise UserError("compare: give at least one configuration (a preset name or a settings file)")
        if not self.seeds:
            raise UserError("--seeds: must be >= 1")
        tasks = {c.episode.task for c in self.configs}
        if len(tasks) > 1:
            which = ", ".join(f"{n}: {c.episode.task}" for n, c in zip(self.names, self.configs))
            raise UserError(f"the configurations are of different tasks ({which}); "
                            "compare configurations of one task")
        for name, c in zip(self.names, self.configs):
            check_run(c)
            c.episode.check()
            first = population_of(c) * episodes_per_genome(c)
            if self.budget < first:
                raise UserError(f"--budget {self.budget}: below one generation of {name} ({population_of(c)} genomes x "
                                f"{episodes_per_genome(c)} episodes each = {first} episodes)")
        check_measure(self.measure, self.terms)
        success = self.criterion()
        for c in self.configs:
            check_walker_test(c.episode, success)
        fresh_noise(self.noise, self.trials)

    @property
    def terms(self) -> tuple[str, ...]:
        return tuple(self.configs[0].episode.parts()[2].term_names)

    def criterion(self) -> Success:
        return parse_success(self.success, self.terms)

    def run_config(self, i: int, seed: int) -> RunConfig:
        """Configuration ``i``'s run of ``seed``."""
        return dataclasses.replace(self.configs[i], seed=int(seed), budget=int(self.budget),
                                   generations=min(int(self.budget), 10**6),
                                   backend="serial", workers=None, address=None)

    def to_dict(self) -> dict:
        d = {"configurations": [{"name": n, "config": settings(c)} for n, c in zip(self.names, self.configs)],
             "seeds": list(self.seeds), "budget": self.budget, "trials": self.trials, "checkpoints": self.checkpoints,
             "noise": self.noise, "measure": self.measure, "success": self.success}
        return {**d, "fingerprint": hashlib.sha256(json_text(d).encode()).hexdigest()}

    @classmethod
    def from_dict(cls, d: dict, where: str) -> "Comparison":
        try:
            cs = d["configurations"]
            return cls(names=tuple(c["name"] for c in cs),
                       configs=tuple(RunConfig.from_dict(c["config"], where=where) for c in cs),
                       seeds=tuple(int(s) for s in d["seeds"]), budget=int(d["budget"]), trials=int(d["trials"]),
                       checkpoints=int(d["checkpoints"]), noise=d["noise"], measure=str(d["measure"]),
                       success=str(d["success"]))
        except (KeyError, TypeError, ValueError) as exc:
            raise UserError(f"{where} is not a comparison ({type(exc).__name__}: {exc})") from None

    def jobs(self, directory: Path) -> list[tuple]:
        """One job per run, configuration by configuration, seed by seed: :func:`run_and_retest`'s arguments."""
        test = {"trials": self.trials, "checkpoints": self.checkpoints, "noise": self.noise, "measure": self.measure,
                "success": self.success, "budget": self.budget}
        return [(str(run_path(directory, n, s)), self.run_config(i, s).to_dict(), str(retest_path(directory, n, s)), n,
                 test)
                for i, n in enumerate(self.names) for s in self.seeds]


def run_path(directory: Path, name: str, seed: int) -> Path:
    return directory / RUNS / name / f"seed_{seed:03d}"


def retest_path(directory: Path, name: str, seed: int) -> Path:
    return directory / RETESTS / f"{name}_seed_{seed:03d}.json"


def open_comparison(comparison: Comparison | None, *, out: str | Path | None = None, resume: str | Path | None = None,
                    given: dict | None = None) -> tuple[Path, Comparison]:
    """A new comparison directory ``out`` for ``comparison``, or the one in ``resume``: its stored comparison, which
    the settings in ``given`` (field -> value, e.g. the configurations named again: ``names`` and ``configs``) must
    not change (one line naming what did).  Everything is checked before anything is written."""
    if resume is not None:
        d = Path(resume)
        if not (d / FILE).is_file():
            raise UserError(f"{d} holds no comparison ({FILE} not found); start one with --out {d}")
        stored = read_json(d / FILE, what="comparison")
        if not isinstance(stored, dict):
            raise UserError(f"{d / FILE} is not a comparison")
        old = Comparison.from_dict(stored, str(d / FILE))
        if old.to_dict()["fingerprint"] != stored.get("fingerprint"):
            raise UserError(f"{d / FILE} was edited (its fingerprint does not match its settings); restore it or start "
                            "a new comparison")
        new = dataclasses.replace(old, **(given or {}))
        if new.to_dict()["fingerprint"] != stored["fingerprint"]:
            changed = [k for k, v in new.to_dict().items() if k != "fingerprint" and stored.get(k) != v]
            raise UserError(f"{d} was made with other {' and '.join(changed)}: a resumed comparison must be the same "
                            f"one (restore them, or compare into another --out)")
        old.check()
        return d, old
    d = Path(out)
    comparison.check()
    if d.exists() and (not d.is_dir() or any(d.iterdir())):
        raise UserError(f"{d} exists and is not empty; give another --out (or --resume {d} to continue the comparison "
                        "in it)")
    d.mkdir(parents=True, exist_ok=True)
    write_json(d / FILE, {"evobiped": __version__, **comparison.to_dict()})
    return d, comparison


def run_and_retest(directory: str, config: dict, retested: str, name: str, test: dict) -> dict:
    """One run (in a worker process): create, resume or leave it as complete; then its checkpoints re-evaluated on
    fresh noise (kept in ``retested``; a run whose file exists is done)."""
    if Path(retested).is_file():
        return read_json(retested, what="retest")
    cfg = RunConfig.from_dict(config)
    d = Path(directory)
    runs = []  # the run, whose record (the checkpoint's rows) grows as it evolves
    evolve(d if (d / rundir.CONFIG).is_file() else cfg, out=d, on_opened=runs.append)
    history = [int(x) for x in rundir.column(runs[0].record.history, "evaluations")]
    per = episodes_per_genome(cfg)
    spent = [per * sum(history[:g + 1]) for g in range(len(history))]
    noise = fresh_noise(test["noise"], test["trials"])
    success = parse_success(test["success"], tuple(cfg.episode.parts()[2].term_names))
    points, done = [], {}
    for i in range(1, test["checkpoints"] + 1):
        target = test["budget"] * i / test["checkpoints"]
        g = next((g for g, e in enumerate(spent) if e >= target), len(spent) - 1)
        if g not in done:
            genome, episode, _ = load_genome(rundir.generation_file(d, g))
            done[g] = retest(episode, genome, seed=cfg.seed, noise=noise, measure=test["measure"], success=success)
        points.append({"target": target, "generation": g, "episodes": spent[g], **done[g]})
    out = {"name": name, "seed": cfg.seed, "generations": len(history), "episodes": spent[-1], "checkpoints": points}
    Path(retested).parent.mkdir(parents=True, exist_ok=True)
    write_json(Path(retested), out)
    return out


def compare_configurations(comparison: Comparison | None = None, *, out: str | Path | None = None,
                           resume: str | Path | None = None, given: dict | None = None, workers: int | None = None,
                           say: Callable[[str], None] | None = None,
                           on_run: Callable[[int, int, dict | None], None] | None = None) -> dict:
    """The whole use case: open (or resume) the comparison, run what is left (``workers`` runs at once, default one per
    core), write results.json, results.md and success.png; returns the results.  ``say(line)``: what it starts;
    ``on_run(done, total, retest)``: before the first run (0, None) and after each."""
    from ..evaluation.pool import spawn_pool, stop_pool
    from .compare_report import write_comparison

    d, c = open_comparison(comparison, out=out, resume=resume, given=given)
    jobs = c.jobs(d)
    for j in jobs:  # another comparison still running here: one line before any run starts or is read
        if Path(j[0]).is_dir():
            rundir.check_at_rest(Path(j[0]), how="wait for the comparison running there to finish")
    todo = [j for j in jobs if not Path(j[2]).is_file()]
    if say:
        say(f"{len(c.names)} configurations x {len(c.seeds)} seeds at {c.budget} episodes each, "
            f"{len(jobs) - len(todo)} runs already done; each policy re-evaluated on {c.trials} fresh presentations -> "
            f"{d}")
    if on_run:
        on_run(0, len(todo), None)
    if todo:
        pool = spawn_pool(min(workers or os.cpu_count() or 1, len(todo)))
        try:
            futures = [pool.submit(run_and_retest, *j) for j in todo]
            for n, f in enumerate(as_completed(futures), 1):
                result = f.result()
                if on_run:
                    on_run(n, len(todo), result)
        finally:
            stop_pool(pool)
    retests = [read_json(j[2], what="retest") for j in jobs]
    return write_comparison(d, c, retests, say=say)
