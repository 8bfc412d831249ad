"""An evolutionary run: config, run directory, checkpoints, resume.

Run directory (every file written atomically)::

    config.json            the full resolved RunConfig
    history.csv            one row per generation (see HISTORY_COLUMNS)
    generations/gen_NNNN.json   best genome of each generation (genome-file format)
    best.json              best genome of the run so far
    checkpoint.json        GA state after the last completed generation
    summary.json           written when the run ends: the best walker, its distance and walking direction

``resume`` continues from checkpoint.json and yields exactly the history an
uninterrupted run with the same config produces (wall times aside).
"""

from __future__ import annotations

import contextlib
import csv
import dataclasses
import io
import math
import signal
import threading
import time
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import numpy as np

from .. import __version__
from ..episode import EpisodeConfig
from ..errors import ConfigError, UserError
from ..fileio import atomic_write, read_json, write_json
from ..genome_file import load_genome, save_genome
from .evaluate import BACKENDS, Evaluator, make_evaluator
from .cma import CMAES, CMAConfig
from .ga import GA, GAConfig

#: optimizer name -> class; each has the GA's ask/tell/ranking/next_generation/carried/state_dict interface
OPTIMIZERS = {"ga": GA, "cma": CMAES}

HISTORY_COLUMNS = ("generation", "best", "mean", "median", "worst", "evaluations", "falls", "unstable", "wall_seconds")


@dataclass(frozen=True, kw_only=True)
class RunConfig:
    """Everything that defines a run; saved as config.json."""

    episode: EpisodeConfig = field(default_factory=EpisodeConfig)
    #: "ga" (Reil & Husbands' GA, the default) or "cma" (CMA-ES)
    optimizer: str = "ga"
    ga: GAConfig = field(default_factory=GAConfig)
    cma: CMAConfig = field(default_factory=CMAConfig)
    generations: int = 120
    seed: int = 0
    backend: str = "process"
    workers: int | None = None
    address: str | None = None
    #: genome file or run directory whose best genome seeds the population (clones)
    initial: str | None = None
    #: names of gene blocks kept fixed (e.g. CPG weights when evolving only sensor weights)
    frozen_blocks: tuple[str, ...] = ()

    def __post_init__(self):
        if not (isinstance(self.generations, int) and self.generations >= 1):
            raise ConfigError(f"generations must be an integer >= 1, got {self.generations!r}")
        if not isinstance(self.seed, int) or isinstance(self.seed, bool) or self.seed < 0:
            raise ConfigError(f"seed must be an integer >= 0, got {self.seed!r}")
        if self.optimizer not in OPTIMIZERS:
            raise ConfigError(f"unknown optimizer {self.optimizer!r} (choose from {', '.join(OPTIMIZERS)})")
        if self.backend not in BACKENDS:
            raise ConfigError(f"unknown backend {self.backend!r} (choose from {', '.join(BACKENDS)})")
        if self.workers is not None and not (isinstance(self.workers, int) and self.workers >= 1):
            raise ConfigError(f"workers must be an integer >= 1, got {self.workers!r}")

    def to_dict(self) -> dict:
        d = dataclasses.asdict(self)
        d["frozen_blocks"] = list(self.frozen_blocks)
        return d

    @classmethod
    def from_dict(cls, d: dict, *, where: str = "config") -> "RunConfig":
        if not isinstance(d, dict):
            raise ConfigError(f"{where}: expected a table of settings")
        d = dict(d)
        try:
            episode = EpisodeConfig(**_table(d.pop("episode", {}), f"{where} [episode]"))
            ga = GAConfig(**_table(d.pop("ga", {}), f"{where} [ga]"))
            cma = CMAConfig(**_table(d.pop("cma", {}), f"{where} [cma]"))
            if "frozen_blocks" in d:
                d["frozen_blocks"] = tuple(d["frozen_blocks"])
            return cls(episode=episode, ga=ga, cma=cma, **d)
        except TypeError as exc:
            raise ConfigError(f"{where}: {_type_error(exc)}") from None


def _table(v: Any, where: str) -> dict:
    if not isinstance(v, dict):
        raise ConfigError(f"{where} must be a table")
    return v


def _type_error(exc: TypeError) -> str:
    msg = str(exc)
    if "unexpected keyword argument" in msg:
        return "unknown setting " + msg.split("argument", 1)[1].strip()
    return msg


def load_toml(path: str | Path) -> dict:
    path = Path(path)
    if not path.is_file():
        raise UserError(f"config file not found: {path}")
    try:
        return tomllib.loads(path.read_text())
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise ConfigError(f"config file {path} is not valid TOML ({exc})") from None


@dataclass
class GenerationStats:
    """One row of history.csv plus what a progress display needs."""

    generation: int
    best: float
    mean: float
    median: float
    worst: float
    evaluations: int
    falls: int
    unstable: int
    wall_seconds: float
    best_fell: bool = False
    evals_per_second: float = 0.0
    generations_total: int = 0

    def row(self) -> list:
        return [getattr(self, c) for c in HISTORY_COLUMNS]


class Run:
    """A run directory and the GA that lives in it."""

    def __init__(self, directory: Path, config: RunConfig, ga: GA, history: list[list], best: dict | None, wall: float):
        self.dir, self.config, self.ga = directory, config, ga
        self.history, self.best, self.wall = history, best, wall
        #: fell / unstable / end_time of the current population (for the generation files)
        self._outcome: dict[str, np.ndarray] = {}

    # ---- creating and resuming
    @classmethod
    def create(cls, directory: str | Path, config: RunConfig) -> "Run":
        """Validate everything first; only then create the (new or empty) directory."""
        directory = Path(directory)
        if directory.exists() and not directory.is_dir():
            raise UserError(f"run directory {directory} exists and is a file; give another --out")
        if directory.exists() and any(directory.iterdir()):
            raise UserError(f"run directory {directory} exists and is not empty (use --resume {directory} or another --out)")
        ga = make_ga(config)
        directory.mkdir(parents=True, exist_ok=True)
        (directory / "generations").mkdir(exist_ok=True)
        write_json(directory / "config.json", {"evobiped": __version__, **config.to_dict()})
        run = cls(directory, config, ga, [], None, 0.0)
        run._write_history()
        return run

    @classmethod
    def resume(cls, directory: str | Path) -> "Run":
        directory = Path(directory)
        if not directory.is_dir():
            raise UserError(f"run directory not found: {directory}")
        cfg = read_json(directory / "config.json", what="run config")
        cfg.pop("evobiped", None)
        config = RunConfig.from_dict(cfg, where=str(directory / "config.json"))
        ga = make_ga(config)
        ck = read_json(directory / "checkpoint.json", what="checkpoint") if (directory / "checkpoint.json").exists() else None
        if ck is None:
            return cls(directory, config, ga, [], None, 0.0)
        try:
            ga.load_state_dict(ck["ga"])
            history, best, wall = ck["history"], ck["best"], float(ck["wall_seconds"])
        except (KeyError, TypeError, ValueError) as exc:
            raise UserError(f"checkpoint {directory / 'checkpoint.json'} is malformed ({exc})") from None
        if len(history) != ga.generation:
            raise UserError(f"checkpoint {directory / 'checkpoint.json'} is inconsistent (history has {len(history)} rows for generation {ga.generation})")
        run = cls(directory, config, ga, history, best, wall)
        run._discard_uncheckpointed()
        run._outcome = {k: np.array(v, dtype=float if k == "end_time" else bool) for k, v in ck.get("outcome", {}).items()}
        return run

    def _discard_uncheckpointed(self) -> None:
        """Undo files of a generation that was interrupted before its checkpoint."""
        for f in (self.dir / "generations").glob("gen_*.json"):
            if int(f.stem[4:]) >= self.ga.generation:
                f.unlink()
        if self.best is not None:
            src = self.dir / "generations" / f"gen_{self.best['generation']:04d}.json"
            best = self.dir / "best.json"
            if src.is_file() and (not best.is_file() or best.read_text() != src.read_text()):
                atomic_write(best, src.read_text())

    @property
    def done(self) -> bool:
        return self.ga.generation >= self.config.generations

    # ---- the loop
    def evolve(self, evaluator: Evaluator, on_generation: Callable[[GenerationStats], None] | None = None) -> dict:
        """Run the remaining generations; checkpoint after each.  Returns the summary."""
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
        """Evaluate the unknown individuals of this generation and record it."""
        ga = self.ga
        pop, unknown = ga.ask()
        ev = evaluator.evaluate(pop[unknown], key=(self.config.seed, ga.generation))
        ga.tell(ev.fitness)
        P = len(pop)
        for key, vals, default in (("fell", ev.fell, False), ("unstable", ev.unstable, False), ("end_time", ev.end_time, np.nan)):
            prev = self._outcome.get(key)
            arr = np.full(P, default, dtype=np.asarray(vals).dtype) if prev is None else prev.copy()
            arr[unknown] = vals
            self._outcome[key] = arr
        f = ga.fitness
        b = int(ga.ranking()[0])
        g = ga.generation
        stats = GenerationStats(
            generation=g,
            best=float(f[b]),
            mean=float(f.mean()),
            median=float(np.median(f)),
            worst=float(f.min()),
            evaluations=int(unknown.sum()),
            falls=int(self._outcome["fell"].sum()),
            unstable=int(self._outcome["unstable"].sum()),
            wall_seconds=0.0,
            best_fell=bool(self._outcome["fell"][b]),
            generations_total=self.config.generations,
        )
        meta = dict(fitness=float(f[b]), fell=bool(self._outcome["fell"][b]), end_time=float(self._outcome["end_time"][b]), seed=self.config.seed, generation=g)
        save_genome(self.dir / "generations" / f"gen_{g:04d}.json", pop[b], self.config.episode, **meta)
        if self.best is None or meta["fitness"] > self.best["fitness"]:
            self.best = meta
            save_genome(self.dir / "best.json", pop[b], self.config.episode, **meta)
        self.history.append(stats.row())
        # individuals the optimizer carries over keep their outcome; the others' are filled in next generation
        ga.next_generation()
        carried = ga.carried()
        for key, arr in self._outcome.items():
            new = np.zeros(len(carried), dtype=arr.dtype)
            new[carried >= 0] = arr[carried[carried >= 0]]
            self._outcome[key] = new
        return stats

    # ---- files
    def checkpoint(self) -> None:
        """GA state + history, then history.csv; each file atomic, and Ctrl-C waits until both are written."""
        outcome = {k: v.tolist() for k, v in self._outcome.items()}
        with _sigint_deferred():
            write_json(
                self.dir / "checkpoint.json",
                {"ga": self.ga.state_dict(), "history": self.history, "best": self.best, "wall_seconds": self.wall, "outcome": outcome},
            )
            self._write_history()

    def _write_history(self) -> None:
        buf = io.StringIO()
        w = csv.writer(buf, lineterminator="\n")
        w.writerow(HISTORY_COLUMNS)
        w.writerows(self.history)
        atomic_write(self.dir / "history.csv", buf.getvalue())

    def _best_walk(self) -> dict | None:
        """Distance and walking direction of the best walker, re-simulated on the nominal episode
        (``EpisodeResult.walk``; the fitness of a perturbed run aggregates other presentations)."""
        if self.best is None or not (self.dir / "best.json").is_file():
            return None
        genome, cfg, _ = load_genome(self.dir / "best.json")
        return cfg.nominal().build().run(genome).walk()

    def finish(self) -> dict:
        summary = {
            "evobiped": __version__,
            "generations": self.ga.generation,
            "best": self.best,
            "wall_seconds": round(self.wall, 3),
            "evaluations": int(sum(r[HISTORY_COLUMNS.index("evaluations")] for r in self.history)),
            "stable": self.best is not None and not self.best["fell"],
            "best_walk": self._best_walk(),
        }
        write_json(self.dir / "summary.json", summary)
        return summary


@contextlib.contextmanager
def _sigint_deferred():
    """Hold Ctrl-C back for the duration and raise it right after (main thread only).

    A Python-level handler, not a signal mask: the signal may be delivered to
    any thread (Rerun's, for one), but Python handlers always run in the main thread.
    """
    if threading.current_thread() is not threading.main_thread() or signal.getsignal(signal.SIGINT) is not signal.default_int_handler:
        yield  # another thread, or a process that ignores or handles Ctrl-C itself (pool workers)
        return
    caught = []
    old = signal.signal(signal.SIGINT, lambda signum, frame: caught.append(signum))
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, old)
    if caught:
        raise KeyboardInterrupt


def make_ga(config: RunConfig):
    """Build the optimizer (GA or CMA-ES; the episode too, to learn the genome layout): fails before any file is written."""
    episode = config.episode.build()
    layout = episode.controller.layout
    initial = None
    if config.initial:
        initial = initial_genome(config.initial, config.episode, layout)
    mutable = None
    if config.frozen_blocks:
        slices = layout.slices()
        unknown = [b for b in config.frozen_blocks if b not in slices]
        if unknown:
            raise ConfigError(f"frozen_blocks {unknown} are not gene blocks of {config.episode.controller} (have {list(slices)})")
        mutable = np.ones(layout.size, bool)
        for b in config.frozen_blocks:
            mutable[slices[b]] = False
    if config.optimizer == "cma":
        return CMAES(layout, config.cma, seed=config.seed, initial=initial, mutable=mutable)
    return GA(layout, config.ga, seed=config.seed, initial=initial, mutable=mutable)


def initial_genome(source: str, episode: EpisodeConfig, layout) -> np.ndarray:
    """The genome that seeds a run: a genome file or a run directory's best.json.

    A genome of a walking run seeds a run with extra input weights (steering):
    the missing trailing genes are filled with zeros (no influence).
    """
    path = Path(source)
    path = path / "best.json" if path.is_dir() else path
    genome, cfg, _ = load_genome(path)
    if cfg.body != episode.body or cfg.controller != episode.controller:
        raise UserError(f"{path} is a {cfg.body}/{cfg.controller} genome; this run needs {episode.body}/{episode.controller}")
    if len(genome) < layout.size and cfg.controller_options == {k: v for k, v in episode.controller_options.items() if k != "inputs"}:
        genome = np.concatenate([genome, np.zeros(layout.size - len(genome))])
    return layout.validate(genome, what=f"genome in {path}")


def eta_seconds(stats: GenerationStats, history: list[list]) -> float:
    done = len(history)
    if not done:
        return math.nan
    walls = [r[HISTORY_COLUMNS.index("wall_seconds")] for r in history]
    return float(np.mean(walls[-5:])) * (stats.generations_total - done)
