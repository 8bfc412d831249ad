"""Steering to sources a walker never heard: per source, when it first came within reach, its final distance, whether it
fell, and how long it stayed up after arriving.

    python scripts/steer_check.py GENOME.json [--seconds 80] [--reach 0.5] [--source X Y ...]

Default sources: 15 positions at bearings -60, -30, 0, 30, 60 deg from the initial facing, 6, 10 and 14 m away
(none a training source of the shipped steering presets; the list docs/steering.md tests every steering walker on).
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

from evobiped.files.genome_file import load_genome
from evobiped.tasks.sound import with_sources

TEST_SOURCES = [(r * np.cos(np.radians(b)), r * np.sin(np.radians(b))) for r in (6.0, 10.0, 14.0)
                for b in (-60, -30, 0, 30, 60)]


class _Reach:
    def __init__(self, reach: float):
        self.reach, self.first = reach, None

    def start(self, episode, sims):
        self.first = np.full(sims.n, np.nan)

    def tick(self, t, sims, ids, neurons, action, task_state):
        d = np.linalg.norm(task_state.position - task_state.source, axis=1)
        new = np.isnan(self.first) & (d <= self.reach)
        new[np.setdiff1d(np.arange(len(d)), ids)] = False
        self.first[new] = t

    def end(self, result):
        pass


def check(path, sources, seconds: float, reach: float) -> list[dict]:
    genome, cfg, _ = load_genome(path)
    cfg = with_sources(cfg.nominal(), [list(s) for s in sources])
    watch = _Reach(reach)
    r = cfg.build().run(genome, seconds=seconds, listener=watch).rows
    d = np.linalg.norm(r.end_position - np.array(sources), axis=1)
    out = []
    for j, s in enumerate(sources):
        arrived = watch.first[j]
        out.append({"source": [round(float(v), 3) for v in s], "final_m": float(d[j]), "fell": bool(r.fell[j]),
                    "end_s": float(r.end_time[j]), "arrived_s": None if np.isnan(arrived) else float(arrived),
                    "up_after_arrival_s": None if np.isnan(arrived) else float(r.end_time[j] - arrived)})
    return out


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("genome")
    p.add_argument("--seconds", type=float, default=80.0)
    p.add_argument("--reach", type=float, default=0.5)
    p.add_argument("--source", nargs=2, type=float, action="append", metavar=("X", "Y"))
    a = p.parse_args(argv)
    if not (a.seconds > 0 and a.reach > 0):
        print("steer_check: error: --seconds and --reach must be > 0", file=sys.stderr)
        return 2
    rows = check(a.genome, [tuple(s) for s in a.source] if a.source else TEST_SOURCES, a.seconds, a.reach)
    print(f"{'source (m)':>18} {'final (m)':>10} {'arrived (s)':>12} {'up after (s)':>13}  fell")
    for r in rows:
        arr = "-" if r["arrived_s"] is None else f"{r['arrived_s']:.1f}"
        up = "-" if r["up_after_arrival_s"] is None else f"{r['up_after_arrival_s']:.1f}"
        print(f"{str(tuple(r['source'])):>18} {r['final_m']:>10.2f} {arr:>12} {up:>13}  "
              f"{'at %.1f s' % r['end_s'] if r['fell'] else 'no'}")
    final = [r["final_m"] for r in rows]
    stayed = sum(r["up_after_arrival_s"] is not None and r["up_after_arrival_s"] >= 50 and not r["fell"] for r in rows)
    print(f"median final distance {np.median(final):.2f} m (range {min(final):.2f}-{max(final):.2f}); fell in "
          f"{sum(r['fell'] for r in rows)} of {len(rows)}; reached within {a.reach:g} m and up 50 s after in {stayed} "
          f"of {len(rows)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
