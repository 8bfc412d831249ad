"""Re-simulate the shipped walkers in this numerical environment and say how far each drifted from its file.

    python scripts/refresh_walkers.py                  # report only (docs/walkers/*.json genome files)
    python scripts/refresh_walkers.py --write          # and rewrite each file's fitness, outcome and environment
    python scripts/refresh_walkers.py FILE.json ...    # other genome files

A genome file records the numerical environment its results were made in (evobiped.core.provenance) and, for a
shipped walker, its outcome (evobiped.files.outcome): what a replay elsewhere checks.  After a deliberate version change
(constraints.txt), run this, read the drift, and --write only when every outcome still holds.  The stored
fitness is rewritten only for files whose episode is nominal (a run under perturbations stored the aggregate over
its perturbed presentations, which a nominal replay does not reproduce); the outcome is always the nominal
episode's.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from evobiped.files.genome_file import load_genome, save_genome
from evobiped.files.outcome import compare, outcome
from evobiped.core.provenance import differences

ROOT = Path(__file__).resolve().parent.parent
#: genome-file metadata the writer sets itself
OWN = ("format", "version", "environment", "outcome")


def shipped() -> list[Path]:
    """The genome files in docs/walkers (not the robustness reports)."""
    return sorted(p for p in (ROOT / "docs" / "walkers").glob("*.json") if not p.stem.endswith("_robustness"))


def refresh(path: Path, write: bool) -> bool:
    """Report ``path``'s drift in this environment; rewrite it if ``write`` and its outcome holds. True: it holds."""
    genome, cfg, meta = load_genome(path)
    nominal = not cfg.perturbed
    episode = cfg.nominal().build()
    result = episode.run(genome)
    done = outcome(result, episode.task.targets())
    changed = differences(meta.get("environment"))
    print(f"{path.name}: environment {'as recorded' if not changed else 'differs: ' + '; '.join(changed)}")
    if nominal and isinstance(meta.get("fitness"), (int, float)):
        d = float(result.fitness[0]) - meta["fitness"]
        print(f"  fitness {float(result.fitness[0])!r}, stored {meta['fitness']!r} (drift {d:+.3g})")
    stored = meta.get("outcome") or {k: meta[k] for k in ("fell", "end_time") if k in meta and nominal}
    drift, failures = compare(stored, done)
    for line in drift:
        print(f"  {line}")
    for line in failures:
        print(f"  OUTCOME DIFFERS: {line}")
    if write and not failures:
        keep = {k: v for k, v in meta.items() if k not in OWN}
        if nominal:
            keep.update(fitness=float(result.fitness[0]), fell=bool(result.fell[0]), end_time=float(result.end_time[0]))
        save_genome(path, genome, cfg, **keep, outcome=done)
        print(f"  rewritten: {path}")
    return not failures


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("files", nargs="*", type=Path, help="genome files (default: the shipped walkers)")
    parser.add_argument("--write", action="store_true", help="rewrite each file whose outcome holds")
    args = parser.parse_args(argv)
    results = [refresh(p, args.write) for p in (args.files or shipped())]
    print(f"{sum(results)} of {len(results)} outcomes hold")
    return 0 if all(results) else 1


if __name__ == "__main__":
    sys.exit(main())
