"""Re-run the shipped network walkers at their control period, half and a quarter of it, under both integrations.

    python scripts/dt_convergence.py                     # docs/walkers/ctrnn_*.json and steer_ctrnn_*.json
    python scripts/dt_convergence.py FILE.json ...       # other CTRNN genome files

A network evolved at dt = 0.02 s with forward Euler may lean on Euler's error (a fast self-inhibited neuron that
flips every tick).  Its continuous-time network is what a finer step converges to: a walker that still walks at
dt / 2 and dt / 4 under the exponential integration (controller option ``integration``) walks as a CTRNN, one that
walks only at its own dt under Euler walks as the discrete map.  Each line: the walker, the control period, the
integration, whether it stayed up (and until when), the distance walked and its direction from the initial facing
(and, for a steering walker, its final distance to the source), for the nominal episode of the file's length.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path

from evobiped.core.options import replace
from evobiped.files.genome_file import load_genome
from evobiped.files.outcome import outcome

ROOT = Path(__file__).resolve().parent.parent


def network_walkers() -> list[Path]:
    """The shipped CTRNN genome files (not the robustness reports)."""
    found = [*(ROOT / "docs" / "walkers").glob("ctrnn_*.json"), *(ROOT / "docs" / "walkers").glob("steer_ctrnn_*.json")]
    return sorted(p for p in found if not p.stem.endswith("_robustness"))


def rows(path: Path) -> list[str]:
    """One markdown table line per (control period, integration) of the walker in ``path``."""
    genome, cfg, _ = load_genome(path)
    base = cfg.controller_options
    out = []
    for fraction in (1, 2, 4):
        for integration in ("euler", "exponential"):
            dt = base.dt / fraction
            options = replace(base, "controller_options", dt=dt, integration=integration)
            episode = dataclasses.replace(cfg, controller_options=options).nominal().build()
            result = episode.run(genome)
            done = outcome(result, episode.task.targets())
            r = done["rows"][0]
            up = "up" if not done["fell"] else f"fell at {done['end_time']:.2f} s"
            heading = "-" if r["heading_deg"] is None else f"{r['heading_deg']:+.1f}"
            target = f" {r['to_target']:.2f} m |" if "to_target" in r else " - |"
            out.append(f"| {path.stem} | {dt:g} | {integration} | {up} | {r['distance']:.2f} | {heading} |{target}")
            print(out[-1], flush=True)
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("files", nargs="*", type=Path, help="CTRNN genome files (default: the shipped network walkers)")
    args = parser.parse_args(argv)
    print("| walker | dt (s) | integration | up | distance (m) | direction (deg) | to source |")
    print("|---|---|---|---|---|---|---|")
    for path in args.files or network_walkers():
        rows(path)
    return 0


if __name__ == "__main__":
    sys.exit(main())
