"""``evobiped bench``: evaluation speed as ratios against raw MuJoCo stepping."""

from __future__ import annotations

import dataclasses
import json

from ...flags import check_workers, choices_text, positive_float, positive_int
from ...core.errors import UserError
from ...core.progress import Progress


def add_bench(sub) -> None:
    p = sub.add_parser("bench", help="evaluation speed as ratios against raw MuJoCo stepping (same model, dt, cores)")
    p.add_argument("--preset", metavar="NAME", help="time the episode of this preset (its body, controller, task and "
                                                    "options, nominal; with its running normaliser's sense collection) "
                                                    "instead of --body/--controller")
    p.add_argument("--from", dest="initial", metavar="GENOME_OR_RUN",
                   help="the genome a preset that tunes a given genome starts from (its episode is timed)")
    p.add_argument("--body", default="reil", help=f"body: {choices_text('body')}, or mjcf:PATH (an MJCF biped and its "
                                                  "declaration: docs/own_robot.md; default reil)")
    p.add_argument("--controller", default="ctrnn", help=f"controller: {choices_text('controller')} (default ctrnn)")
    p.add_argument("--population", type=positive_int, help="walkers (default 50; --quick 16)")
    p.add_argument("--seconds", type=positive_float, help="episode length in s (default 50; --quick 4)")
    p.add_argument("--workers", type=positive_int, help="threads for raw stepping, workers for the pools (default: all "
                                                        "cores)")
    p.add_argument("--repeats", type=positive_int, help="interleaved repeats of each measurement; the median counts "
                                                        "(default 5)")
    p.add_argument("--presentations", type=positive_int, default=1, metavar="R",
                   help="also time evaluation on R perturbed presentations per walker, per simulated second (default "
                        "1: not measured)")
    p.add_argument("--kernel", default="auto", metavar="K", help="the tick's array work: auto (compiled where numba is "
                   "installed), compiled or numpy (the same numbers; default auto)")
    p.add_argument("--quick", action="store_true", help="a small run (under 30 s): 16 walkers x 4 s, 5 repeats")
    p.add_argument("--json", action="store_true", help="print machine-readable JSON")
    p.add_argument("--quiet", action="store_true", help="no progress lines")
    p.set_defaults(func=run_bench_cmd)


def run_bench_cmd(args) -> int:
    from ...analysis.bench import QUICK, bench, format_bench
    from ...episode import EpisodeConfig

    size = dict(QUICK) if args.quick else dict(population=50, seconds=50.0, repeats=5)
    size.update({k: getattr(args, k) for k in size if getattr(args, k) is not None})
    context = None
    if args.preset:
        from ...episode import Context
        from ...flags import run_config

        run = run_config(preset=args.preset, initial=args.initial)
        if run.initial:  # the genome is read and checked against the preset's layout, as evolve would
            from ...run.run_config import start_genome

            start_genome(run)
        cfg = dataclasses.replace(run.episode.nominal(), seconds=size["seconds"])
        context = Context(observe=True) if run.normalise.running else None
    else:
        if args.initial:
            raise UserError("bench: --from names the genome of a --preset that tunes one")
        cfg = EpisodeConfig(body=args.body, controller=args.controller, seconds=size["seconds"])
    from ...core.kernel import compiled

    compiled(args.kernel, "--kernel")
    cfg = dataclasses.replace(cfg, kernel=args.kernel)
    check_workers("process", args.workers, None)
    progress = Progress("bench", size["repeats"], "repeats", quiet=args.quiet or args.json)
    r = bench(cfg, population=size["population"], workers=args.workers, repeats=size["repeats"],
              presentations=args.presentations, progress=progress, context=context)
    progress.finish()
    print(json.dumps(r, indent=2) if args.json else format_bench(r))
    return 0


SUBCOMMANDS = (add_bench,)
