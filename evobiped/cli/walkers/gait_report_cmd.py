"""``evobiped gait-report``: a stored walker's gait measured as a gait lab would, and whether it walks."""

from __future__ import annotations

import json
import math

from ...flags import add_stored_walker, check_output_file, note, unfinished_note


def add_gait_report(sub) -> None:
    p = sub.add_parser("gait-report", help="a walker's gait: duty factors, flight, steps, slip, clearance, power, cost "
                                           "of transport, and whether it meets the walking criteria")
    add_stored_walker(p, metavar="GENOME|RUN", nargs="+", also="; several: one row each (with --table)")
    p.add_argument("--seconds", type=float, default=20.0, metavar="S", help="measure the first S s of the nominal "
                   "episode (default 20)")
    p.add_argument("--up-for", type=float, metavar="S", help="then let it walk on to S s: 'up' means it stood that "
                                                             "long (the walking criteria's 200 s)")
    p.add_argument("--figure", metavar="PNG", help="also draw its footfall diagram (stance bars per foot over time) "
                                                   "here")
    p.add_argument("--json", action="store_true", help="print the report as JSON (the stance episodes included; a list "
                   "for several sources)")
    p.add_argument("--table", action="store_true",
                   help="print one Markdown table row per source (the docs' gait table)")
    p.set_defaults(func=run_gait_report_cmd)


def run_gait_report_cmd(args) -> int:
    from pathlib import Path

    from ...analysis.gait_report import WALKING, criteria_words, gait_report
    from ...physics.gait_lab import similar_step
    from ...core.errors import UserError
    from ...record.source import resolve

    for flag, v in (("--seconds", args.seconds), ("--up-for", args.up_for)):
        if v is not None and not (math.isfinite(v) and 0 < v <= 1e5):
            raise UserError(f"{flag} must be a finite number of seconds in (0, 1e5], got {v:g}")
    if args.up_for is not None and args.up_for < args.seconds:
        raise UserError(f"--up-for ({args.up_for:g} s) must be at least --seconds ({args.seconds:g} s)")
    if args.figure is not None and Path(args.figure).suffix.lower() != ".png":
        raise UserError(f"--figure must name a .png file, got {args.figure}")
    if args.figure is not None:
        check_output_file("--figure", args.figure)
    if len(args.source) > 1 and not (args.table or args.json):
        raise UserError("several sources need --table or --json")
    if len(args.source) > 1 and args.figure is not None:
        raise UserError("--figure draws one walker: give one source")
    sources = [resolve(s, args.generation, args.allow_unfinished) for s in args.source]  # all checked before any runs
    for source in sources:
        unfinished_note(source)
    reports = []
    if args.table:
        print(TABLE_HEAD, flush=True)
    for source in sources:
        report = gait_report(source.config, source.genome, seconds=args.seconds, up_for=args.up_for)
        report["source"] = str(source.genome_path)
        if source.unfinished is not None:
            report["unfinished_run"] = source.unfinished
        reports.append(report)
        if args.table:
            print(table_row(source.label, report), flush=True)
    if args.figure is not None:
        from ...files.rundir.output_set import output_set
        from ...record.png.footfall_figure import footfall_figure

        with output_set("gait-report", [Path(args.figure)], say=note):  # its temporaries swept, a cut-short one said
            footfall_figure(reports[0], Path(args.figure), title=sources[0].label)
    if args.json:
        print(json.dumps(reports[0] if len(reports) == 1 else reports, indent=1, default=lambda v: None))
    if args.json or args.table:
        return 0
    report, source = reports[0], sources[0]
    feet = report["feet"]
    rows = [("up", f"{report['up']} ({report.get('up_for', report['seconds']):g} s)"),
            ("speed", f"{report['speed']:.3f} m/s over {report['time_up']:.1f} s, Froude {report['froude']:.3f}"),
            ("direction", "did not move" if report["heading_deg"] is None else f"{report['heading_deg']:+.1f} deg"),
            ("duty factor", " / ".join(f"{f} {report[f'duty_{f}']:.3f}" for f in feet)
             + f" (asymmetry {report['duty_asymmetry']:.3f})"),
            ("airborne", f"{100 * report['airborne']:.1f} % of the time (double support "
                         f"{100 * report['double_support']:.1f} %)"),
            ("steps", f"{report['steps_per_s']:.2f} per s, {report['step_length']:.3f} m each"),
            ("stride", f"steps {report['step_leg']:.2f} leg lengths ({report['leg_length']:.2f} m legs), "
             f"{report['step_similar']:.2f} of the {similar_step(report['speed'], report['leg_length']):.2f} m step "
             f"dynamic similarity predicts{': a shuffle' if report['shuffle'] else ''}"),
            ("stance slip", f"median {report['slip']:.3f} m/s, {100 * report['slip_share']:.1f} % of the speed; 90th "
             f"percentile {100 * report['slip_p90_share']:.1f} %; {100 * report['slide_per_m']:.1f} cm slid per m "
             "walked"),
            ("swing",
             f"peak foot clearance {report['clearance']:.3f} m, knee excursion {report['knee_swing']:.2f} rad"),
            ("power", f"{report['power']:.1f} W/kg positive, cost of transport {report['cost_of_transport']:.2f}, "
             f"torque cost {report['torque_cost']:.0f} N^2 m^2/kg "
             f"({report['torque_cost'] / max(report['speed'], 1e-3):.0f} per m/s)")]
    print(f"gait of {source.genome_path} (first {args.seconds:g} s of its nominal episode, read after every "
          f"{1000 * report['sample_dt']:g} ms physics step)")
    for k, v in rows:
        print(f"  {k:<12} {v}")
    bounds = ", ".join(f"{k} {how.replace('abs', '|x| ')} {b:g}" for k, (how, b, _) in WALKING.items())
    print(f"walks: {'yes' if report['walks'] else 'no: ' + criteria_words(report['failed'])}  (criteria: up, {bounds})")
    return 0


#: the columns of :func:`table_row`
TABLE_HEAD = ("| walker | up | speed (m/s) | duty L / R | airborne | steps/s | step (m) | step / similar | slip (% of "
              "speed; 90th pct) | slid (cm/m) | clearance (m) | W/kg | CoT | walks? |\n"
              "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")


def table_row(name: str, r: dict) -> str:
    """One walker's gait as a row under :data:`TABLE_HEAD`."""
    duty = " / ".join(f"{r[f'duty_{f}']:.2f}" for f in ("left", "right") if f"duty_{f}" in r)
    verdict = "yes" if r["walks"] else "no: " + ", ".join(r["failed"])
    return (f"| `{name}` | {r.get('up_for', r['seconds']):g} s {'up' if r['up'] else 'fell'} | {r['speed']:.2f} | "
            f"{duty} | {100 * r['airborne']:.1f} % | {r['steps_per_s']:.1f} | {r['step_length']:.2f} "
            f"| {r['step_similar']:.2f}{' shuffle' if r['shuffle'] else ''} "
            f"| {100 * r['slip_share']:.0f}; {100 * r['slip_p90_share']:.0f} | {100 * r['slide_per_m']:.1f} "
            f"| {r['clearance']:.3f} | {r['power']:.0f} | {r['cost_of_transport']:.2f} | {verdict} |")


SUBCOMMANDS = (add_gait_report,)
