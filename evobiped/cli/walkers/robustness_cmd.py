"""``evobiped robustness``: the robustness battery of a stored walker; its table, JSON report and figure."""

from __future__ import annotations

import dataclasses
import json

from ...core.errors import UserError
from ...flags import add_stored_walker, finite_float, note, positive_float, seed, unfinished_note
from ...core.progress import Progress
from ...tasks.sound import with_sources


def add_robustness(sub) -> None:
    p = sub.add_parser("robustness", help="the robustness battery (pushes, target offsets, friction, slopes, gene "
                                          "noise) and its score for any Reil walker")
    add_stored_walker(p)
    p.add_argument("--seconds", type=positive_float, default=30.0, help="length of each trial in s (default 30)")
    p.add_argument("--push-after", type=positive_float, default=10.0, metavar="S",
                   help="pushes fall in the first stride after S s (default 10)")
    p.add_argument("--phase-seed", type=seed, metavar="N",
                   help="each push at its own phase of that stride, drawn uniformly from seed N (default: the fixed "
                        "phases 0, 1/4, 1/2, 3/4)")
    p.add_argument("--out", metavar="DIR", help="where robustness.json and robustness.png go (with --phase-seed N: "
                                                "robustness_phasesN.*, <stem>_phasesN_robustness.*) (default: the run "
                                                "directory; for a genome file in a run directory or under runs/ its "
                                                "folder, else runs/<stem>/)")
    p.add_argument("--source", dest="sound_source", nargs=2, type=finite_float, metavar=("X", "Y"),
                   help="a steering walker's sound source at (X, Y) m for every trial (the battery runs one "
                        "presentation)")
    p.add_argument("--json", action="store_true", help="print the score and the summary per family as JSON")
    p.add_argument("--quiet", action="store_true", help="no progress lines")
    p.set_defaults(func=run_robustness_cmd)


def run_robustness_cmd(args) -> int:
    from pathlib import Path

    from ...core.fileio import write_json
    from ...record.png.robustness_figure import robustness_figure
    from ...record.source import resolve
    from ...analysis.robustness import battery, score, summarise, table
    from ...files.rundir import robustness_stem
    from ...files.rundir.output_set import output_set

    if args.push_after >= args.seconds:
        raise UserError(f"--push-after ({args.push_after:g} s) must be shorter than --seconds ({args.seconds:g} s)")
    source = resolve(args.source, args.generation, args.allow_unfinished)
    unfinished_note(source)
    out = Path(args.out) if args.out else source.outputs
    if out.exists() and not out.is_dir():
        raise UserError(f"--out {out} exists and is not a directory")
    stem = robustness_stem(source.label) if source.run_dir is not None else f"{source.genome_path.stem}_robustness"
    if args.phase_seed is not None:  # a battery of its own: never overwrites the fixed-phase results
        tail = "_robustness"
        stem = (stem[:-len(tail)] + f"_phases{args.phase_seed}{tail}" if stem.endswith(tail)
                else f"{stem}_phases{args.phase_seed}")
    progress = Progress("robustness", 1.0, quiet=args.quiet or args.json)
    config = with_sources(source.config.nominal(), [args.sound_source] if args.sound_source else None)
    trials = battery(config.build(), source.genome, seconds=args.seconds, push_after=args.push_after,
                     phase_seed=args.phase_seed, progress=progress)
    progress.finish()
    rows = summarise(trials)
    total = score(trials)
    out.mkdir(parents=True, exist_ok=True)
    report = {"source": str(source.genome_path), "seconds": args.seconds, "push_after": args.push_after,
              "phase_seed": args.phase_seed,
              "score": total, "families": rows, "trials": [dataclasses.asdict(t) for t in trials],
              **({"unfinished_run": source.unfinished} if source.unfinished is not None else {})}
    seed = source.meta.get("seed")
    who = f"{source.name}: {source.config.body}/{source.config.controller}" + (f", run seed {seed}" if seed is not None
                                                                               else "")
    # the results and their figure are one set: the previous pair goes first; a cut-short one is said
    with output_set("robustness", [out / f"{stem}.json", out / f"{stem}.png"], say=note):
        write_json(out / f"{stem}.json", report)
        phases = "" if args.phase_seed is None else f", random phases, seed {args.phase_seed}"
        png = robustness_figure(trials, out / f"{stem}.png", seconds=args.seconds,
                                title=f"Robustness battery, {len(trials)} trials of {args.seconds:g} s (pushes after "
                                      f"{args.push_after:g} s{phases}): score {total:.3f} "
                                      f"({sum(t.survived for t in trials)} of {len(trials)} survived)\n{who}")
    if args.json:
        print(json.dumps({"score": total, "families": rows}))
    else:
        print(table(rows))
        print(f"robustness score: {total:.3f} ({sum(t.survived for t in trials)} of {len(trials)} trials survived)")
        print(f"results: {out / (stem + '.json')}\nfigure: {png}")
    return 0


SUBCOMMANDS = (add_robustness,)
