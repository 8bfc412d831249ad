"""``evobiped evolve``: a new run from a preset, a settings file and flags, or a resumed one; progress lines and the
summary."""

from __future__ import annotations

import contextlib
import sys

from ...core.errors import UserError, exit_status, last_line
from ...flags import (RUN_FLAGS, add_source_flag, check_workers, choices_text, positive_float, positive_int, run_config,
                      walk_line)
from ...core.progress import Progress, hms


def add_evolve(sub) -> None:
    from ...optimizers import OPTIMIZERS, described

    what = ("evolve controllers with Reil & Husbands' GA (the default, with the paper's settings), CMA-ES, evolution "
            "strategies or MAP-Elites (--optimizer)")
    p = sub.add_parser("evolve", help=what, description=what + "; --preset picks named settings (`evobiped presets`)")
    p.add_argument("--preset", metavar="NAME", help=f"named settings shipped with evobiped: {choices_text('preset')} "
                   "(`evobiped presets` describes them); --config and flags override it")
    p.add_argument("--config", metavar="FILE.toml", help="settings file; flags given here override it")
    p.add_argument("--optimizer", choices=tuple(OPTIMIZERS), help=f"{described(quote='')}; default ga")
    p.add_argument("--body", help=f"body: {choices_text('body')}, or mjcf:PATH (an MJCF biped and its declaration: "
                                  "docs/own_robot.md; default reil)")
    p.add_argument("--env", metavar="ID", help="a Gymnasium environment's id (Hopper-v5, Walker2d-v5, "
                   "evobiped/ReilBiped-v0, ...): its physics and return are the episode and the fitness (docs/gym.md)")
    p.add_argument("--controller", help=f"controller: {choices_text('controller')} (default ctrnn)")
    p.add_argument("--task", help=f"task: {choices_text('task')} (default walk)")
    add_source_flag(p)
    p.add_argument("--population", type=positive_int, help="population size (default: GA 50, CMA-ES 4 + 3 ln genes; "
                                                           "ES: twice its mirrored pairs)")
    p.add_argument("--generations", type=positive_int, help="generations (default 120)")
    p.add_argument("--seconds", "--episode-seconds", dest="episode_seconds", type=positive_float,
                   help="episode length in s (default 50; --episode-seconds: the same, its older name)")
    p.add_argument("--cyclic", action="store_true", default=None,
                   help="reward cyclic motor-neuron activity (Sect. III-A): the task's cyclic criterion")
    p.add_argument("--seed", type=int, help="run seed (default 0)")
    p.add_argument("--backend", help=f"backend: {choices_text('backend')} (default process)")
    p.add_argument("--workers", type=positive_int, help="worker processes / threads / Ray actors (default: all cores; "
                   "more than the cores earns a warning; not with the serial backend)")
    p.add_argument("--address", help="Ray cluster address (only with --backend ray; default: start a local Ray)")
    p.add_argument("--from", dest="initial", metavar="RUN_OR_GENOME",
                   help="start from this genome (the GA: a population of its clones; CMA-ES: the initial mean; "
                   "MAP-Elites: the first batch, it and its mutants)")
    p.add_argument("--freeze", metavar="BLOCKS", help="gene blocks the optimizer must not change, comma-separated "
                   "(e.g. weights,time_constants,biases: evolve only a CTRNN's input weights)")
    p.add_argument("--out", metavar="DIR", help="run directory (default runs/<body>_<controller>_seed<seed>)")
    p.add_argument("--resume", metavar="DIR", help="continue the run in DIR from its last checkpoint")
    p.add_argument("--rerun", nargs="?", const="spawn", metavar="ADDR",
                   help="also stream fitness per generation to a Rerun viewer: a new one, or the one at ADDR "
                        "(the run directory's evolution.rrd is written either way)")
    p.add_argument("--quiet", action="store_true", help="no progress lines")
    p.set_defaults(func=run_evolve_cmd)


def run_evolve_cmd(args) -> int:
    from ...usecases.evolving import evolve

    if args.rerun is not None:  # before anything is written
        from ...record.recordings.viewer import connect_url, require_display, require_viewer

        if args.rerun == "spawn":
            require_display()
        else:
            require_viewer(connect_url(args.rerun))
    on_retry = lambda n, limit: print(f"evobiped: a worker died; evaluating its batch again (retry {n} of {limit})",
                                      # noqa: E731
                                      file=sys.stderr, flush=True)
    if args.resume:
        if any(getattr(args, f) is not None for f in (*RUN_FLAGS, "out") if f not in ("backend", "workers", "address")):
            raise UserError("--resume takes the run's saved config: give only --workers/--backend/--address with it")
        where = dict(config=args.resume, backend=args.backend, workers=args.workers, address=args.address)
    else:  # the settings, the start genome and the run directory are checked before anything is written
        where = dict(config=run_config(**{f: getattr(args, f) for f in RUN_FLAGS}), out=args.out)
    shown = _Shown(args)
    try:
        with shown.viewer:
            evolve(**where, check=check_workers, on_opened=shown.opened, on_started=shown.started,
                   on_evaluated=shown.evaluated,
                   on_generation=shown.generation, on_retry=on_retry, on_done=shown.done, on_stop=shown.stopped)
    except KeyboardInterrupt as exc:
        if not shown.stop_said:  # before the evaluator started: the command's own "interrupted" line
            raise
        return exit_status(exc)
    return 0


class _Shown:
    """What the command shows of a run as :func:`~evobiped.usecases.evolving.evolve` goes: the repairs and notes of
    a resume, the header, a progress line per generation with the time left (every walker's episode length told to
    the clock), an optional live viewer, the final lines, and what a stop signal left."""

    def __init__(self, args):
        self.args, self.stop_said = args, False
        self.say = (lambda *a: None) if args.quiet else (lambda msg: print(msg, file=sys.stderr, flush=True))
        self.viewer, self.log, self.line, self.clock = contextlib.ExitStack(), None, None, None

    def opened(self, run) -> None:
        self.run = run
        for repair in run.repairs:
            print(f"evobiped: repaired: {repair}", file=sys.stderr)
        if run.environment_differences:
            print("evobiped: note: this run started in another numerical environment "
                  f"({'; '.join(run.environment_differences)}): from here on it is not bit-identical to an "
                  "uninterrupted run there", file=sys.stderr)
        if run.done:
            print(f"run {self.args.resume} is already complete ({run.optimizer.generation} generations)")

    def started(self, run, backend: str) -> None:
        from ...core.progress import GenerationClock

        c = run.config
        population = len(run.optimizer.ask()[0])
        until = (f" (or fewer: it stops once its walker {'walks' if c.stop.when == 'walking' else 'is fit enough'})"
                 if c.stop.active else "")
        what = (f"{c.episode.env}: {c.episode.controller}" if c.episode.env else
                f"{c.episode.body}/{c.episode.controller} on '{c.episode.task}'")
        from ...run.run_config import episodes_per_genome

        # a budget that ends the run before its generations do: the line counts episodes, its time left at the
        # rate of this session's episodes (else generations, forecast walker by walker)
        self.budgeted = c.budget is not None and c.budget < c.generations * population * episodes_per_genome(c)
        length = f"{c.budget} episodes (its budget)" if self.budgeted else f"{c.generations} generations"
        self.say(f"evolving {what} with {c.optimizer}, population {population}, {length}{until}, "
                 f"{c.episode.length:g} s episodes, seed {c.seed}, backend {backend} -> {run.dir}")
        if self.args.rerun is not None:
            self.log = self.viewer.enter_context(_viewer_log(run, self.args.rerun))
        if self.budgeted:
            self.line = Progress("evolve", c.budget, "episodes", quiet=self.args.quiet, at_most=c.stop.active)
            self.first_episodes = run.episodes()
        else:
            self.line = Progress("evolve", c.generations, "generations", quiet=self.args.quiet, at_most=c.stop.active)
        # every walker's episode, generation by generation
        self.clock = GenerationClock(c.generations, c.episode.length)

    def evaluated(self, rows) -> None:
        self.clock.episodes(rows.end_time)

    def generation(self, s) -> None:
        from ...core.progress import generation_note

        if self.log is not None:
            self.log.log_generation(s.generation, best=s.best, mean=s.mean, worst=s.worst, median=s.median,
                                    evaluations=s.evaluations, falls=s.falls, unstable=s.unstable,
                                    wall_seconds=s.wall_seconds)
        self.clock.generation(s.wall_seconds)
        best = self.run.record.best or {"fitness": s.best, "fell": s.best_fell}
        note = generation_note(
            best=best["fitness"], best_fell=best["fell"], this=s.best, this_fell=s.best_fell, mean=s.mean,
            worst=s.worst,
            evals_per_second=s.evals_per_second, simulated=s.simulated_seconds, longest=s.longest_seconds)
        if self.budgeted:
            done = self.run.episodes()
            rate = (done - self.first_episodes) / self.line.elapsed if self.line.elapsed > 0 else 0.0
            left = max(self.line.total - done, 0) / rate if rate > 0 else float("nan")
            self.line.report(done, f"generation {s.generation + 1}; {note}" + phase_note(self.run), left=left)
        else:
            self.line.report(s.generation + 1, note + phase_note(self.run), left=self.clock.left(s.generation + 1))
        lost = lost_line(self.run, s.generation)
        if lost:
            self.say(lost)

    def done(self, run, summary: dict) -> None:
        best = summary["best"]
        state = "fell at %.2f s" % best["end_time"] if best["fell"] else "did not fall"
        walk = f"; {walk_line(summary['best_walk'])}" if summary.get("best_walk") else ""
        if run.config.episode.env is not None:  # an environment's episode: its return and steps, no walk
            terms = best.get("terms", {})
            state = (f"return {terms.get('return', best['fitness']):.3f} in {terms.get('length', 0):.0f} steps, "
                     + ("ended by the environment" if best["fell"] else "to its time limit"))
            walk = ""
        # the elapsed time of the progress lines; a resumed run's evaluations span its earlier sessions too
        earlier = f" ({hms(summary['wall_seconds'])} of evaluation over all its sessions)" if self.args.resume else ""
        if run.context.lost_stop():
            print(f"stopped after generation {summary['generations'] - 1}: lost "
                  f"({lost_words(run.context.attempts.lost[-1], run)})")
        if summary.get("stopped_early"):
            rule = run.config.stop
            what = ("its evaluation walkers met the walking criteria" if rule.when == "walking"
                    else f"its evaluation walkers' fitness reached {rule.above:g}")
            print(f"stopped after generation {summary['generations'] - 1}: {what} for {rule.generations} generations "
                  "running ([stop])")
        print(f"done: best fitness {best['fitness']:.3f} (generation {best['generation']}, {state}{walk}); "
              f"{summary['evaluations']} evaluations, elapsed {hms(self.line.elapsed)}{earlier}; results in {run.dir}")

    def stopped(self, line: str) -> None:
        self.stop_said = True
        last_line(line)


def _viewer_log(run, rerun: str):
    """A live viewer of the run's fitness (a new one, or the one at ADDR), started with the history so far
    (the run's own evolution.rrd is written either way, after every generation)."""
    from ...record.recordings.evolution_log import EvolutionLog
    from ...files.rundir import history_columns

    log = EvolutionLog(recording_id=run.recording_id, **({"spawn": True} if rerun == "spawn" else {"connect": rerun}))
    if run.record.history:
        log.log_history(history_columns(run.record.history))
    return log


SUBCOMMANDS = (add_evolve,)


def phase_note(run) -> str:
    """The curriculum's phase for evolve's line ("; phase 2 of 2, its 37th generation"), and the attempt after a
    restart; empty for a run without either."""
    c, attempts = run.context.curriculum, run.context.attempts
    out = ""
    if c.active:
        since = attempts.phase_since if attempts is not None else None
        taken = "" if since is None else f", {run.optimizer.generation - since} generations in it"
        out += f"; now phase {c.phase + 1} of {len(c.options.phases)}{taken}"
    if attempts is not None and attempts.attempt:
        out += f"; attempt {attempts.attempt + 1}"
    return out


def lost_words(event: dict, run) -> str:
    """A lost phase in words: which phase, the patience it took (or the generations its walkers fell)."""
    phases = max(len(run.config.curriculum.phases), 1)
    if event.get("why") == "fallen":
        return (f"in phase {event['phase'] + 1} of {phases} the evaluation walkers fell in "
                f"{run.config.restart.fallen_for[event['phase']]} generations running (restart.fallen_for)")
    goal = "meet the stopping rule" if event["phase"] == phases - 1 and run.config.stop.active else (
        "advance" if event["phase"] < phases - 1 else "end")
    return (f"phase {event['phase'] + 1} of {phases} did not {goal} within its "
            f"{run.config.restart.patience[event['phase']]} generations (restart.patience)")


def lost_line(run, generation: int) -> str | None:
    """The line that says the run was lost after ``generation``, and what it does (None: it was not)."""
    attempts = run.context.attempts
    if attempts is None or not attempts.lost or attempts.lost[-1]["generation"] != generation:
        return None
    event, o = attempts.lost[-1], run.config.restart
    then = {"restart": f"starting over at generation {generation + 1} (restart {attempts.attempt} of at most "
                       f"{o.max_restarts})",
            "stop": "stopping" + (f" (all {o.max_restarts} restarts spent)" if o.action == "restart" else ""),
            "warn": "going on (restart.action = 'warn')"}[event["action"]]
    return f"evolve: lost: {lost_words(event, run)}; {then}"
