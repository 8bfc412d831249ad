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
    p.add_argument("--ramp", type=float, default=0.1, metavar="A", help="the knob moves towards a new speed by at most A m/s per s, "
                   "switching elites every second (default 0.1; 0: at once)")
    p.set_defaults(func=run_gait_cmd)


def run_gait_cmd(args) -> int:
    import math

    from ..repertoire.elites import load_repertoire
    from ..repertoire.speed import follow, hysteresis, tracking

    try:
        speeds = [float(v) for v in args.speed.split(",")]
    except ValueError:
        speeds = []
    if not speeds or not all(math.isfinite(v) and v > 0 for v in speeds):
        refuse("--speed", f"expected positive speeds in m/s, comma-separated, got {args.speed!r}")
    if not (math.isfinite(args.ramp) and args.ramp >= 0):
        refuse("--ramp", f"must be a finite number >= 0 m/s per s, got {args.ramp}")
    rep = load_repertoire(args.run)
    stretches = follow(rep, speeds, args.hold, args.turning, ramp=args.ramp, step=min(1.0, args.hold))
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
