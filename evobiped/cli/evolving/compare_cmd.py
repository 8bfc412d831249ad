"""``evobiped compare``: run configurations for N seeds each at one budget of evaluated episodes and compare their
final policies on fresh noise: success rates (Wilson 95 %), the measure's median and IQR, Vargha-Delaney A and
Mann-Whitney p per pair; results.md (printed), results.json, success.png."""

from __future__ import annotations

import sys
from pathlib import Path

from ...core.errors import UserError
from ...flags import choices_text, positive_int, seed

#: the comparison's settings a resume takes from its directory unless given again (then they must match)
SETTINGS = ("seeds", "budget", "trials", "checkpoints", "noise", "measure", "success")


def add_compare(sub) -> None:
    what = ("compare run configurations over N seeds at one budget of evaluated episodes: success rates, effect sizes, "
            "tests")
    p = sub.add_parser("compare", help=what, description=what + "; each run's final policy is re-evaluated on fresh "
                                                                "noise")
    p.add_argument("configs", nargs="*", metavar="CONFIG", help=f"a preset ({choices_text('preset')}) or a settings "
                                                                "file (TOML, as evolve --config takes)")
    p.add_argument("--seeds", type=positive_int, metavar="N", help="runs per configuration, seeds FIRST..FIRST+N-1")
    p.add_argument("--first-seed", type=seed, default=None, metavar="FIRST", help="the first seed (default 0)")
    p.add_argument("--budget", type=positive_int, metavar="EVALS",
                   help="episodes each run evaluates: it stops at the first "
                   "generation boundary where it has evaluated this many (genomes x presentations each)")
    p.add_argument("--trials", type=positive_int, metavar="K", help="fresh presentations per re-evaluated policy "
                                                                    "(default 8)")
    p.add_argument("--checkpoints", type=positive_int, metavar="C",
                   help="points of the success curve: each run's policy "
                   "re-evaluated where it reached budget x i / C episodes (default 4; the last is the final policy)")
    p.add_argument("--noise", metavar="FILE.toml", help="the fresh presentations' perturbations: the file's "
                   "[episode.perturbations] table (default: initial-pose noise of 0.02 rad)")
    p.add_argument("--measure", metavar="TERM", help="fitness (default) or a term of the task, e.g. distance")
    p.add_argument("--success", metavar="CRITERION", help="walker (default: up 200 s and a walk by the gait lab's "
                                                          "criteria over the first 50 s, under the fresh noise), "
                                                          "forward (up 200 s, 20 m in the first 50 s within 30 deg) or "
                                                          "TERM>=X (also >, <=, <), e.g. distance>=5")
    p.add_argument("--workers", type=positive_int, help="runs at once, each in its own process (default: all cores)")
    p.add_argument("--out", metavar="DIR", help="comparison directory (default runs/compare_<names>)")
    p.add_argument("--resume", metavar="DIR", help="continue the comparison in DIR (its configurations and settings; "
                                                   "any given again must be the same)")
    p.add_argument("--quiet", action="store_true", help="no progress lines")
    p.set_defaults(func=run_compare_cmd)


def _configs(names: list[str]) -> tuple[tuple[str, ...], tuple]:
    """Each CONFIG's name (the preset's, the file's stem; repeats numbered) and RunConfig."""
    from ...files.presets import names as presets
    from ...flags import run_config

    shipped, labels, configs = presets(), [], []
    for text in names:
        if text in shipped:
            label, config = text, run_config(preset=text)
        elif text.endswith(".toml") or Path(text).exists():
            if not Path(text).is_file():
                raise UserError(f"settings file not found: {text}")
            label, config = Path(text).stem, run_config(config=text)
        else:
            raise UserError(f"{text!r} is neither a preset ({', '.join(shipped)}) nor a settings file")
        n = sum(1 for x in labels if x == label or x.startswith(f"{label}-"))
        labels.append(label if n == 0 else f"{label}-{n + 1}")
        configs.append(config)
    return tuple(labels), tuple(configs)


def _noise(path: str | None) -> dict | None:
    from ...core.fileio import read_toml

    if path is None:
        return None
    d = read_toml(path, what="noise file")
    table = d.get("episode", {}).get("perturbations") if isinstance(d.get("episode"), dict) else None
    if not isinstance(table, dict):
        raise UserError(f"noise file {path} has no [episode.perturbations] table")
    return table


def default_compare_dir(names: tuple[str, ...]) -> str:
    base = Path("runs") / ("compare_" + "_".join(names))
    path, i = base, 1
    while path.exists():
        i += 1
        path = base.with_name(f"{base.name}_{i}")
    return str(path)


def run_compare_cmd(args) -> int:
    from ...core.progress import Progress
    from ...usecases.comparing import Comparison, compare_configurations

    given = {"seeds": None if args.seeds is None
             else tuple(range(args.first_seed or 0, (args.first_seed or 0) + args.seeds)),
             "budget": args.budget, "trials": args.trials, "checkpoints": args.checkpoints, "noise": _noise(args.noise),
             "measure": args.measure, "success": args.success}
    if args.first_seed is not None and args.seeds is None:
        raise UserError("--first-seed: give --seeds N with it")
    names, configs = _configs(args.configs)
    given = {k: v for k, v in given.items() if v is not None}
    comparison = None
    if args.resume:
        if args.out:
            raise UserError("--out: a resumed comparison stays in its directory (--resume DIR)")
        if configs:  # named again: they must be the stored ones
            given.update(names=names, configs=configs)
    else:
        if not configs:
            raise UserError("compare: give at least one CONFIG (a preset or a settings file)")
        for flag, value in (("--seeds", args.seeds), ("--budget", args.budget)):
            if value is None:
                raise UserError(f"{flag}: required (unless --resume DIR)")
        comparison = Comparison(names=names, configs=configs, **given)
    line = Progress("compare", 1, "runs", quiet=args.quiet)

    def on_run(done: int, total: int, r: dict) -> None:
        if r is None:  # the runs begin
            line.restart(max(total, 1))
            return
        final = r["checkpoints"][-1]
        line.report(done, f"{r['name']} seed {r['seed']}: {r['episodes']} episodes in {r['generations']} generations, "
                          f"final {final['value']:.3f}, {sum(final['passed'])} of {len(final['passed'])} fresh "
                          "presentations passed")

    results_dir = args.resume or args.out or default_compare_dir(names)
    kwargs = {"resume": args.resume} if args.resume else {"out": results_dir}
    try:
        results = compare_configurations(comparison, given=given if args.resume else None, workers=args.workers,
                                         say=line.say, on_run=on_run, **kwargs)
    except KeyboardInterrupt as exc:
        from ...core.errors import exit_status, last_line
        from ...usecases.comparing import FILE

        if not (Path(results_dir) / FILE).is_file():  # stopped before the comparison was opened: nothing to resume
            raise
        last_line(f"evobiped: interrupted; the runs done so far are kept: continue with: "
                  f"evobiped compare --resume {results_dir}")
        return exit_status(exc)
    from ...usecases.compare_report import markdown

    print(markdown(results), end="")
    print(f"results in {results_dir} (results.md, results.json, success.png)", file=sys.stderr if args.quiet
          else sys.stdout)
    return 0


SUBCOMMANDS = (add_compare,)
