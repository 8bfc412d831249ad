"""``evobiped taga``: the Taga biped walked by its rhythm generator (Taga et al. 1991): gait metrics, pushes, a genome
file."""

from __future__ import annotations

import json

import numpy as np

from ...core.errors import UserError
from ...flags import check_output_file, finite_float, note, positive_float, refuse, within
from ...core.progress import Progress


def add_taga(sub) -> None:
    p = sub.add_parser("taga", help="run the Taga biped with its rhythm generator (Taga et al. 1991); gait metrics "
                                    "table")
    p.add_argument("--u0", type=finite_float, nargs="+", default=[5.5], metavar="U",
                   help="tonic input(s) u0, one walker each (default 5.5)")
    from .parameters import PRESETS

    p.add_argument("--preset", default="taga", help=f"rhythm-generator parameters: {', '.join(PRESETS)} (default taga: "
                                                    "Appendix D)")
    p.add_argument("--seconds", type=positive_float, help="simulated time in s from Appendix E's initial state "
                                                          "(default 20; not with --push)")
    p.add_argument("--window", type=positive_float,
                   help="metrics over the last WINDOW s, at most --seconds (default 10; not with --push)")
    p.add_argument("--slope", type=finite_float, default=0.0, metavar="PCT",
                   help="terrain slope in %% (uphill > 0; default 0)")
    p.add_argument("--slope-start", type=finite_float, default=0.0, metavar="X",
                   help="x (m) where the slope begins (default 0)")
    p.add_argument("--kg", type=positive_float, default=1e4, help="ground stiffness N/m (default 1e4)")
    p.add_argument("--bg", type=finite_float, default=1e3, help="ground damping N s/m (default 1e3)")
    p.add_argument("--timestep", type=positive_float, default=0.0005, help="physics step in s (default 0.0005)")
    p.add_argument("--push", choices=("leg", "hip"), help="Fig. 7: after 10 s push the right shank (200 N) or the hip "
                                                          "(288 N) forward for 0.2 s")
    p.add_argument("--push-force", type=within(0, 1e4, "N", "a push beyond 10 kN throws any biped"),
                   help="push force in N (default 200 leg, 288 hip; only with --push)")
    p.add_argument("--push-delay", type=within(0, 2, "s", "the schedule waits 2 s for the lift-off"),
                   help="push this many s after the right foot lifts off (default 0.05; only with --push)")
    p.add_argument("--save-genome", metavar="FILE.json", help="also write the genome file of the (first) walker, for "
                                                              "evobiped replay")
    p.add_argument("--json", action="store_true", help="print machine-readable JSON")
    p.add_argument("--quiet", action="store_true", help="no progress lines")
    p.add_argument("--reproduce", metavar="DIR", help="run every experiment of the paper with its published parameters "
                                                      "and write taga_results.json, summary.md and the figures (Figs. "
                                                      "5-11) into DIR (made if missing); only --quick and --quiet go "
                                                      "with it")
    p.add_argument("--quick", action="store_true",
                   help="with --reproduce: coarser grids in every part, to check the pipeline, not the numbers")
    p.set_defaults(func=run_taga_cmd)
    _DEFAULTS.update(vars(p.parse_args([])))


#: the longest simulated time of a run, s
MAX_SECONDS = 3600.0
_DEFAULTS: dict = {}  # every flag's default, to name the flags given with --reproduce


def _run_reproduce(args) -> int:
    from pathlib import Path

    given = [k for k, v in _DEFAULTS.items() if k not in ("reproduce", "quick", "quiet", "func")
             and getattr(args, k) != v]
    if given:
        refuse("/".join("--" + k.replace("_", "-") for k in given), "--reproduce runs the paper's own experiments and "
                                                                    "settings; only --quick and --quiet go with it")
    try:
        Path(args.reproduce).mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise UserError(f"--reproduce: cannot make the folder {args.reproduce}: {e.strerror}") from None
    from .taga_reproduce import reproduce_taga

    reproduce_taga(args.reproduce, quick=args.quick, quiet=args.quiet, say=note)
    return 0


def _nan_to_null(row: dict) -> dict:
    """A metrics row for strict JSON: non-finite floats become null."""
    return {k: (None if isinstance(v, float) and not np.isfinite(v) else v) for k, v in row.items()}


def run_taga_cmd(args) -> int:
    from ...bodies import TagaBiped
    from ...controllers.matsuoka import MatsuokaOptions
    from . import protocols
    from .parameters import PRESETS, preset_genome
    from ...core.options import check_value, option_bounds
    from ...core.validate import number

    if args.reproduce is not None:
        return _run_reproduce(args)
    if args.quick:
        refuse("--quick", "it coarsens the grids of --reproduce; give --reproduce DIR")
    if args.preset not in PRESETS:
        raise UserError(f"unknown preset {args.preset!r} (choose from {', '.join(PRESETS)})")
    for u in args.u0:
        check_value(MatsuokaOptions, "u0", u, "--u0")
    low, high = option_bounds(TagaBiped.Options, "slope")  # the body's declared limit, in % here
    number(args.slope, "--slope", low=100 * low, high=100 * high, unit="%")
    for flag in ("kg", "bg", "timestep", "slope_start"):
        check_value(TagaBiped.Options, flag, getattr(args, flag), f"--{flag.replace('_', '-')}")
    seconds = 20.0 if args.seconds is None else args.seconds
    number(seconds, "--seconds", high=MAX_SECONDS, unit="s (an hour of walking; the paper's runs: 20 s)")
    window = min(10.0, seconds) if args.window is None else args.window
    if args.push:
        if args.seconds is not None or args.window is not None:
            refuse("--seconds/--window", "--push runs its own schedule (10 s, the push, 8 s more) and reports strides, "
                                         "not a window")
    else:
        if args.push_force is not None or args.push_delay is not None:
            refuse("--push-force/--push-delay", "they shape the push; give --push leg or --push hip")
        if window > seconds:
            refuse("--window", f"the metrics window ({window:g} s) cannot be longer than the simulated --seconds "
                               f"({seconds:g} s)")
    opts = dict(preset=args.preset, timestep=args.timestep, kg=args.kg, bg=args.bg, slope=args.slope / 100,
                slope_start=args.slope_start)
    total = 10.0 + 2.0 + 0.2 + 8.0 if args.push else seconds
    progress = Progress("taga", total, "s simulated", quiet=args.quiet or args.json)
    if args.save_genome:
        check_output_file("--save-genome", args.save_genome)
        from ...episode import EpisodeConfig
        from ...files.genome_file import save_genome

        body = {k: v for k, v in opts.items() if k != "preset"}
        cfg = EpisodeConfig(body="taga", controller="matsuoka", seconds=seconds, body_options=body,
                            controller_options={"u0": args.u0[0]})
        save_genome(args.save_genome, preset_genome(cfg.build().controller, args.preset), cfg, preset=args.preset)
    if args.push:
        if len(args.u0) != 1:
            raise UserError("--push takes one --u0 value")
        force = args.push_force if args.push_force is not None else (200.0 if args.push == "leg" else 288.0)
        target = "right_shank" if args.push == "leg" else "hip"
        delay = 0.05 if args.push_delay is None else args.push_delay
        _, (s,) = protocols.push(target, force, [delay], u0=args.u0[0], progress=progress.update, **opts)
        progress.finish()
        if args.json:
            print(json.dumps(_nan_to_null(s), allow_nan=False))
            return 0
        if s["t_push"] is None:
            print(f"push {target} {force:g} N (u0 = {args.u0[0]:g}): not given, the walker fell at {s['fell_at']:.2f} "
                  "s, before the push")
            return 0
        print(f"push {target} {force:g} N for 0.2 s at t = {s['t_push']:.2f} s (u0 = {args.u0[0]:g}): "
              + (f"fell at {s['fell_at']:.2f} s" if s["fell"]
                 else f"recovered after {s['strides_to_recover']} strides"))
        print(f"before: stride {s['stride_length_before']:.3f} m, cycle {s['cycle_duration_before']:.3f} s")
        for i, (L, D) in enumerate(s["strides_after"]):
            print(f"  stride {i + 1:2d} after: {L:.3f} m  {D:.3f} s")
        return 0
    _, rows = protocols.steady(args.u0, seconds=seconds, window=window, progress=progress.update, **opts)
    progress.finish()
    if args.json:
        settings = {**{k: v for k, v in vars(args).items() if k not in ("func", "reproduce", "quick")},
                    "seconds": seconds, "window": window}
        print(json.dumps({"settings": settings, "walkers": [_nan_to_null(r) for r in rows]}, allow_nan=False))
        return 0
    print(f"Taga biped, preset {args.preset}, slope {args.slope:g} %, kg {args.kg:g}, bg {args.bg:g}; "
          f"metrics over the last {window:g} of {seconds:g} s")
    print(f"{'u0':>6} {'gait':<6} {'fell at':>7} {'strides':>7} {'stride m':>8} {'cycle s':>7} {'speed':>6} "
          f"{'double':>6} {'flight':>6} {'hip min-max m':>14}")
    for r in rows:
        fell = f"{r['fell_at']:.2f}" if r["fell"] else "-"
        print(f"{r['u0']:6.2f} {r['gait']:<6} {fell:>7} {r['strides']:7d} {r['stride_length']:8.3f} "
              f"{r['cycle_duration']:7.3f} {r['speed']:6.3f} {r['double_support']:6.3f} {r['flight']:6.3f} "
              f"{r['hip_min']:6.3f}-{r['hip_max']:.3f}")
    return 0


SUBCOMMANDS = (add_taga,)
