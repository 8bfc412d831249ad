"""The ``evobiped`` command: parse, build configs, call the package, print.

Every subcommand is a function ``add_<name>(subparsers)`` that registers its
parser and handler.  A :class:`~evobiped.errors.UserError` (or a bad argument)
becomes one line on stderr and exit status 2.
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import json
import os
import sys

import numpy as np

from . import __version__
from .errors import UserError, exit_status, stop_on_signals
from .progress import Progress, hms
from .tasks.steer import with_sources


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # one line, exit 2, no usage dump
        self.exit(2, f"{self.prog}: error: {message}\n")


def positive_float(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not (v > 0 and np.isfinite(v)):
        raise argparse.ArgumentTypeError(f"must be > 0, got {text}")
    return v


def positive_int(text: str) -> int:
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number") from None
    if v <= 0:
        raise argparse.ArgumentTypeError(f"must be > 0, got {text}")
    return v


def choices_text(kind: str) -> str:
    """The valid names of a name-valued option, for its help text: ``choices_text("body")`` -> ``"reil, taga"``."""
    if kind == "body":
        from .bodies import BODIES as reg
    elif kind == "controller":
        from .controllers import CONTROLLERS as reg
    elif kind == "task":
        from .tasks import TASKS as reg
    elif kind == "backend":
        from .evolution.evaluate import BACKENDS as reg
    elif kind == "preset":
        from .presets import names as preset_names

        reg = preset_names()
    else:
        raise ValueError(kind)
    return ", ".join(reg)


def add_source_flag(p) -> None:
    p.add_argument("--source", dest="sources", nargs=2, type=float, action="append", metavar=("X", "Y"),
                   help="a sound source at (X, Y) m for the steer task, one presentation each; repeat it for several "
                        "(default: the config's, or the paper's (10, 3) and (10, -3))")


def refuse(flags: str, why: str) -> None:
    """A flag that does not apply here: one line, exit 2."""
    raise UserError(f"{flags}: {why}")


def check_workers(backend: str, workers: int | None, address: str | None) -> None:
    """--workers and --address must apply to the backend; more local workers than cores earns a warning line."""
    import os

    if address is not None and backend != "ray":
        refuse("--address", f"only a Ray backend connects to a cluster (use --backend ray; the backend here is {backend})")
    if workers is not None and backend == "serial":
        refuse("--workers", "the serial backend runs in this process (use --backend process, thread or ray for workers)")
    cores = os.cpu_count() or 1
    if workers is not None and workers > cores and address is None:
        print(f"evobiped: warning: --workers {workers} on {cores} cores: the extra workers share cores and do not run faster",
              file=sys.stderr)


# ---------------------------------------------------------------- episode
def add_episode(sub) -> None:
    p = sub.add_parser("episode", help="run one episode and print its fitness")
    src = p.add_mutually_exclusive_group()
    src.add_argument("--genome", metavar="FILE", help="genome JSON file (default: a random genome)")
    src.add_argument("--seed", type=int, default=0, help="seed of the random genome (default 0)")
    p.add_argument("--body", help=f"body: {choices_text('body')} (default reil; not with --genome, whose file names it)")
    p.add_argument("--controller", help=f"controller: {choices_text('controller')} (default ctrnn; not with --genome)")
    p.add_argument("--seconds", type=positive_float, help="episode length in s (default 50)")
    add_source_flag(p)
    p.add_argument("--json", action="store_true", help="print machine-readable JSON")
    p.set_defaults(func=run_episode_cmd)


def run_episode_cmd(args) -> int:
    from .episode import EpisodeConfig
    from .genome_file import load_genome

    if args.genome:
        if args.body or args.controller:
            refuse("--body/--controller", "a genome file names its own body and controller; give them without --genome")
        genome, cfg, _ = load_genome(args.genome)
    else:
        cfg = EpisodeConfig(body=args.body or "reil", controller=args.controller or "ctrnn")
        genome = None
    if args.seconds:
        cfg = EpisodeConfig(**{**cfg.__dict__, "seconds": args.seconds})
    cfg = with_sources(cfg, args.sources)
    ep = cfg.build()
    if genome is None:
        genome = ep.controller.layout.sample(np.random.default_rng(args.seed))
    r = ep.run(genome)
    out = {
        "body": cfg.body,
        "controller": cfg.controller,
        "fitness": float(r.fitness[0]),
        "fell": bool(r.fell[0]),
        "unstable": bool(r.unstable[0]),
        "end_time": float(r.end_time[0]),
        **r.walk(),
    }
    targets = ep.task.targets()
    if targets is not None:  # the final distance to each presentation's target (a steering walker's sources)
        rows = r.rows if r.rows is not None else r
        out["sources"] = [{"source": list(map(float, q)), "final_distance": float(np.linalg.norm(rows.end_position[j] - q)),
                           "fell": bool(rows.fell[j]), "end_time": float(rows.end_time[j])}
                          for j, q in enumerate(targets)]
    if args.json:
        print(json.dumps(out))
    else:
        state = f"fell at t = {out['end_time']:.2f} s" if out["fell"] else f"stayed up for {out['end_time']:.1f} s"
        print(f"fitness = {out['fitness']:.3f}; {state}; {walk_line(out)}")
        for s in out.get("sources", []):
            how = f"fell at t = {s['end_time']:.2f} s" if s["fell"] else f"up for {s['end_time']:.1f} s"
            print(f"source ({s['source'][0]:g}, {s['source'][1]:g}) m: final distance {s['final_distance']:.2f} m ({how})")
        if out.get("sources"):
            print(f"median final distance over {len(out['sources'])} source(s): {np.median([s['final_distance'] for s in out['sources']]):.2f} m")
    return 0


def walk_line(walk: dict) -> str:
    """'walked 38.7 m, -165 deg from the initial facing: backwards' from ``EpisodeResult.walk()``."""
    from .tasks.walk import direction_words

    heading = walk["heading_deg"] if walk["heading_deg"] is not None else float("nan")
    return f"walked {walk['distance']:.2f} m, {direction_words(heading)}"


# ---------------------------------------------------------------- evolve
def add_evolve(sub) -> None:
    what = "evolve controllers with Reil & Husbands' GA (the default, with the paper's settings) or CMA-ES (--optimizer cma)"
    p = sub.add_parser("evolve", help=what, description=what + "; --preset picks named settings (`evobiped presets`)")
    p.add_argument("--preset", metavar="NAME", help=f"named settings shipped with evobiped: {choices_text('preset')} "
                   "(`evobiped presets` describes them); --config and flags override it")
    p.add_argument("--config", metavar="FILE.toml", help="settings file; flags given here override it")
    p.add_argument("--optimizer", choices=("ga", "cma"), help="ga (Reil & Husbands' GA, default) or cma (CMA-ES)")
    p.add_argument("--body", help=f"body: {choices_text('body')} (default reil)")
    p.add_argument("--controller", help=f"controller: {choices_text('controller')} (default ctrnn)")
    p.add_argument("--task", help=f"task: {choices_text('task')} (default walk)")
    add_source_flag(p)
    p.add_argument("--population", type=positive_int, help="population size (default: GA 50, CMA-ES 4 + 3 ln genes)")
    p.add_argument("--generations", type=positive_int, help="generations (default 120)")
    p.add_argument("--episode-seconds", type=positive_float, help="episode length in s (default 50)")
    p.add_argument("--cyclic", action="store_true", default=None, help="reward cyclic motor-neuron activity (Sect. III-A): the task's cyclic criterion")
    p.add_argument("--seed", type=int, help="run seed (default 0)")
    p.add_argument("--backend", help=f"backend: {choices_text('backend')} (default process)")
    p.add_argument("--workers", type=positive_int, help="worker processes / threads / Ray actors (default: all cores; "
                   "more than the cores earns a warning; not with the serial backend)")
    p.add_argument("--address", help="Ray cluster address (only with --backend ray; default: start a local Ray)")
    p.add_argument("--from", dest="initial", metavar="RUN_OR_GENOME", help="start from this genome (the GA: a population of its clones; CMA-ES: the initial mean)")
    p.add_argument("--freeze", metavar="BLOCKS", help="gene blocks the optimizer must not change, comma-separated "
                   "(e.g. weights,time_constants,biases: evolve only a CTRNN's input weights)")
    p.add_argument("--out", metavar="DIR", help="run directory (default runs/<body>_<controller>_seed<seed>)")
    p.add_argument("--resume", metavar="DIR", help="continue the run in DIR from its last checkpoint")
    p.add_argument("--rerun", nargs="?", const="spawn", metavar="ADDR",
                   help="also stream fitness per generation to a Rerun viewer: a new one, or the one at ADDR "
                        "(the run directory's evolution.rrd is written either way)")
    p.add_argument("--quiet", action="store_true", help="no progress lines")
    p.set_defaults(func=run_evolve_cmd)


#: evolve's flags that :func:`run_config` takes (the run-settings flags; not --out, --resume, --rerun, --quiet)
RUN_FLAGS = ("preset", "config", "optimizer", "body", "controller", "task", "sources", "population", "generations",
             "episode_seconds", "cyclic", "seed", "backend", "workers", "address", "initial", "freeze")


def run_config(*, preset: str | None = None, config: str | None = None, optimizer: str | None = None, body: str | None = None,
               controller: str | None = None, task: str | None = None, sources=None, population: int | None = None,
               generations: int | None = None, episode_seconds: float | None = None, cyclic: bool | None = None,
               seed: int | None = None, backend: str | None = None, workers: int | None = None, address: str | None = None,
               initial: str | None = None, freeze: str | None = None):
    """RunConfig from a preset, a settings file and the flags' values (None: not given; flags win)."""
    from .episode import EpisodeConfig
    from .evolution.run import RunConfig
    from .fileio import read_toml
    from .tasks import TASKS

    from .presets import merge, path

    d = read_toml(path(preset)) if preset else {}
    if config:
        d = merge(d, read_toml(config))
    ep = dict(d.get("episode", {})) if isinstance(d.get("episode", {}), dict) else d.get("episode")
    ga = dict(d.get("ga", {})) if isinstance(d.get("ga", {}), dict) else d.get("ga")
    for key, value in (("body", body), ("controller", controller), ("task", task), ("seconds", episode_seconds)):
        if value is not None:
            ep[key] = value
    task_name = ep.get("task", EpisodeConfig.task) if isinstance(ep, dict) else None
    if cyclic and task_name in TASKS:  # the task's cyclic criterion (an unknown task is refused below)
        ep["task_options"] = {**ep.get("task_options", {}), **TASKS[task_name].criterion("cyclic", "--cyclic")}
    if population is not None:  # the population of either optimizer
        ga["population"] = population
        d["cma"] = {**(d.get("cma") if isinstance(d.get("cma"), dict) else {}), "population": population}
    for key, value in (("optimizer", optimizer), ("generations", generations), ("seed", seed), ("backend", backend),
                       ("workers", workers), ("address", address), ("initial", initial)):
        if value is not None:
            d[key] = value
    if freeze:
        d["frozen_blocks"] = [b.strip() for b in freeze.split(",") if b.strip()]
    where = config or (f"preset {preset}" if preset else "")
    built = RunConfig.from_dict({**d, "episode": ep, "ga": ga}, where=where)
    return dataclasses.replace(built, episode=with_sources(built.episode, sources))


def default_run_dir(config) -> str:
    from pathlib import Path

    base = Path("runs") / f"{config.episode.body}_{config.episode.controller}_seed{config.seed}"
    path, i = base, 1
    while path.exists():
        i += 1
        path = base.with_name(f"{base.name}_{i}")
    return str(path)


def run_evolve_cmd(args) -> int:
    from .evolution.evaluate import make_evaluator
    from .evolution.run import Run

    if args.rerun is not None:  # before anything is written
        from .record.viewer import connect_url, require_display, require_viewer

        require_display() if args.rerun == "spawn" else require_viewer(connect_url(args.rerun))
    on_retry = lambda n, limit: print(f"evobiped: a worker died; evaluating its batch again (retry {n} of {limit})",  # noqa: E731
                                      file=sys.stderr, flush=True)
    if args.resume:
        if any(getattr(args, f) is not None for f in (*RUN_FLAGS, "out") if f not in ("backend", "workers", "address")):
            raise UserError("--resume takes the run's saved config: give only --workers/--backend/--address with it")
        run = Run.resume(args.resume)  # locks the directory and repairs its derived files
        try:
            for repair in run.repairs:
                print(f"evobiped: repaired: {repair}", file=sys.stderr)
            if run.environment_differences:
                print(f"evobiped: note: this run started in another numerical environment ({'; '.join(run.environment_differences)}):"
                      " from here on it is not bit-identical to an uninterrupted run there", file=sys.stderr)
            if run.done:
                print(f"run {args.resume} is already complete ({run.ga.generation} generations)")
                run.close()
                return 0
            backend = args.backend or run.config.backend
            workers = args.workers or run.config.workers
            address = args.address or run.config.address
            check_workers(backend, workers, address)
            evaluator = make_evaluator(run.config.episode, backend, workers, address, on_retry=on_retry)
        except BaseException:
            run.close()
            raise
    else:
        config = run_config(**{f: getattr(args, f) for f in RUN_FLAGS})
        backend, workers, address = config.backend, config.workers, config.address
        check_workers(backend, workers, address)
        out = args.out or default_run_dir(config)
        evaluator = make_evaluator(config.episode, backend, workers, address, on_retry=on_retry)  # fails before any file is written
        try:
            run = Run.create(out, config)
        except BaseException:
            evaluator.close()
            raise
    with run:
        return _evolve(run, evaluator, backend, args)


def _evolve(run, evaluator, backend: str, args) -> int:
    """The generations left, with progress lines and an optional live viewer; the summary line."""
    from .progress import time_left
    from .rundir import HISTORY

    say = (lambda *a: None) if args.quiet else (lambda msg: print(msg, file=sys.stderr, flush=True))
    c = run.config
    population = len(run.ga.ask()[0])
    say(f"evolving {c.episode.body}/{c.episode.controller} on '{c.episode.task}' with {c.optimizer}, population {population}, "
        f"{c.generations} generations, {c.episode.seconds:g} s episodes, seed {c.seed}, backend {backend} -> {run.dir}")
    with evaluator, contextlib.ExitStack() as stack:
        log = stack.enter_context(_viewer_log(run, args.rerun)) if args.rerun is not None else None

        line = Progress("evolve", c.generations, "generations", quiet=args.quiet)
        walls, clocks = [], []  # per generation of this session: wall s, longest episode s

        def progress(s):
            if log is not None:
                log.log_generation(s.generation, best=s.best, mean=s.mean, worst=s.worst, median=s.median,
                                   evaluations=s.evaluations, falls=s.falls, unstable=s.unstable, wall_seconds=s.wall_seconds)
            walls.append(s.wall_seconds)
            clocks.append(s.longest_seconds)
            # episodes lengthen as walkers learn to stay up: the time left if every generation's longest episode runs
            # its T (the run's aim), and if they stay as short as now
            steps = s.generations_total - s.generation - 1
            full, short = time_left(walls, clocks, steps, ahead=c.episode.seconds), time_left(walls, clocks, steps)
            shorter = f"; {hms(short)} if episodes stay as short as now" if short < 0.75 * full else ""
            best = run.best or {"fitness": s.best, "fell": s.best_fell}
            line.report(s.generation + 1, f"best {best['fitness']:.3f} {'(fell)' if best['fell'] else '(up)'}, this generation's "
                        f"{s.best:.3f} {'(fell)' if s.best_fell else '(up)'}, mean {s.mean:.3f}, worst {s.worst:.3f}; "
                        f"{s.evals_per_second:.1f} eval/s, {s.simulated_seconds:.0f} s simulated, longest episode "
                        f"{s.longest_seconds:.1f} s{shorter}", left=full)

        try:
            summary = run.evolve(evaluator, progress)
        except KeyboardInterrupt as exc:  # Ctrl-C, SIGTERM, SIGHUP
            print(f"evobiped: interrupted after generation {run.ga.generation - 1} (numbered from 0, as in {HISTORY}); checkpoint saved; "
                  f"continue with: evobiped evolve --resume {run.dir}", file=sys.stderr)
            return exit_status(exc)
    best = summary["best"]
    state = "fell at %.2f s" % best["end_time"] if best["fell"] else "did not fall"
    walk = f"; {walk_line(summary['best_walk'])}" if summary.get("best_walk") else ""
    print(f"done: best fitness {best['fitness']:.3f} (generation {best['generation']}, {state}{walk}); "
          f"{summary['evaluations']} evaluations in {hms(summary['wall_seconds'])}; results in {run.dir}")
    return 0


def _viewer_log(run, rerun: str):
    """A live viewer of the run's fitness (a new one, or the one at ADDR), started with the history so far
    (the run's own evolution.rrd is written either way, after every generation)."""
    from .record.evolution_log import EvolutionLog
    from .rundir import history_columns

    log = EvolutionLog(recording_id=run.recording_id, **({"spawn": True} if rerun == "spawn" else {"connect": rerun}))
    if run.history:
        log.log_history(history_columns(run.history))
    return log


def add_presets(sub) -> None:
    p = sub.add_parser("presets", help="list the named run settings for `evolve --preset NAME`")
    p.set_defaults(func=run_presets_cmd)


def run_presets_cmd(args) -> int:
    from .presets import describe, names

    width = max(map(len, names()))
    for name in names():
        print(f"{name:<{width}}  {describe(name)}")
    return 0


# ---------------------------------------------------------------- replay
def add_replay(sub) -> None:
    p = sub.add_parser("replay", help="re-simulate a stored genome into a Rerun recording (and figures)")
    p.add_argument("source", metavar="SOURCE", help="a run directory (its best.json) or a genome JSON file")
    p.add_argument("--generation", type=int, metavar="N", help="replay the best of generation N of a run directory")
    p.add_argument("--seconds", type=positive_float, metavar="S", help="episode length in s (default: the stored one)")
    where = p.add_mutually_exclusive_group()
    where.add_argument("--out", metavar="FILE.rrd", help="recording file (default RUN/replay_best.rrd, or runs/<stem>/replay_<stem>.rrd for a genome file)")
    where.add_argument("--spawn", action="store_true", help="stream to a newly spawned Rerun viewer instead of a file")
    where.add_argument("--connect", nargs="?", const="", metavar="ADDR", help="stream to a running viewer (default 127.0.0.1:9876)")
    p.add_argument("--figures", nargs="?", const="", metavar="DIR", help="also write the figures as PNG (default: beside the recording)")
    p.add_argument("--video", metavar="FILE", help="also render a video, MP4 or GIF by the suffix, without a display "
                   "(MuJoCo's offscreen renderer; MUJOCO_GL unset: a display's GLFW, else EGL, else OSMesa); "
                   "the frames go into the recording too")
    p.add_argument("--video-size", nargs=2, type=positive_int, metavar=("W", "H"), default=[480, 360],
                   help="size of each panel in pixels, even numbers (default 480 360; a steering walker gets one panel per source)")
    p.add_argument("--video-fps", type=positive_float, default=25.0, metavar="FPS", help="frames per simulated second (default 25: real time)")
    p.add_argument("--video-window", nargs=2, type=float, metavar=("T0", "T1"), help="only simulated times T0..T1 s (default: all)")
    add_source_flag(p)
    p.add_argument("--quiet", action="store_true", help="no progress lines")
    p.set_defaults(func=run_replay_cmd)


def run_replay_cmd(args) -> int:
    from pathlib import Path

    from .record.replay import default_out, replay
    from .record.source import resolve
    from .rundir import figures_dir

    video_flags = args.video_window is not None or args.video_size != [480, 360] or args.video_fps != 25.0
    if args.video is None and video_flags:
        refuse("--video-size/--video-fps/--video-window", "they shape the video: give --video FILE too")
    if any(v % 2 for v in args.video_size):
        refuse("--video-size", f"width and height must be even (H.264), got {args.video_size[0]} {args.video_size[1]}")
    if args.video_window is not None and not 0 <= args.video_window[0] < args.video_window[1]:
        refuse("--video-window", f"needs 0 <= T0 < T1, got {args.video_window[0]:g} {args.video_window[1]:g}")
    source = resolve(args.source, args.generation)
    figures = args.figures
    if figures == "":
        base = Path(args.out).parent if args.out else default_out(source).parent
        figures = figures_dir(base, source.label)
    seconds = args.seconds or source.config.seconds
    progress = Progress("replay", seconds, "s simulated", quiet=args.quiet)
    frames = Progress("replay video", 1.0, "frames rendered", quiet=args.quiet)
    r = replay(source, seconds=args.seconds, out=args.out, spawn=args.spawn, connect=args.connect, figures_dir=figures,
               listener=progress.listener(), sources=args.sources, video=args.video,
               video_options=dict(fps=args.video_fps, size=tuple(args.video_size), window=args.video_window, progress=frames))
    progress.finish()
    if args.video:
        frames.finish()
    state = f"fell at t = {r.end_time:.2f} s" if r.fell else f"stayed up for {r.end_time:.1f} s"
    print(f"replayed fitness = {r.fitness!r}; {state}; {walk_line(r.walk)}")
    if not r.compared:
        why = ("it is the aggregate over the perturbed presentations the run evolved on; the replay is nominal"
               if source.config.perturbed else "--source changed the sources" if args.sources and not args.seconds
               else "--seconds changed the episode length")
        print(f"stored fitness not compared: {why}")
    elif r.stored_fitness is None:
        print("stored fitness: none in the genome file")
    elif not r.environment_differences:
        verdict = "equals it bit for bit" if r.matches else f"DIFFERS by {r.fitness - r.stored_fitness:.3g}"
        print(f"stored fitness   = {r.stored_fitness!r}: the replay {verdict} (same numerical environment)")
    else:
        print(f"numerical environment differs from the stored one: {'; '.join(r.environment_differences)}")
        print(f"stored fitness   = {r.stored_fitness!r}: "
              + ("the replay equals it bit for bit all the same" if r.matches else f"drift {drift_text(r.fitness, r.stored_fitness)}"))
    if r.outcome_checked:
        if r.environment_differences and not r.compared:
            print(f"numerical environment differs from the stored one: {'; '.join(r.environment_differences)}")
        print("outcome drift: " + "; ".join(r.drift))
        print("outcome holds within the declared tolerance" if not r.outcome_failures
              else "outcome DIFFERS: " + "; ".join(r.outcome_failures))
    print(f"recording: {r.recording}" if r.recording else "recording streamed to the viewer")
    for f in r.figures:
        print(f"figure: {f}")
    if r.video is not None:
        print(f"video: {r.video}")
    return 0 if r.reproduced else 1


def drift_text(value: float, stored: float) -> str:
    """``+3.4e-06 (8.2e-05 relative)``: how far a replayed fitness drifted from the stored one."""
    d = value - stored
    rel = f" ({abs(d) / abs(stored):.2g} relative)" if stored else ""
    return f"{d:+.3g}{rel}"


# ---------------------------------------------------------------- robustness
def add_robustness(sub) -> None:
    p = sub.add_parser("robustness", help="the robustness battery (pushes, target offsets, friction, slopes) for any Reil walker")
    p.add_argument("source", metavar="SOURCE", help="a run directory (its best.json) or a genome JSON file")
    p.add_argument("--generation", type=int, metavar="N", help="the best of generation N of a run directory")
    p.add_argument("--seconds", type=positive_float, default=30.0, help="length of each trial in s (default 30)")
    p.add_argument("--push-after", type=positive_float, default=10.0, metavar="S",
                   help="pushes fall in the first stride after S s (default 10)")
    p.add_argument("--out", metavar="DIR", help="where robustness.json and robustness.png go (default: the run directory, or runs/<stem>/ for a genome file)")
    p.add_argument("--source", dest="sound_source", nargs=2, type=float, metavar=("X", "Y"),
                   help="a steering walker's sound source at (X, Y) m for every trial (the battery runs one presentation)")
    p.add_argument("--json", action="store_true", help="print the summary as JSON")
    p.add_argument("--quiet", action="store_true", help="no progress lines")
    p.set_defaults(func=run_robustness_cmd)


def run_robustness_cmd(args) -> int:
    from pathlib import Path

    from .fileio import write_json
    from .record.robustness_figure import robustness_figure
    from .record.source import resolve
    from .robustness import battery, summarise, table
    from .rundir import genome_outputs, robustness_stem

    if args.push_after >= args.seconds:
        raise UserError(f"--push-after ({args.push_after:g} s) must be shorter than --seconds ({args.seconds:g} s)")
    source = resolve(args.source, args.generation)
    out = Path(args.out) if args.out else (source.run_dir or genome_outputs(source.genome_path))
    if out.exists() and not out.is_dir():
        raise UserError(f"--out {out} exists and is not a directory")
    stem = robustness_stem(source.label) if source.run_dir is not None else f"{source.genome_path.stem}_robustness"
    progress = Progress("robustness", 1.0, quiet=args.quiet or args.json)
    config = with_sources(source.config.nominal(), [args.sound_source] if args.sound_source else None)
    trials = battery(config.build(), source.genome, seconds=args.seconds, push_after=args.push_after, progress=progress)
    progress.finish()
    rows = summarise(trials)
    out.mkdir(parents=True, exist_ok=True)
    report = {"source": str(source.genome_path), "seconds": args.seconds, "push_after": args.push_after,
              "families": rows, "trials": [dataclasses.asdict(t) for t in trials]}
    write_json(out / f"{stem}.json", report)
    seed = source.meta.get("seed")
    who = f"{source.name}: {source.config.body}/{source.config.controller}" + (f", run seed {seed}" if seed is not None else "")
    png = robustness_figure(trials, out / f"{stem}.png", seconds=args.seconds,
                            title=f"Robustness battery, {len(trials)} trials of {args.seconds:g} s (pushes after {args.push_after:g} s)\n{who}")
    if args.json:
        print(json.dumps(rows))
    else:
        print(table(rows))
        print(f"results: {out / (stem + '.json')}\nfigure: {png}")
    return 0


# ---------------------------------------------------------------- g3
def add_g3(sub) -> None:
    p = sub.add_parser("g3", help="run the G3 gait generator (Pribe et al. 1997) at GO levels; gait table and PNGs")
    from .experiments.g3.network import PRESETS

    p.add_argument("preset", help=f"parameter set: {', '.join(PRESETS)}")
    lv = p.add_mutually_exclusive_group()
    lv.add_argument("--go", type=float, nargs="+", metavar="I", help="GO level(s) (default: the preset's)")
    lv.add_argument("--sweep", type=float, nargs=3, metavar=("START", "STOP", "STEP"), help="GO levels START..STOP (inclusive)")
    p.add_argument("--continue", dest="mode", action="store_const", const="continue", default="reset",
                   help="one run through the levels keeping the state (default: reset to zero per level)")
    p.add_argument("--from-go", type=float, metavar="I0", help="start every run at I0 and switch at --switch-at (Figs. 8B, 10)")
    p.add_argument("--switch-at", type=positive_float, help="time of the switch from --from-go (default 30; only with --from-go)")
    p.add_argument("--t-run", type=positive_float, help="time units per level (default: the preset's, 120)")
    p.add_argument("--dt", type=positive_float, default=0.005, help="RK4 step in model time units (default 0.005)")
    p.add_argument("--channels", help="channels drawn in the diagrams, names or 0-3 (default all: LF,RF,LH,RH; only with --out)")
    p.add_argument("--out", metavar="DIR", help="write PNG gait diagrams and the frequency plot here")
    p.add_argument("--json", action="store_true", help="print machine-readable JSON")
    p.set_defaults(func=run_g3_cmd)


def run_g3_cmd(args) -> int:
    from .experiments.g3 import network as g3
    from .experiments.g3.simulation import go_sweep
    from .errors import ConfigError

    pre = g3.preset(args.preset)
    if args.switch_at is not None and args.from_go is None:
        refuse("--switch-at", "it times the switch from --from-go; give --from-go too")
    switch_at = 30.0 if args.switch_at is None else args.switch_at
    channels = [c.strip() for c in (args.channels or "LF,RF,LH,RH").split(",") if c.strip()]
    if not channels:
        raise ConfigError("--channels: the channel list is empty")
    idx = []
    for c in channels:
        if c.upper() in g3.LIMBS:
            idx.append(g3.LIMBS.index(c.upper()))
        elif c.isdigit() and int(c) < len(g3.LIMBS):
            idx.append(int(c))
        else:
            raise ConfigError(f"--channels: unknown channel {c!r} (use {', '.join(g3.LIMBS)} or 0-3)")
    if args.channels is not None and not args.out:
        refuse("--channels", "it picks the channels of the diagrams; give --out DIR to draw them")
    if args.sweep:
        a, b, step = args.sweep
        if not step > 0 or b < a:
            raise ConfigError("--sweep needs START <= STOP and STEP > 0")
        levels = np.round(np.arange(a, b + step / 2, step), 10)
    else:
        levels = np.array(args.go if args.go else pre.go, float)
    if (levels < 0).any() or (args.from_go is not None and args.from_go < 0):
        raise ConfigError(f"GO levels must be >= 0, got {min(levels.min(), args.from_go or 0):g}")
    s = go_sweep(pre, levels, mode=args.mode, t_run=args.t_run, from_go=args.from_go, switch_at=switch_at, dt=args.dt)
    rows = [{"go": float(lv), **g.as_dict()} for lv, g in zip(s.levels, s.gaits)]
    files = []
    if args.out:
        from .experiments.g3.g3_figures import sweep_figures

        files = [str(f) for f in sweep_figures(args.out, f"g3_{pre.name}", s, idx, g3.LIMBS, title=f"G3 {pre.name} ({args.mode})")]
    if args.json:
        print(json.dumps({"preset": pre.name, "source": pre.source, "mode": args.mode, "levels": rows, "files": files}))
        return 0
    print(f"G3 {pre.name}: {pre.source}; {args.mode}" + (f" from I = {args.from_go:g} at t = {switch_at:g}" if args.from_go is not None else ""))
    print(f"{'I':>6} {'gait':<7} {'seq':<8} {'freq':>7} {'period':>7}  {'phases LF RF LH RH':<23} {'up':>5} {'first':<7} {'settle':>6}")
    for r in rows:
        ph = " ".join(f"{p:.2f}" if np.isfinite(p) else "  - " for p in r["phases"])
        print(f"{r['go']:6.3f} {r['label']:<7} {r['sequence']:<8} {r['frequency']:7.4f} {r['period']:7.3f}  {ph:<23} "
              f"{np.mean(r['duty']):5.3f} {r['transient_label']:<7} {r['settle_time']:6.1f}")
    print("up: mean fraction of the cycle a channel is above threshold (its limb off the ground; 1 - the duty factor)")
    for f in files:
        print(f"wrote {f}")
    return 0


# ---------------------------------------------------------------- study
def add_study(sub) -> None:
    p = sub.add_parser("study", help="K evolutionary runs per condition (plain, cyclic): success rates, distances, Fig. 5")
    p.add_argument("--runs", type=positive_int, default=10, help="runs (seeds) per condition (default 10)")
    p.add_argument("--conditions", default="plain,cyclic", help="fitness criteria, comma-separated: plain (eq. 4), cyclic, "
                   "forward (forward progress x time up) (default plain,cyclic)")
    p.add_argument("--controllers", help="controller axis, comma-separated (e.g. ctrnn,simbicon; default: the base run's)")
    p.add_argument("--optimizers", help="optimizer axis, comma-separated: ga, cma (default: the base run's)")
    p.add_argument("--preset", metavar="NAME", help=f"base run settings shipped with evobiped: {choices_text('preset')} (`evobiped presets`)")
    p.add_argument("--config", metavar="FILE.toml", help="base run settings (as for evolve); flags override it")
    p.add_argument("--population", type=positive_int, help="population size (default 50)")
    p.add_argument("--generations", type=positive_int, help="generations (default 120)")
    p.add_argument("--episode-seconds", type=positive_float, help="episode length in s (default 50)")
    p.add_argument("--first-seed", type=int, default=0, help="seeds are FIRST .. FIRST+K-1 (default 0)")
    p.add_argument("--recheck-seconds", type=positive_float, default=200.0, help="re-simulate stable best walkers this long (default 200)")
    p.add_argument("--backend", default="process", help=f"backend: {choices_text('backend')} (default process: one run per core)")
    p.add_argument("--workers", type=positive_int, help="runs at once (default: all cores; not with the serial backend)")
    p.add_argument("--address", help="Ray cluster address (only with --backend ray)")
    p.add_argument("--replays", action="store_true", help="also write a Rerun recording of each run's best walker")
    p.add_argument("--out", metavar="DIR", default="runs/study", help="study directory (default runs/study); an existing one is resumed")
    p.add_argument("--quiet", action="store_true", help="no progress lines")
    p.set_defaults(func=run_study_cmd)


def run_study_cmd(args) -> int:
    from pathlib import Path

    from .experiments.reil.study import StudyConfig, run_study, write_results

    base = run_config(preset=args.preset, config=args.config, episode_seconds=args.episode_seconds, population=args.population,
                      generations=args.generations)
    base = dataclasses.replace(base, seed=0)
    conditions = tuple(c.strip() for c in args.conditions.split(",") if c.strip())
    axis = lambda text: tuple(x.strip() for x in (text or "").split(",") if x.strip())  # noqa: E731
    cfg = StudyConfig(run=base, runs=args.runs, conditions=conditions, controllers=axis(args.controllers), optimizers=axis(args.optimizers),
                      first_seed=args.first_seed, recheck_seconds=args.recheck_seconds)
    check_workers(args.backend, args.workers, args.address)
    if args.backend == "ray" and args.address:
        from .evolution.evaluate import check_reachable

        check_reachable(args.address)
    say = (lambda m: None) if args.quiet else (lambda m: print(m, file=sys.stderr, flush=True))
    try:
        outcomes = run_study(args.out, cfg, backend=args.backend, workers=args.workers, address=args.address, progress=say)
    except KeyboardInterrupt as exc:
        print("evobiped: study interrupted; run the same command again to resume (finished runs are kept, the others resume from their checkpoints)", file=sys.stderr)
        return exit_status(exc)
    for path in write_results(args.out, cfg, outcomes):
        say(f"wrote {path}")
    if args.replays:
        from .record.replay import replay
        from .record.source import resolve
        from .experiments.reil.study import run_dir

        for c in cfg.condition_names:
            for k in range(cfg.runs):
                rep = replay(resolve(run_dir(Path(args.out), c, k, cfg)))
                say(f"recording: {rep.recording}")
    print((Path(args.out) / "table.md").read_text(), end="")
# ---------------------------------------------------------------- taga
def add_taga(sub) -> None:
    p = sub.add_parser("taga", help="run the Taga biped with its rhythm generator (Taga et al. 1991); gait metrics table")
    p.add_argument("--u0", type=float, nargs="+", default=[5.5], metavar="U", help="tonic input(s) u0, one walker each (default 5.5)")
    from .experiments.taga.walking import PRESETS

    p.add_argument("--preset", default="taga", help=f"rhythm-generator parameters: {', '.join(PRESETS)} (default taga: Appendix D)")
    p.add_argument("--seconds", type=positive_float, help="simulated time in s from Appendix E's initial state (default 20; not with --push)")
    p.add_argument("--window", type=positive_float, help="metrics over the last WINDOW s, at most --seconds (default 10; not with --push)")
    p.add_argument("--slope", type=float, default=0.0, metavar="PCT", help="terrain slope in %% (uphill > 0; default 0)")
    p.add_argument("--slope-start", type=float, default=0.0, metavar="X", help="x (m) where the slope begins (default 0)")
    p.add_argument("--kg", type=positive_float, default=1e4, help="ground stiffness N/m (default 1e4)")
    p.add_argument("--bg", type=float, default=1e3, help="ground damping N s/m (default 1e3)")
    p.add_argument("--timestep", type=positive_float, default=0.0005, help="physics step in s (default 0.0005)")
    p.add_argument("--push", choices=("leg", "hip"), help="Fig. 7: after 10 s push the right shank (200 N) or the hip (288 N) forward for 0.2 s")
    p.add_argument("--push-force", type=float, help="push force in N (default 200 leg, 288 hip; only with --push)")
    p.add_argument("--push-delay", type=float, help="push this many s after the right foot lifts off (default 0.05; only with --push)")
    p.add_argument("--save-genome", metavar="FILE.json", help="also write the genome file of the (first) walker, for evobiped replay")
    p.add_argument("--json", action="store_true", help="print machine-readable JSON")
    p.add_argument("--quiet", action="store_true", help="no progress lines")
    p.set_defaults(func=run_taga_cmd)


def _nan_to_null(row: dict) -> dict:
    """A metrics row for strict JSON: non-finite floats become null."""
    return {k: (None if isinstance(v, float) and not np.isfinite(v) else v) for k, v in row.items()}


def run_taga_cmd(args) -> int:
    from .bodies import TagaBiped
    from .controllers.matsuoka import MatsuokaOptions
    from .experiments.taga import walking as tx
    from .options import check_value, option_bounds
    from .validate import number

    if args.preset not in tx.PRESETS:
        raise UserError(f"unknown preset {args.preset!r} (choose from {', '.join(tx.PRESETS)})")
    for u in args.u0:
        check_value(MatsuokaOptions, "u0", u, "--u0")
    low, high = option_bounds(TagaBiped.Options, "slope")  # the body's declared limit, in % here
    number(args.slope, "--slope", low=100 * low, high=100 * high, unit="%")
    for flag in ("kg", "bg", "timestep", "slope_start"):
        check_value(TagaBiped.Options, flag, getattr(args, flag), f"--{flag.replace('_', '-')}")
    seconds = 20.0 if args.seconds is None else args.seconds
    window = min(10.0, seconds) if args.window is None else args.window
    if args.push:
        if args.seconds is not None or args.window is not None:
            refuse("--seconds/--window", "--push runs its own schedule (10 s, the push, 8 s more) and reports strides, not a window")
    else:
        if args.push_force is not None or args.push_delay is not None:
            refuse("--push-force/--push-delay", "they shape the push; give --push leg or --push hip")
        if window > seconds:
            refuse("--window", f"the metrics window ({window:g} s) cannot be longer than the simulated --seconds ({seconds:g} s)")
    opts = dict(preset=args.preset, timestep=args.timestep, kg=args.kg, bg=args.bg, slope=args.slope / 100, slope_start=args.slope_start)
    total = 10.0 + 2.0 + 0.2 + 8.0 if args.push else seconds
    progress = Progress("taga", total, "s simulated", quiet=args.quiet or args.json)
    if args.save_genome:
        from .episode import EpisodeConfig
        from .genome_file import save_genome

        body = {k: v for k, v in opts.items() if k != "preset"}
        cfg = EpisodeConfig(body="taga", controller="matsuoka", seconds=seconds, body_options=body, controller_options={"u0": args.u0[0]})
        save_genome(args.save_genome, tx.preset_genome(cfg.build().controller, args.preset), cfg, preset=args.preset)
    if args.push:
        if len(args.u0) != 1:
            raise UserError("--push takes one --u0 value")
        force = args.push_force if args.push_force is not None else (200.0 if args.push == "leg" else 288.0)
        target = "right_shank" if args.push == "leg" else "hip"
        delay = 0.05 if args.push_delay is None else args.push_delay
        _, (s,) = tx.push(target, force, [delay], u0=args.u0[0], progress=progress.update, **opts)
        progress.finish()
        if args.json:
            print(json.dumps(_nan_to_null(s), allow_nan=False))
            return 0
        if s["t_push"] is None:
            print(f"push {target} {force:g} N (u0 = {args.u0[0]:g}): not given, the walker fell at {s['fell_at']:.2f} s, before the push")
            return 0
        print(f"push {target} {force:g} N for 0.2 s at t = {s['t_push']:.2f} s (u0 = {args.u0[0]:g}): "
              + (f"fell at {s['fell_at']:.2f} s" if s["fell"] else f"recovered after {s['strides_to_recover']} strides"))
        print(f"before: stride {s['stride_length_before']:.3f} m, cycle {s['cycle_duration_before']:.3f} s")
        for i, (L, D) in enumerate(s["strides_after"]):
            print(f"  stride {i + 1:2d} after: {L:.3f} m  {D:.3f} s")
        return 0
    _, rows = tx.steady(args.u0, seconds=seconds, window=window, progress=progress.update, **opts)
    progress.finish()
    if args.json:
        settings = {**{k: v for k, v in vars(args).items() if k != "func"}, "seconds": seconds, "window": window}
        print(json.dumps({"settings": settings, "walkers": [_nan_to_null(r) for r in rows]}, allow_nan=False))
        return 0
    print(f"Taga biped, preset {args.preset}, slope {args.slope:g} %, kg {args.kg:g}, bg {args.bg:g}; "
          f"metrics over the last {window:g} of {seconds:g} s")
    print(f"{'u0':>6} {'gait':<6} {'fell at':>7} {'strides':>7} {'stride m':>8} {'cycle s':>7} {'speed':>6} {'double':>6} {'flight':>6} {'hip min-max m':>14}")
    for r in rows:
        fell = f"{r['fell_at']:.2f}" if r["fell"] else "-"
        print(f"{r['u0']:6.2f} {r['gait']:<6} {fell:>7} {r['strides']:7d} {r['stride_length']:8.3f} {r['cycle_duration']:7.3f} "
              f"{r['speed']:6.3f} {r['double_support']:6.3f} {r['flight']:6.3f} {r['hip_min']:6.3f}-{r['hip_max']:.3f}")
    return 0


# ---------------------------------------------------------------- bench
def add_bench(sub) -> None:
    p = sub.add_parser("bench", help="evaluation speed as ratios against raw MuJoCo stepping (same model, dt, cores)")
    p.add_argument("--body", default="reil", help=f"body: {choices_text('body')} (default reil)")
    p.add_argument("--controller", default="ctrnn", help=f"controller: {choices_text('controller')} (default ctrnn)")
    p.add_argument("--population", type=positive_int, help="walkers (default 50; --quick 16)")
    p.add_argument("--seconds", type=positive_float, help="episode length in s (default 50; --quick 4)")
    p.add_argument("--workers", type=positive_int, help="threads for raw stepping, workers for the pools (default: all cores)")
    p.add_argument("--repeats", type=positive_int, help="interleaved repeats of each measurement; the median counts (default 5)")
    p.add_argument("--presentations", type=positive_int, default=1, metavar="R",
                   help="also time evaluation on R perturbed presentations per walker, per simulated second (default 1: not measured)")
    p.add_argument("--quick", action="store_true", help="a small run (under 30 s): 16 walkers x 4 s, 5 repeats")
    p.add_argument("--json", action="store_true", help="print machine-readable JSON")
    p.add_argument("--quiet", action="store_true", help="no progress lines")
    p.set_defaults(func=run_bench_cmd)


def run_bench_cmd(args) -> int:
    from .bench import QUICK, bench, format_bench
    from .episode import EpisodeConfig

    size = dict(QUICK) if args.quick else dict(population=50, seconds=50.0, repeats=5)
    size.update({k: getattr(args, k) for k in size if getattr(args, k) is not None})
    cfg = EpisodeConfig(body=args.body, controller=args.controller, seconds=size["seconds"])
    check_workers("process", args.workers, None)
    progress = Progress("bench", size["repeats"], "repeats", quiet=args.quiet or args.json)
    r = bench(cfg, population=size["population"], workers=args.workers, repeats=size["repeats"], presentations=args.presentations,
              progress=progress)
    progress.finish()
    print(json.dumps(r, indent=2) if args.json else format_bench(r))
    return 0


# ---------------------------------------------------------------- distill
def add_distill(sub) -> None:
    p = sub.add_parser("distill", help="train a CTRNN to imitate a walker (DAgger + backpropagation through time); writes a genome file")
    p.add_argument("teacher", metavar="TEACHER", help="a run directory (its best.json) or a genome JSON file, any controller")
    p.add_argument("--generation", type=int, metavar="N", help="the best of generation N of a run directory")
    p.add_argument("--config", metavar="FILE.toml", help="[distill] settings and [student] controller options")
    p.add_argument("--neurons", type=int, metavar="N", help="the student's neurons (default 40)")
    p.add_argument("--iterations", type=positive_int, metavar="I", help="DAgger iterations (default 5)")
    p.add_argument("--seed", type=int, default=0, help="seed of the rollouts' noise and the fit (default 0)")
    p.add_argument("--seconds", type=positive_float, default=50.0, metavar="S", help="the student's episode length in s (default 50)")
    p.add_argument("--out", metavar="FILE.json", help="the student's genome file (default runs/distill_<teacher run or file>_seed<S>/student.json)")
    p.add_argument("--quiet", action="store_true", help="no progress lines")
    p.set_defaults(func=run_distill_cmd)


def run_distill_cmd(args) -> int:
    from pathlib import Path

    from .distill import distill, parse_options, student_config
    from .fileio import read_toml, write_json
    from .genome_file import save_genome
    from .outcome import outcome
    from .record.source import resolve

    source = resolve(args.teacher, args.generation)
    table = read_toml(args.config) if args.config else {}
    unknown = sorted(set(table) - {"distill", "student"})
    if unknown:
        raise UserError(f"{args.config}: unknown section {unknown[0]!r} (choose from distill, student)")
    settings = dict(table.get("distill", {}))
    if args.iterations is not None:
        settings["iterations"] = args.iterations
    options = parse_options(settings)
    overrides = dict(table.get("student", {}))
    body = overrides.pop("body", source.config.body)
    if body != source.config.body:
        raise UserError(f"the student's body {body!r} differs from the teacher's {source.config.body!r}: a student imitates "
                        "its teacher on the teacher's body")
    if args.neurons is not None:
        overrides["n_neurons"] = args.neurons
    student = student_config(source.config, overrides, seconds=args.seconds)
    student.layout()  # the contract (sensors, normalisation) checked before anything runs
    name = source.run_dir.name if source.run_dir is not None else source.genome_path.stem
    out = Path(args.out) if args.out else Path("runs") / f"distill_{name}_seed{args.seed}" / "student.json"
    if out.exists() and not out.is_file():
        raise UserError(f"--out {out} exists and is not a file")
    teacher_cfg = dataclasses.replace(source.config, perturbations={})
    check = teacher_cfg.build().run(source.genome)
    if check.fell[0]:
        raise UserError(f"the teacher {source.genome_path} falls at {check.end_time[0]:.1f} s of its own episode "
                        f"(latency {teacher_cfg.latency} ticks): it cannot teach walking")
    walk = check.walk()
    progress = Progress("distill", 1.0, quiet=args.quiet)
    progress.say(f"teacher {source.genome_path}: up {check.end_time[0]:g} s, {walk_line(walk)}")
    report = distill(teacher_cfg, source.genome, student=student, options=options, seed=args.seed, progress=progress.say)
    progress.finish()
    episode = student.build()
    done = episode.run(report.genome)
    out.parent.mkdir(parents=True, exist_ok=True)
    save_genome(out, report.genome, student, fitness=float(done.fitness[0]), fell=bool(done.fell[0]),
                end_time=float(done.end_time[0]), seed=args.seed, teacher=str(source.genome_path),
                distill=dataclasses.asdict(options), iterations=report.iterations, outcome=outcome(done, episode.task.targets()))
    write_json(out.with_name(out.stem + "_distill.json"), {"teacher": str(source.genome_path), "options": dataclasses.asdict(options),
                                                          "iterations": report.iterations})
    state = f"fell at t = {done.end_time[0]:.2f} s" if done.fell[0] else f"stayed up for {done.end_time[0]:.1f} s"
    print(f"student ({student.controller_options.n_neurons} neurons): {state}; {walk_line(done.walk())}")
    print(f"genome file: {out}")
    return 0


SUBCOMMANDS = [add_episode, add_evolve, add_presets, add_robustness, add_study, add_bench, add_replay, add_distill, add_taga, add_g3]


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="evobiped", description="Evolve neural controllers for bipedal walkers in MuJoCo.")
    parser.add_argument("--version", action="version", version=f"evobiped {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    for add in SUBCOMMANDS:
        add(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    restore = stop_on_signals()  # SIGTERM, SIGHUP: as Ctrl-C
    try:
        return int(args.func(args) or 0)
    except UserError as exc:
        print(f"evobiped: error: {exc}", file=sys.stderr)
        return 2
    except BrokenPipeError:  # the reader went away (`evobiped presets | head -1`): stop quietly, as cat does
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())  # no second error when Python flushes stdout
        return 141
    except OSError as exc:  # a file or directory that cannot be read or written: one line, not a traceback
        if exc.filename is None:
            raise
        from pathlib import Path

        where = Path(exc.filename)
        if where.name.startswith(".") and where.name.endswith(".tmp"):  # an atomic write's temporary file: name its folder
            where = where.parent
        print(f"evobiped: error: cannot access {where}: {exc.strerror or exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt as exc:
        print("evobiped: interrupted", file=sys.stderr)
        return exit_status(exc)
    finally:
        restore()


if __name__ == "__main__":
    sys.exit(main())
