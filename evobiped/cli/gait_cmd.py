"""``evobiped gait``: a speed knob over a map-elites run's gait repertoire (one commanded speed, or a schedule)."""

from __future__ import annotations

from ..flags import positive_float, refuse


def add_gait(sub) -> None:
    p = sub.add_parser("gait", help="walk at a commanded speed (or a schedule of speeds) with the nearest gaits of a map-elites run's archive")
    p.add_argument("run", metavar="RUN", help="a map-elites run directory (its archive.json)")
    p.add_argument("--speed", metavar="V[,V...]", required=True,
                   help="commanded mean forward speed in m/s; several, comma-separated: a schedule, --hold s each, elites switched on the fly")
    p.add_argument("--turning", type=float, default=0.0, metavar="W", help="commanded turning rate in deg/s, + left (default 0)")
    p.add_argument("--hold", type=positive_float, default=10.0, metavar="S", help="seconds each speed is held (default 10)")
    p.add_argument("--ramp", type=float, default=None, metavar="A", help="the knob speeds up by at most A m/s per s, "
                   "switching elites every second (default 0.1; 0: at once)")
    p.add_argument("--ramp-down", type=float, default=None, metavar="A", help="the knob slows down by at most A m/s per s "
                   "(default 0.2; 0: at once)")
    p.add_argument("--correction", type=float, default=None, metavar="S", help="the knob makes up a shortfall (or excess) in the distance "
                   "walked so far in a stretch within about S s (default 3; 0: no loop, the knob asks for the command itself)")
    p.add_argument("--overshoot", type=float, default=None, metavar="F", help="the most the knob may ask above or below the command, "
                   "a fraction of it (default 0.2)")
    p.set_defaults(func=run_gait_cmd)


def run_gait_cmd(args) -> int:
    import math

    from ..repertoire.elites import load_repertoire
    from ..repertoire.speed import CORRECTION, OVERSHOOT, RAMP, RAMP_DOWN, follow, hysteresis, tracking

    try:
        speeds = [float(v) for v in args.speed.split(",")]
    except ValueError:
        speeds = []
    if not speeds or not all(math.isfinite(v) and v > 0 for v in speeds):
        refuse("--speed", f"expected positive speeds in m/s, comma-separated, got {args.speed!r}")
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
    stretches = follow(rep, speeds, args.hold, args.turning, ramp=ramp, ramp_down=ramp_down, step=min(1.0, args.hold),
                       correction=correction, overshoot=overshoot)
    a = rep.archive
    t = 0.0
    for s in stretches:
        print(f"{t:5.1f}-{t + args.hold:5.1f} s: commanded {s.commanded:.3f} m/s -> at its end cell {a.cell[s.elite, 0]},{a.cell[s.elite, 1]} "
              f"(archive {s.archive_speed:.3f} m/s): walked {s.measured:.3f} m/s ({100 * s.error:.1f} % off)" + ("" if s.up else ", DOWN"))
        t += args.hold
    error, down = tracking(stretches)
    print(f"mean tracking error {100 * error:.1f} % over {len(stretches)} stretches of {args.hold:g} s; "
          + ("no fall" if not down else f"down in {down} stretch(es)"))
    for v, up, dn in hysteresis(stretches):
        cells = [f"{a.cell[s.elite, 0]},{a.cell[s.elite, 1]}" for s in (up, dn)]
        print(f"hysteresis at {v:.3f} m/s: rising {up.measured:.3f} m/s (cell {cells[0]}), falling {dn.measured:.3f} m/s "
              f"(cell {cells[1]})" + ("" if up.up and dn.up else "; down on the way"))
    return 0


SUBCOMMANDS = (add_gait,)
