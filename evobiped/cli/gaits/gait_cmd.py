"""``evobiped gait``: a speed knob over a map-elites run's gait repertoire (one commanded speed, or a schedule), a
commanded walker's genome (the command task) following commanded speeds and turning rates, or a rhythm generator's
walker through levels of its one command (``--u0``, ``--go``: :mod:`.gait_levels`)."""

from __future__ import annotations

from ...flags import MAX_SPEED, MAX_TURNING, count, finite_float, note, number_list, positive_float, refuse, seed


#: the most stretches a speed battery runs, all its schedules together (the docs' batteries: 180)
MAX_STRETCHES = 10**5


def add_gait(sub) -> None:
    p = sub.add_parser("gait", help="walk at a commanded speed (or a schedule of speeds) with the nearest gaits of a "
                                    "map-elites run's archive, or with a commanded walker's genome")
    p.add_argument("run", metavar="RUN|GENOME", help="a map-elites run directory (its archive.json), a commanded "
                                                     "walker (a genome file or run directory of the command task), or "
                                                     "with --u0/--go a matsuoka/g3 walker's")
    p.add_argument("--speed", metavar="V[,V...]",
                   help="commanded mean forward speed in m/s; several, comma-separated: a schedule, --hold s each (a "
                   "repertoire: elites switched on the fly; a commanded walker: 0 is a stop; without it, its own "
                   "nominal schedule)")
    p.add_argument("--turning", default="0", metavar="W[,W...]", help="commanded turning rate in deg/s, + left "
                                                                      "(default 0); a commanded walker also takes a "
                                                                      "list, one per speed")
    p.add_argument("--u0", metavar="A[,B...]", help="a matsuoka walker's genome: its tonic input u0 through "
                   "these levels, --hold s each, in one episode: speed per level (from 3 s into each), its gait, "
                   "speed fitted against u0; writes <stem>_u0.json and .png (levels beyond 50 %% outside the u0 it "
                   "was evolved with are clipped)")
    p.add_argument("--go", metavar="A[,B...]", help="a g3 walker's genome: its GO signal through these levels, as "
                   "--u0 does; writes <stem>_go.json and .png")
    p.add_argument("--hold", "--stretch", dest="hold", type=positive_float, default=10.0, metavar="S",
                   help="seconds each command is held (default 10)")
    p.add_argument("--json", action="store_true", help="a commanded walker, --u0, --go: print the report as JSON")
    p.add_argument("--out", metavar="DIR", help="a commanded walker, --u0, --go: where <stem>_command.json (_u0, _go) "
                                                "and .png go (default: "
                                                "the run directory; for a genome file in a run directory or under "
                                                "runs/ its folder, else runs/<stem>/)")
    p.add_argument("--battery", type=count(10**4, "schedules of a battery"), default=None, metavar="N",
                   help="a commanded walker: N random schedules of "
                   "--stretches speeds drawn uniformly in its evolved speed range (or --range), --hold s each, "
                   "straight ahead; every stretch's speed against its command (within 10 %%), 1 s windows inside them, "
                   "falls, its gait at constant commands, and (a walker evolved with stops) a 20 s stop between two "
                   "walks at its slowest, middle and fastest speed; writes <stem>_speed_battery.json")
    p.add_argument("--stretches", type=count(10**4, "stretches of a schedule"), default=6, metavar="K",
                   help="--battery: stretches per schedule (default 6)")
    p.add_argument("--range", dest="speed_range", metavar="LOW,HIGH", help="--battery: the speeds drawn, m/s (default: "
                   "the speed range the walker was evolved for)")
    p.add_argument("--seed", type=seed, default=0, help="--battery: the seed of the schedules (default 0)")
    p.add_argument("--ramp", type=finite_float, default=None, metavar="A",
                   help="the knob speeds up by at most A m/s per s, "
                   "switching elites every second (default 0.1; 0: at once)")
    p.add_argument("--ramp-down", type=finite_float, default=None, metavar="A",
                   help="the knob slows down by at most A m/s per s "
                   "(default 0.2; 0: at once)")
    p.add_argument("--correction", type=finite_float, default=None, metavar="S",
                   help="the knob makes up a shortfall (or excess) in the distance "
                   "walked so far in a stretch within about S s (default 3; 0: no loop, the knob asks for the command "
                   "itself)")
    p.add_argument("--overshoot", type=finite_float, default=None, metavar="F",
                   help="the most the knob may ask above or below the command, "
                   "a fraction of it (default 0.2)")
    p.set_defaults(func=run_gait_cmd)


def run_gait_cmd(args) -> int:
    from pathlib import Path

    if args.u0 is not None or args.go is not None:
        from .gait_levels import run_levels

        return run_levels(args)

    speeds = number_list("--speed", args.speed, MAX_SPEED, "m/s")
    turnings = number_list("--turning", args.turning, MAX_TURNING, "deg/s")
    if not (Path(args.run) / "archive.json").is_file():
        return _run_commanded(args, speeds, turnings)
    if args.json or args.out:
        refuse("--json/--out", "apply to a commanded walker's genome, not to a repertoire")
    return _run_repertoire(args, speeds, turnings)


def _run_repertoire(args, speeds, turnings) -> int:
    import math

    from ...repertoire.elites import load_repertoire
    from ...repertoire.speed import CORRECTION, OVERSHOOT, RAMP, RAMP_DOWN, follow, hysteresis, tracking

    if speeds is None or not all(v > 0 for v in speeds):
        refuse("--speed", f"a repertoire needs positive speeds in m/s, comma-separated, got {args.speed!r}")
    if len(turnings) != 1:
        refuse("--turning", "a repertoire walks at one turning rate")
    turning = turnings[0]
    ramp = RAMP if args.ramp is None else args.ramp
    ramp_down = RAMP_DOWN if args.ramp_down is None else args.ramp_down
    for flag, value in (("--ramp", ramp), ("--ramp-down", ramp_down)):
        if not (math.isfinite(value) and value >= 0):
            refuse(flag, f"must be a finite number >= 0 m/s per s, got {value}")
    correction = CORRECTION if args.correction is None else args.correction
    overshoot = OVERSHOOT if args.overshoot is None else args.overshoot
    if not (math.isfinite(correction) and correction >= 0):
        refuse("--correction", f"must be a finite number >= 0 s, got {args.correction}")
    if not (math.isfinite(overshoot) and 0 <= overshoot < 1):
        refuse("--overshoot", f"must be a fraction in [0, 1), got {args.overshoot}")
    rep = load_repertoire(args.run)
    stretches = follow(rep, speeds, args.hold, turning, ramp=ramp, ramp_down=ramp_down, step=min(1.0, args.hold),
                       correction=correction, overshoot=overshoot)
    a = rep.archive
    t = 0.0
    for s in stretches:
        print(f"{t:5.1f}-{t + args.hold:5.1f} s: commanded {s.commanded:.3f} m/s -> at its end cell "
              f"{a.cell[s.elite, 0]},{a.cell[s.elite, 1]} (archive {s.archive_speed:.3f} m/s): walked {s.measured:.3f} "
              f"m/s ({100 * s.error:.1f} % off)" + ("" if s.up else ", DOWN"))
        t += args.hold
    error, down = tracking(stretches)
    print(f"mean tracking error {100 * error:.1f} % over {len(stretches)} stretches of {args.hold:g} s; "
          + ("no fall" if not down else f"down in {down} stretch(es)"))
    for v, up, dn in hysteresis(stretches):
        cells = [f"{a.cell[s.elite, 0]},{a.cell[s.elite, 1]}" for s in (up, dn)]
        print(f"hysteresis at {v:.3f} m/s: rising {up.measured:.3f} m/s (cell {cells[0]}), falling {dn.measured:.3f} "
              f"m/s (cell {cells[1]})" + ("" if up.up and dn.up else "; down on the way"))
    return 0


def _run_commanded(args, speeds, turnings) -> int:
    """A commanded walker's genome through the commands (``--speed`` m/s, ``--turning`` deg/s, ``--hold`` s each), or
    its own nominal schedule: a line per stretch (or JSON), <stem>_command.json and <stem>_command.png."""
    import json
    import math
    from pathlib import Path

    from ...analysis.commanded import check_commanded, follow_commands, nominal_plan, plan, stretch_line
    from ...core.fileio import write_json
    from ...record.png.command_figure import command_figure
    from ...record.source import resolve

    for flag in ("ramp", "ramp_down", "correction", "overshoot"):
        if getattr(args, flag) is not None:
            refuse(f"--{flag.replace('_', '-')}", "applies to a repertoire's speed knob, not to a commanded walker")
    source = resolve(args.run)
    check_commanded(source.config, str(source.genome_path))
    out = Path(args.out) if args.out else source.outputs
    if out.exists() and not out.is_dir():
        refuse("--out", f"{out} exists and is not a directory")
    if args.battery is not None:
        if args.speed is not None or turnings != [0.0]:
            refuse("--battery", "draws its own speeds, straight ahead: give it without --speed and --turning")
        return _run_battery(args, source, out)
    if speeds is None:
        if turnings != [0.0]:
            refuse("--turning", "needs --speed (without it the walker follows its own nominal schedule)")
        times, speeds, turnings, seconds = nominal_plan(source.config, args.hold)
        notes = [f"no --speed: the walker follows its own nominal schedule ({len(speeds)} stretches, {seconds:g} s)"]
    else:
        speeds, turnings, notes = plan(source.config, speeds, [math.radians(w) for w in turnings])
        times, seconds = [i * args.hold for i in range(len(speeds))], args.hold * len(speeds)
    report = follow_commands(source.config, source.genome, times, speeds, turnings, seconds)
    report.update(source=str(source.genome_path), notes=notes)
    from ...files.rundir.output_set import output_set

    out.mkdir(parents=True, exist_ok=True)
    stem = f"{source.genome_path.stem}_command" if source.run_dir is None else f"{source.label}_command"
    title = f"{source.name}: commanded and walked speed and turning rate"
    with output_set("gait", [out / f"{stem}.json", out / f"{stem}.png"], say=note):  # no new JSON beside an old PNG
        write_json(out / f"{stem}.json", report)
        png = command_figure(report, out / f"{stem}.png", title=title)
    if args.json:
        print(json.dumps({k: v for k, v in report.items() if k != "trace"}, default=lambda v: None))
        return 0
    for line in notes:
        print(line)
    for s in report["stretches"]:
        print(stretch_line(s))
    done = [s for s in report["stretches"] if s["speed_error_pct"] is not None and not s["down"]]
    mean = (f"mean speed error {sum(s['speed_error_pct'] for s in done) / len(done):.1f} % over {len(done)} walking "
            "stretches; " if done else "")
    print(mean + ("no fall" if not report["fell"] else f"fell at {report['end_time']:.1f} s"))
    print(f"results: {out / (stem + '.json')}\nfigure: {png}")
    return 0


def _run_battery(args, source, out) -> int:
    """``--battery N``: the speed battery of :mod:`evobiped.analysis.speed_battery`, a line per schedule, a summary, the
    gait at constant commands, and <stem>_speed_battery.json."""
    import json

    from ...analysis.gait_report import gait_line
    from ...analysis.speed_battery import gait_at_speeds, speed_battery, stop_and_go
    from ...core.fileio import write_json
    from ...tasks.command_schedule import trained_range

    if args.battery * args.stretches > MAX_STRETCHES:
        refuse("--battery/--stretches", f"{args.battery} schedules of {args.stretches} stretches are "
               f"{args.battery * args.stretches:,} stretches; a battery runs at most {MAX_STRETCHES:,}")
    (lo, hi), stops, _ = trained_range(source.config.task_options)
    if args.speed_range is not None:
        pair = number_list("--range", args.speed_range, MAX_SPEED, "m/s")
        if len(pair) != 2 or not 0 < pair[0] <= pair[1]:
            refuse("--range", f"expected LOW,HIGH m/s with 0 < LOW <= HIGH, got {args.speed_range!r}")
        if pair[0] < lo - 1e-9 or pair[1] > hi + 1e-9:
            print(f"note: --range {pair[0]:g}-{pair[1]:g} m/s is beyond the {lo:g}-{hi:g} m/s this walker was evolved "
                  "for; the commands are clipped to it")
        lo, hi = max(pair[0], lo), min(pair[1], hi)
    if not 0 < lo <= hi:
        refuse("--battery", f"the walker was evolved for no walking speed range ({lo:g}-{hi:g} m/s); give --range")
    report = speed_battery(source.config, source.genome, n=args.battery, stretches=args.stretches, stretch=args.hold,
                           low=lo, high=hi, seed=args.seed,
                           progress=None if args.json else lambda i, n: print(f"schedule {i} of {n} done", flush=True))
    speeds = [v for v in (0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8) if lo - 1e-9 <= v <= hi + 1e-9]
    report["gait"] = gait_at_speeds(source.config, source.genome, speeds)
    report["stop_and_go"] = stop_and_go(source.config, source.genome, [lo, (lo + hi) / 2, hi]) if stops else []
    report["source"] = str(source.genome_path)
    from ...files.rundir.output_set import output_set

    out.mkdir(parents=True, exist_ok=True)
    stem = f"{source.genome_path.stem}_speed_battery" if source.run_dir is None else f"{source.label}_speed_battery"
    with output_set("gait battery", [out / f"{stem}.json"], say=note):  # its temporaries swept, a cut-short one said
        write_json(out / f"{stem}.json", report)
    if args.json:
        print(json.dumps({k: v for k, v in report.items() if k != "schedules"}, default=lambda v: None))
        return 0
    for i, r in enumerate(report["schedules"]):
        errs = " ".join(f"{s['commanded']:.2f}->{s['walked']:.2f}" if s["walked"] is not None
                        else f"{s['commanded']:.2f}->down"
                        for s in r["stretches"])
        print(f"schedule {i:2d}: {errs}  " + ("passed" if r["passed"] else f"FELL at {r['end_time']:.1f} s" if r["fell"]
                                              else f"{sum(not s['within'] for s in r['stretches'])} stretch(es) off"))
    m = report["summary"]
    se, we = m["stretch_error_pct"], m["window_error_pct"]
    print(f"{m['no_fall']} of {m['schedules']} schedules without a fall; {m['passed']} with every stretch within "
          f"{100 * report['tolerance']:g} %; {m['within']} of {m['stretches']} stretches within; stretch error median "
          f"{se['median']:.1f} %, p90 {se['p90']:.1f} %, max {se['max']:.1f} %; {report['window']:g} s windows median "
          f"{we['median']:.1f} %, p90 {we['p90']:.1f} %")
    for g in report["gait"]:
        print(f"gait at {g['commanded']:.1f} m/s: {gait_line(g)}; "
              + ("a walk" if g["walks"] else "not a walk: " + ", ".join(g["failed"])))
    for g in report["stop_and_go"]:
        stopped = f"stopped {g['time_to_stop']:g} s after the command" if g[
            "time_to_stop"] is not None else "never stopped"
        print(f"stop and go from {g['speed']:.2f} m/s: " + (f"FELL at {g['end_time']:.1f} s" if g["fell"] else
              f"{stopped}, {g['stop_speed']:+.3f} m/s over the stop's second half (both feet down "
              f"{100 * g['double_support']:.0f} % of it), drifted {g['drift']:+.2f} m in 20 s, walked off at "
              f"{g['walk_off']:.2f} m/s"))
    print(f"results: {out / (stem + '.json')}")
    return 0


SUBCOMMANDS = (add_gait,)
