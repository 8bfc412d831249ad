"""``evobiped study``: K evolutionary runs per condition of Reil & Husbands' experiment; success rates, distances, Fig.
5."""

from __future__ import annotations

import dataclasses
import sys

from ...core.errors import exit_status
from ...flags import check_workers, choices_text, positive_float, positive_int, run_config, seed


def add_study(sub) -> None:
    p = sub.add_parser("study", help="K evolutionary runs per condition (plain, cyclic): success rates, distances, "
                                     "Fig. 5")
    p.add_argument("--runs", type=positive_int, default=10, help="runs (seeds) per condition (default 10)")
    p.add_argument("--conditions", default="plain,cyclic", help="fitness criteria, comma-separated: plain (eq. 4), "
                                                                "cyclic, forward (forward progress x time up) (default "
                                                                "plain,cyclic)")
    p.add_argument("--controllers", help="controller axis, comma-separated (e.g. ctrnn,simbicon; default: the base "
                                         "run's)")
    p.add_argument("--optimizers", help="optimizer axis, comma-separated: ga, cma (default: the base run's)")
    p.add_argument("--preset", metavar="NAME", help="base run settings shipped with evobiped: "
                                                    f"{choices_text('preset')} (`evobiped presets`)")
    p.add_argument("--config", metavar="FILE.toml", help="base run settings (as for evolve); flags override it")
    p.add_argument("--population", type=positive_int, help="population size (default 50)")
    p.add_argument("--generations", type=positive_int, help="generations (default 120)")
    p.add_argument("--seconds", "--episode-seconds", dest="episode_seconds", type=positive_float,
                   help="episode length in s (default 50; --episode-seconds: the same, its older name)")
    p.add_argument("--first-seed", type=seed, default=0, help="seeds are FIRST .. FIRST+K-1 (default 0)")
    p.add_argument("--recheck-seconds", type=positive_float, default=200.0,
                   help="re-simulate stable best walkers this long (default 200)")
    p.add_argument("--backend", default="process", help=f"backend: {choices_text('backend')} (default process: one run "
                                                        "per core)")
    p.add_argument("--workers", type=positive_int,
                   help="runs at once (default: all cores; not with the serial backend)")
    p.add_argument("--address", help="Ray cluster address (only with --backend ray)")
    p.add_argument("--replays", action="store_true", help="also write a Rerun recording of each run's best walker")
    p.add_argument("--out", metavar="DIR", default="runs/study", help="study directory (default runs/study); an "
                                                                      "existing one is resumed")
    p.add_argument("--quiet", action="store_true", help="no progress lines")
    p.set_defaults(func=run_study_cmd)


def run_study_cmd(args) -> int:
    from pathlib import Path

    from .study import StudyConfig, run_study
    from .study_results import write_results

    base = run_config(preset=args.preset, config=args.config, episode_seconds=args.episode_seconds,
                      population=args.population, generations=args.generations)
    base = dataclasses.replace(base, seed=0)
    conditions = tuple(c.strip() for c in args.conditions.split(",") if c.strip())
    axis = lambda text: tuple(x.strip() for x in (text or "").split(",") if x.strip())  # noqa: E731
    cfg = StudyConfig(run=base, runs=args.runs, conditions=conditions, controllers=axis(args.controllers),
                      optimizers=axis(args.optimizers),
                      first_seed=args.first_seed, recheck_seconds=args.recheck_seconds)
    check_workers(args.backend, args.workers, args.address)
    if args.backend == "ray" and args.address:
        from ...evaluation.ray_backend import check_reachable

        check_reachable(args.address)
    say = (lambda m: None) if args.quiet else (lambda m: print(m, file=sys.stderr, flush=True))
    try:
        outcomes = run_study(args.out, cfg, backend=args.backend, workers=args.workers, address=args.address,
                             progress=say)
    except KeyboardInterrupt as exc:
        print("evobiped: study interrupted; run the same command again to resume (finished runs are kept, the others "
              "resume from their checkpoints)", file=sys.stderr)
        return exit_status(exc)
    for path in write_results(args.out, cfg, outcomes):
        say(f"wrote {path}")
    if args.replays:
        from ...usecases.replaying import replay
        from ...record.source import resolve
        from .study import run_dir

        for c in cfg.condition_names:
            for k in range(cfg.runs):
                rep = replay(resolve(run_dir(Path(args.out), c, k, cfg)))
                say(f"recording: {rep.recording}")
    print((Path(args.out) / "table.md").read_text(), end="")


SUBCOMMANDS = (add_study,)
