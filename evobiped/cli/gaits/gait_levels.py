"""``evobiped gait GENOME --u0 A,B,...`` / ``--go A,B,...``: a matsuoka (g3) walker through levels of its tonic input
(GO signal), ``--hold`` s each in one episode: a row per level, the speed fitted against the command, <stem>_u0.json
(<stem>_go.json) and a PNG (:mod:`evobiped.analysis.rhythm_command`)."""

from __future__ import annotations

from ...flags import note, number_list, refuse

#: the longest episode a sweep runs, all its levels together (s)
MAX_SECONDS = 3600.0
#: the flags of the other gait commands, with their defaults (none of them goes with --u0/--go)
OTHERS = {"speed": None, "turning": "0", "battery": None, "stretches": 6, "speed_range": None, "seed": 0, "ramp": None,
          "ramp_down": None, "correction": None, "overshoot": None}


def run_levels(args) -> int:
    """``args.u0`` or ``args.go`` (comma-separated levels) for the genome ``args.run``: see the module."""
    import json
    from pathlib import Path

    from ...analysis.rhythm_command import check_command, clip_levels, command_sweep, sweep_lines
    from ...core.fileio import write_json
    from ...files.rundir.output_set import output_set
    from ...record.png.levels_figure import levels_figure
    from ...record.source import resolve

    if args.u0 is not None and args.go is not None:
        refuse("--u0/--go", "give one: --u0 drives a matsuoka walker's tonic input, --go a g3 walker's GO signal")
    option = "u0" if args.u0 is not None else "go"
    given = [k for k, v in OTHERS.items() if getattr(args, k) != v]
    if given:
        refuse("/".join("--" + k.replace("_", "-").replace("speed-range", "range") for k in given),
               f"do not go with --{option} (it sweeps the controller's own command, straight ahead)")
    levels = number_list(f"--{option}", getattr(args, option))
    if not all(v >= 0 for v in levels):
        refuse(f"--{option}", f"levels must be >= 0, got {getattr(args, option)!r}")
    if args.hold * len(levels) > MAX_SECONDS:
        refuse("--hold", f"{len(levels)} levels of {args.hold:g} s are {args.hold * len(levels):g} s; a sweep runs "
                         f"at most {MAX_SECONDS:g} s")
    source = resolve(args.run)
    check_command(source.config, option, str(source.genome_path))
    levels, notes = clip_levels(source.config, option, levels)
    out = Path(args.out) if args.out else source.outputs
    if out.exists() and not out.is_dir():
        refuse("--out", f"{out} exists and is not a directory")
    report = command_sweep(source.config, source.genome, option, levels, args.hold)
    report.update(source=str(source.genome_path), notes=notes)
    out.mkdir(parents=True, exist_ok=True)
    stem = f"{source.genome_path.stem if source.run_dir is None else source.label}_{option}"
    title = f"{source.name}: forward speed through levels of {option}, {args.hold:g} s each"
    with output_set("gait", [out / f"{stem}.json", out / f"{stem}.png"], say=note):  # no new JSON beside an old PNG
        write_json(out / f"{stem}.json", report)
        png = levels_figure(report, out / f"{stem}.png", title=title)
    if args.json:
        print(json.dumps({k: v for k, v in report.items() if k != "trace"}))
        return 0
    for line in notes + sweep_lines(report):
        print(line)
    print(f"results: {out / (stem + '.json')}\nfigure: {png}")
    return 0
