"""What the commands share: argument types, one-line refusals, the worker check, the run settings that a
preset, a settings file and flags give, and the one-line summary of a walk.

The ``evobiped`` command (:mod:`evobiped.cli`) and the experiments' own subcommands
(``evobiped/experiments/<name>/command.py``) build their parsers and configs with these.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys

import numpy as np

from .core.errors import UserError
from .tasks.sound import with_sources


def finite_float(text: str) -> float:
    """A finite number (argparse type): ``nan``, ``inf`` and text are refused."""
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not np.isfinite(v):
        raise argparse.ArgumentTypeError(f"must be a finite number, got {text}")
    return v


def positive_float(text: str) -> float:
    v = finite_float(text)
    if v <= 0:
        raise argparse.ArgumentTypeError(f"must be > 0, got {text}")
    return v


def nonnegative_float(text: str) -> float:
    v = finite_float(text)
    if v < 0:
        raise argparse.ArgumentTypeError(f"must be >= 0, got {text}")
    return v


def within(low: float, high: float, unit: str = "", why: str = ""):
    """An argparse type: a finite number from ``low`` to ``high`` (in ``unit``); the refusal states the bound and
    ``why`` it is the bound (e.g. ``"a step cycle"``)."""
    def parse(text: str) -> float:
        v = finite_float(text)
        if not low <= v <= high:
            u = f" {unit}" if unit else ""
            raise argparse.ArgumentTypeError(f"must be from {low:g} to {high:g}{u}" + (f" ({why})" if why else "")
                                             + f", got {text}")
        return v

    parse.__name__ = "number"  # argparse names a type by it in "invalid number value"
    return parse


def _whole(text: str) -> int:
    """A whole number, written as one (``12``) or as an exact float (``1e3``)."""
    try:
        return int(text)
    except ValueError:
        pass
    try:
        v = float(text)
    except ValueError:
        v = float("nan")
    if not (np.isfinite(v) and v == int(v)):
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number")
    return int(v)


def positive_int(text: str) -> int:
    v = _whole(text)
    if v <= 0:
        raise argparse.ArgumentTypeError(f"must be > 0, got {text}")
    return v


#: the largest seed a flag takes (NumPy's generators take any whole number >= 0; 2^63 - 1 fits every integer type)
MAX_SEED = 2**63 - 1


def seed(text: str) -> int:
    """A random seed (argparse type): a whole number from 0 to :data:`MAX_SEED`."""
    v = _whole(text)
    if not 0 <= v <= MAX_SEED:
        raise argparse.ArgumentTypeError(f"must be a whole number from 0 to 2^63 - 1 (a seed), got {text}")
    return v


def count(high: int, what: str):
    """An argparse type: a whole number from 1 to ``high``, the bound ``what`` (e.g. ``"the memory of the table"``)."""
    def parse(text: str) -> int:
        v = _whole(text)
        if not 1 <= v <= high:
            raise argparse.ArgumentTypeError(f"must be a whole number from 1 to {high:,} ({what}), got {text}")
        return v

    parse.__name__ = "count"
    return parse


def choices_text(kind: str) -> str:
    """The valid names of a name-valued option, for its help text: ``choices_text("body")`` -> ``"reil, taga"``."""
    if kind == "body":
        from .bodies import BODIES as reg
    elif kind == "controller":
        from .controllers import CONTROLLERS as reg
    elif kind == "task":
        from .tasks import TASKS as reg
    elif kind == "backend":
        from .evaluation import BACKENDS as reg
    elif kind == "preset":
        from .files.presets import names as preset_names

        reg = preset_names()
    else:
        raise ValueError(kind)
    return ", ".join(reg)


def add_stored_walker(p, dest: str = "source", metavar: str = "SOURCE", *, also: str = "", nargs=None,
                      generation: str = "the best of generation N of a run directory") -> None:
    """A command's stored walker: the positional ``dest`` (a run directory, its best.json, or a genome JSON file; its
    help ends with ``also``) and ``--generation N`` (help ``generation``), which
    :func:`evobiped.record.source.resolve` reads."""
    p.add_argument(dest, metavar=metavar, nargs=nargs, help="a run directory (its best.json) or a genome JSON "
                                                            f"file{also}")
    p.add_argument("--generation", type=int, metavar="N", help=generation)
    add_allow_unfinished(p)


def add_allow_unfinished(p) -> None:
    """``--allow-unfinished``: read a run directory that an evolve is still writing (refused without it)."""
    p.add_argument("--allow-unfinished", action="store_true", help="read a run that an evolve is still writing (its "
                   "generations so far; said on stderr and recorded in what is written); without it such a run is "
                   "refused")


def unfinished_note(source) -> None:
    """Say on stderr which generation of a run being written ``source`` (:class:`~evobiped.record.source.Source`) was
    read, if it was."""
    if source.unfinished is not None:
        u = source.unfinished
        note(f"{source.run_dir or source.genome_path.parent} is being written by process {u['writer']}: read as of its "
             f"first {u['generations']} generations")


def add_source_flag(p) -> None:
    p.add_argument("--source", dest="sources", nargs=2, type=finite_float, action="append", metavar=("X", "Y"),
                   help="a sound source at (X, Y) m for the steer task, or for a commanded walker (its commands then "
                        "come from its ears), one presentation each; repeat it for several (default: the config's, or "
                        "the paper's (10, 3) and (10, -3))")


def number_list(flag: str, text: str | None, bound: float | None = None, unit: str = "") -> list[float] | None:
    """A comma-separated list of finite numbers (None: not given), each within +-``bound`` (in ``unit``) if given;
    one line, exit 2, for anything else."""
    if text is None:
        return None
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        values = []
    if not values or not all(np.isfinite(v) for v in values):
        refuse(flag, f"expected finite numbers, comma-separated, got {text!r}")
    if bound is not None and not all(abs(v) <= bound for v in values):
        refuse(flag, f"each value must be within -{bound:g} to {bound:g}{' ' + unit if unit else ''}, got {text!r}")
    return values


#: the fastest commanded speed a flag takes, m/s (no walker here walks 1 m/s; a sprinter runs 10)
MAX_SPEED = 10.0
#: the fastest commanded turning rate a flag takes, deg/s (two turns a second)
MAX_TURNING = 720.0


def check_output_file(flag: str, path: str) -> None:
    """A file a command will write at ``path`` (given with ``flag``), checked before any work: its folder must exist
    and ``path`` must not be a folder; one line, exit 2, otherwise."""
    from pathlib import Path

    where = Path(path)
    folder = where.parent
    if where.is_dir():
        refuse(flag, f"{where} is a directory; name a file in it")
    if not folder.is_dir():
        refuse(flag, f"the folder {folder} does not exist" if not folder.exists() else f"{folder} is not a folder")


def note(line: str) -> None:
    """A command's note on standard error (``evobiped: note: ...``): what it found and did about it."""
    print(f"evobiped: note: {line}", file=sys.stderr)


def refuse(flags: str, why: str) -> None:
    """A flag that does not apply here: one line, exit 2."""
    raise UserError(f"{flags}: {why}")


def check_workers(backend: str, workers: int | None, address: str | None) -> None:
    """--workers and --address must apply to the backend; more local workers than this machine runs
    (:func:`~evobiped.evaluation.worker_limit`) are refused, more than its cores earn a warning line."""
    import os

    if address is not None and backend != "ray":
        refuse("--address", "only a Ray backend connects to a cluster (use --backend ray; the backend here is "
                            f"{backend})")
    if workers is not None and backend == "serial":
        refuse("--workers",
               "the serial backend runs in this process (use --backend process, thread or ray for workers)")
    from .evaluation import check_worker_count

    check_worker_count(backend, workers, address, name="--workers")
    cores = os.cpu_count() or 1
    if workers is not None and workers > cores and address is None:
        print(f"evobiped: warning: --workers {workers} on {cores} cores: the extra workers share cores and do not run "
              "faster", file=sys.stderr)


def walk_line(walk: dict) -> str:
    """'walked 38.7 m, -165 deg from the initial facing: backwards' from ``EpisodeResult.walk()``."""
    from .tasks.walk import direction_words

    heading = walk["heading_deg"] if walk["heading_deg"] is not None else float("nan")
    return f"walked {walk['distance']:.2f} m, {direction_words(heading)}"


#: the run-settings flags :func:`run_config` takes (evolve's; not --out, --resume, --rerun, --quiet)
RUN_FLAGS = ("preset", "config", "optimizer", "body", "controller", "task", "sources", "population", "generations",
             "episode_seconds", "cyclic", "seed", "backend", "workers", "address", "initial", "freeze",
             "env")


def run_config(*, preset: str | None = None, config: str | None = None, optimizer: str | None = None,
               body: str | None = None,
               controller: str | None = None, task: str | None = None, sources=None, population: int | None = None,
               generations: int | None = None, episode_seconds: float | None = None, cyclic: bool | None = None,
               seed: int | None = None, backend: str | None = None, workers: int | None = None,
               address: str | None = None, initial: str | None = None, freeze: str | None = None,
               env: str | None = None):
    """RunConfig from a preset, a settings file and the flags' values (None: not given; flags win)."""
    from .episode import EpisodeConfig
    from .run.run_config import RunConfig, check_tables
    from .core.fileio import read_toml
    from .tasks import TASKS

    from .files.presets import merge, path, split_declarations

    d, declared = split_declarations(preset, read_toml(path(preset))) if preset else ({}, {})
    if config:
        d = merge(d, read_toml(config))
    where = config or (f"preset {preset}" if preset else "")
    check_tables(d, where)  # before the flags go into its tables
    ep = dict(d.get("episode", {})) if isinstance(d.get("episode", {}), dict) else d.get("episode")
    for key, value in (("body", body), ("controller", controller), ("task", task), ("seconds", episode_seconds),
                       ("env", env)):
        if value is not None:
            ep[key] = value
    task_name = ep.get("task", EpisodeConfig.task) if isinstance(ep, dict) else None
    if cyclic and task_name in TASKS:  # the task's cyclic criterion (an unknown task is refused below)
        ep["task_options"] = {**ep.get("task_options", {}), **TASKS[task_name].criterion("cyclic", "--cyclic")}
    if population is not None:  # the population of every optimizer; only the chosen one's refuses a value
        from .core.errors import ConfigError
        from .core.options import check_value
        from .optimizers import OPTIMIZERS

        chosen = optimizer or d.get("optimizer", "ga")
        for name, cls in OPTIMIZERS.items():
            key, value = cls.population_setting(population)
            try:
                check_value(cls.Options, key, value, "--population")
            except ConfigError:
                if name == chosen:
                    raise
                continue
            d[cls.table] = {**(d.get(cls.table) if isinstance(d.get(cls.table), dict) else {}), key: value}
    for key, value in (("optimizer", optimizer), ("generations", generations), ("seed", seed), ("backend", backend),
                       ("workers", workers), ("address", address), ("initial", initial)):
        if value is not None:
            d[key] = value
    if freeze:
        d["frozen_blocks"] = [b.strip() for b in freeze.split(",") if b.strip()]
    built = RunConfig.from_dict({**d, "episode": ep}, where=where)
    if declared.get("needs_start") and not built.initial:
        refuse(f"--preset {preset}", "tunes a given genome: name it with --from GENOME_OR_RUN (see `evobiped presets`)")
    return dataclasses.replace(built, episode=with_sources(built.episode, sources))
