"""``evobiped g3``: the G3 gait generator (Pribe et al. 1997) at GO levels; the gait table and diagrams."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ...flags import finite_float, note, positive_float, refuse, within


def add_g3(sub) -> None:
    p = sub.add_parser("g3", help="run the G3 gait generator (Pribe et al. 1997) at GO levels; gait table and PNGs")
    from .network import PRESETS

    p.add_argument("preset", nargs="?", help=f"parameter set: {', '.join(PRESETS)} (not with --reproduce)")
    lv = p.add_mutually_exclusive_group()
    lv.add_argument("--go", type=finite_float, nargs="+", metavar="I", help="GO level(s) (default: the preset's)")
    lv.add_argument("--sweep", type=finite_float, nargs=3, metavar=("START", "STOP", "STEP"),
                    help="GO levels START..STOP (inclusive)")
    p.add_argument("--continue", dest="mode", action="store_const", const="continue", default="reset",
                   help="one run through the levels keeping the state (default: reset to zero per level)")
    p.add_argument("--from-go", type=finite_float, metavar="I0",
                   help="start every run at I0 and switch at --switch-at (Figs. 8B, 10)")
    p.add_argument("--switch-at", type=positive_float, help="time of the switch from --from-go (default 30; only with "
                                                            "--from-go)")
    p.add_argument("--t-run", type=positive_float, help="time units per level (default: the preset's, 120)")
    p.add_argument("--dt", type=positive_float, default=0.005, help="RK4 step in model time units (default 0.005)")
    p.add_argument("--channels", help="channels drawn in the diagrams, names or 0-3 (default all: LF,RF,LH,RH; only "
                                      "with --out)")
    p.add_argument("--out", metavar="DIR", help="write PNG gait diagrams and the frequency plot here")
    p.add_argument("--json", action="store_true", help="print machine-readable JSON")
    p.add_argument("--reproduce", metavar="DIR",
                   help="check the paper claim by claim: write summary.json, one CSV per sweep and "
                   "the figures into DIR (made if missing) and print the numbers docs/g3.md quotes; no PRESET, only "
                   "--step and --t-run go with it")
    p.add_argument("--step", type=within(1e-3, 1, "", "a sweep of at most some thousand levels"),
                   help="with --reproduce: GO increment of its sweeps (default 0.01, the paper's)")
    p.set_defaults(func=run_g3_cmd)
    _DEFAULTS.update(vars(p.parse_args([])))


#: the most GO levels one sweep runs (the paper's sweeps: 0.01 apart, some hundreds)
MAX_LEVELS = 10**4
_DEFAULTS: dict = {}  # every flag's default, to name the flags given with --reproduce
_FLAG = {"preset": "PRESET", "mode": "--continue"}


def _run_reproduce(args) -> int:
    from pathlib import Path

    from ...core.errors import UserError

    given = [k for k, v in _DEFAULTS.items() if k not in ("reproduce", "step", "t_run", "func")
             and getattr(args, k) != v]
    if given:
        refuse("/".join(_FLAG.get(k, "--" + k.replace("_", "-")) for k in given),
               "--reproduce runs the paper's own presets and levels; only --step and --t-run go with it")
    try:
        Path(args.reproduce).mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise UserError(f"--reproduce: cannot make the folder {args.reproduce}: {e.strerror}") from None
    from .g3_reproduce import reproduce_g3

    step, t_run = 0.01 if args.step is None else args.step, 200.0 if args.t_run is None else args.t_run
    reproduce_g3(args.reproduce, step=step, t_run=t_run, say=note)
    return 0


def run_g3_cmd(args) -> int:
    from . import network as g3
    from .simulation import go_sweep
    from ...core.errors import ConfigError

    if args.reproduce is not None:
        return _run_reproduce(args)
    if args.step is not None:
        refuse("--step", "it spaces the sweeps of --reproduce; give --sweep START STOP STEP for a preset's levels")
    if args.preset is None:
        raise ConfigError(f"g3: give a PRESET ({', '.join(g3.PRESETS)}) or --reproduce DIR")
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
    if args.out and Path(args.out).exists() and not Path(args.out).is_dir():
        refuse("--out", f"{args.out} exists and is not a directory")
    if args.channels is not None and not args.out:
        refuse("--channels", "it picks the channels of the diagrams; give --out DIR to draw them")
    if args.sweep:
        a, b, step = args.sweep
        if not step > 0 or b < a:
            raise ConfigError("--sweep needs START <= STOP and STEP > 0")
        if (b - a) / step + 1 > MAX_LEVELS:
            raise ConfigError(f"--sweep {a:g} {b:g} {step:g} gives {(b - a) / step + 1:,.0f} GO levels; a sweep runs "
                              f"at most {MAX_LEVELS:,} (each a run of --t-run time units)")
        levels = np.round(np.arange(a, b + step / 2, step), 10)
    else:
        levels = np.array(args.go if args.go else pre.go, float)
    if (levels < 0).any():
        raise ConfigError(f"GO levels must be >= 0, got {levels.min():g}")
    if args.from_go is not None and args.from_go < 0:
        raise ConfigError(f"--from-go: a GO level must be >= 0, got {args.from_go:g}")
    s = go_sweep(pre, levels, mode=args.mode, t_run=args.t_run, from_go=args.from_go, switch_at=switch_at, dt=args.dt)
    rows = [{"go": float(lv), **g.as_dict()} for lv, g in zip(s.levels, s.gaits)]
    files = []
    if args.out:
        from ...files.rundir.output_set import output_set
        from .g3_figures import sweep_figures, sweep_files

        stem = f"g3_{pre.name}"
        title = f"G3 {pre.name} ({args.mode})"
        with output_set(f"g3 {pre.name}", sweep_files(Path(args.out), stem), say=note):  # no old run beside new plots
            files = [str(f) for f in sweep_figures(args.out, stem, s, idx, g3.LIMBS, title=title)]
    if args.json:
        print(json.dumps({"preset": pre.name, "source": pre.source, "mode": args.mode, "levels": rows, "files": files}))
        return 0
    print(f"G3 {pre.name}: {pre.source}; {args.mode}"
          + (f" from I = {args.from_go:g} at t = {switch_at:g}" if args.from_go is not None else ""))
    print(f"{'I':>6} {'gait':<7} {'seq':<8} {'freq':>7} {'period':>7}  {'phases LF RF LH RH':<23} {'up':>5} "
          f"{'first':<7} {'settle':>6}")
    for r in rows:
        ph = " ".join(f"{p:.2f}" if np.isfinite(p) else "  - " for p in r["phases"])
        print(f"{r['go']:6.3f} {r['label']:<7} {r['sequence']:<8} {r['frequency']:7.4f} {r['period']:7.3f}  {ph:<23} "
              f"{np.mean(r['duty']):5.3f} {r['transient_label']:<7} {r['settle_time']:6.1f}")
    print("up: mean fraction of the cycle a channel is above threshold (its limb off the ground; 1 - the duty factor)")
    for f in files:
        print(f"wrote {f}")
    return 0


SUBCOMMANDS = (add_g3,)
