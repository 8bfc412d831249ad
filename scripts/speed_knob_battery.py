"""The speed knob over many schedules: how often every 10 s window is within 10 % of its command with no fall.

Random schedules of ``--stretches`` speeds drawn uniformly from [LOW, HIGH] m/s (``--schedules`` of them,
seeded), plus any given with ``--schedule``; each followed by :func:`evobiped.repertoire.speed.follow` with the
given loop settings::

    python scripts/speed_knob_battery.py docs/repertoire --range 0.21,0.63 [--schedules 30] [--correction 3]
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

from evobiped.core.errors import UserError
from evobiped.repertoire.elites import load_repertoire
from evobiped.repertoire.speed import CORRECTION, OVERSHOOT, RAMP, RAMP_DOWN, follow

TOLERANCE = 0.10


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("run")
    p.add_argument("--range", default="0.21,0.63", help="LOW,HIGH m/s of the random schedules")
    p.add_argument("--schedules", type=int, default=30)
    p.add_argument("--stretches", type=int, default=6)
    p.add_argument("--schedule", action="append", default=[], metavar="V,V,...", help="a schedule to add")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--hold", type=float, default=10.0)
    p.add_argument("--ramp", type=float, default=RAMP)
    p.add_argument("--ramp-down", type=float, default=RAMP_DOWN)
    p.add_argument("--correction", type=float, default=CORRECTION)
    p.add_argument("--overshoot", type=float, default=OVERSHOOT)
    a = p.parse_args(argv)
    low, high = (float(x) for x in a.range.split(","))
    rng = np.random.default_rng(a.seed)
    schedules = [[float(x) for x in s.split(",")] for s in a.schedule]
    schedules += [list(np.round(rng.uniform(low, high, a.stretches), 2)) for _ in range(a.schedules)]
    try:
        rep = load_repertoire(a.run)
        met = fell = 0
        worst = []
        for speeds in schedules:
            out = follow(rep, speeds, a.hold, ramp=a.ramp, ramp_down=a.ramp_down, correction=a.correction,
                         overshoot=a.overshoot)
            down = not all(s.up for s in out)
            err = max(s.error for s in out)
            ok = not down and err <= TOLERANCE
            met, fell = met + ok, fell + down
            worst.append(err)
            print(f"{','.join(f'{v:g}' for v in speeds)}: walked {' '.join(f'{s.measured:.3f}' for s in out)}; "
                  f"worst window {100 * err:.1f} % off" + (", FELL" if down else "") + (" - met" if ok else ""),
                  flush=True)
    except UserError as e:
        print(f"speed_knob_battery: error: {e}", file=sys.stderr)
        return 2
    print(f"{met} of {len(schedules)} schedules had every window within {100 * TOLERANCE:g} % and no fall; {fell} "
          f"fell; median worst window {100 * float(np.median(worst)):.1f} %")
    return 0


if __name__ == "__main__":
    sys.exit(main())
