"""Make commanded walkers from walking networks, with no search, and put each through the speed battery.

    python scripts/command_from_walkers.py RUN_OR_GENOME [...] [--schedules 10] [--out DIR]

For each walker (a genome file, or a run directory: its last generation's walker, ES's theta): its own speed V over
20 s; ``evobiped genome command-start --speed-gain 1 --reference-speed V`` (the speed command moving the frame of its
velocity sense); ``evobiped genome command-calibrate`` (the command's scale fitted over 0.3-0.75 m/s); then the speed
battery of ``evobiped gait --battery`` over 0.2-0.8 m/s.  Prints a Markdown row per walker and writes each commanded
walker and its battery JSON to --out (default runs/command_from_walkers).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from evobiped.analysis.gait_report import gait_report
from evobiped.analysis.speed_battery import calibrate_speed, speed_battery
from evobiped.core.errors import UserError
from evobiped.core.fileio import write_json
from evobiped.files.genome_edit import command_genome
from evobiped.files.genome_file import load_genome, save_genome


def walker_file(source: str) -> Path:
    """A genome file: ``source`` itself, or a run directory's last generation file."""
    p = Path(source)
    if p.is_dir():
        generations = sorted((p / "generations").glob("gen_*.json"))
        if not generations:
            raise UserError(f"{p}: no generation files")
        return generations[-1]
    return p


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("walkers", nargs="+")
    ap.add_argument("--schedules", type=int, default=10)
    ap.add_argument("--out", default="runs/command_from_walkers")
    args = ap.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    print("| walker | its speed (m/s) | fit: walked = a + b x command | schedules without a fall | every stretch "
          "within 10 % | stretches within 10 % | stretch error median / p90 (%) |")
    print("|---|---|---|---|---|---|---|")
    for i, source in enumerate(args.walkers):
        path = walker_file(source)
        genome, cfg, _ = load_genome(path)
        speed = gait_report(cfg, genome, seconds=20.0)["speed"]
        framed, framed_cfg = command_genome(path, 1.0, speed)
        try:
            cal_cfg, fit = calibrate_speed(framed_cfg, framed, [0.3, 0.45, 0.6, 0.75])
        except UserError as e:
            print(f"| {source} | {speed:.2f} | not calibrated: {e} | | | | |", flush=True)
            continue
        name = f"commanded_{i}"
        save_genome(out / f"{name}.json", framed, cal_cfg, source=str(path))
        b = speed_battery(cal_cfg, framed, n=args.schedules)
        write_json(out / f"{name}_speed_battery.json", {**b, "source": str(path)})
        m = b["summary"]
        se = m["stretch_error_pct"]
        print(f"| {source} | {speed:.2f} | {fit['intercept']:.2f} + {fit['slope']:.2f} v | {m['no_fall']} of "
              f"{m['schedules']} | {m['passed']} | {m['within']} of {m['stretches']} | {se['median']:.1f} / "
              f"{se['p90']:.1f} |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
