"""Episodes an environment's runs took to a return threshold, from their history.csv (docs/benchmarks.md).

    python scripts/episodes_to.py 3120 runs/bench/hopper-ars-*

For each run directory: the first generation whose best row (ES: theta's own episode) returned at least the
threshold (history.csv's ``best_return``), the episodes evaluated up to and including it (every row: an ES run's
2 N perturbations and theta's row), those of the perturbations alone (``--pairs N``), and the best return reached;
with ``--fresh K`` that policy's and the last generation's mean return over K resets they were never scored on.
Then the median and range over the runs that reached it.  ``--at E``: the runs compared at an equal budget of E
episodes instead: the best return within E episodes, and (with ``--fresh K``) the mean over K fresh resets of the
policy of the generation whose episodes reach E (ES: theta).
"""

from __future__ import annotations

import argparse
import csv
import statistics
from pathlib import Path


def episodes_to(run: Path, threshold: float) -> tuple[int | None, int | None, int, float]:
    """(generation reached or None, episodes up to it or None, generations run, best return) of one run directory."""
    with open(run / "history.csv") as f:
        rows = list(csv.DictReader(f))
    total, best = 0, float("-inf")
    reached = None
    for r in rows:
        total += int(r["evaluations"])
        best = max(best, float(r["best_return"]))
        if reached is None and float(r["best_return"]) >= threshold:
            reached = (int(r["generation"]), total)
    return (*(reached or (None, None)), len(rows), best)


def at_budget(run: Path, budget: int) -> tuple[int, float]:
    """(the generation whose evaluated episodes reach ``budget``, or the last one; the best return up to it)."""
    with open(run / "history.csv") as f:
        rows = list(csv.DictReader(f))
    total, best = 0, float("-inf")
    for r in rows:
        total += int(r["evaluations"])
        best = max(best, float(r["best_return"]))
        if total >= budget:
            break
    return int(r["generation"]), best


def fresh_returns(run: Path, generation: int, k: int) -> list[float]:
    """The returns of generation ``generation``'s best (its genome file, its normaliser frozen in) from ``k`` resets
    it was never scored on (keys (2**31 - 1, i)): the environment's return, whatever the fitness's reward shift."""
    import numpy as np

    from evobiped.files.genome_file import load_genome

    genome, config, _ = load_genome(run / "generations" / f"gen_{generation:04d}.json")
    episode = config.build()
    return [float(episode.run(np.asarray(genome)[None], trials=(2**31 - 1, i)).terms["return"][0]) for i in range(k)]


def fresh_words(run: Path, generation: int, k: int, what: str) -> str:
    """``; WHAT over K fresh resets: mean M, min N`` for generation ``generation``'s best (:func:`fresh_returns`)."""
    fresh = fresh_returns(run, generation, k)
    return f"; {what} over {k} fresh resets: mean {statistics.mean(fresh):.1f}, min {min(fresh):.1f}"


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("threshold", type=float)
    p.add_argument("runs", nargs="+", type=Path)
    p.add_argument("--pairs", type=int, default=8, help="ES's mirrored pairs N (for the perturbation episodes alone)")
    p.add_argument("--fresh", type=int, default=0, metavar="K", help="also the mean return of the policy that reached "
                   "the threshold over K fresh resets")
    p.add_argument("--at", type=int, default=None, metavar="E", help="compare at an equal budget of E episodes")
    args = p.parse_args()
    if args.at is not None:
        for run in args.runs:
            g, best = at_budget(run, args.at)
            line = f"{run}: within {args.at} episodes (generation {g}) best return {best:.1f}"
            print(line + (fresh_words(run, g, args.fresh, f"generation {g}'s policy") if args.fresh else ""))
        return
    found = []
    for run in args.runs:
        g, episodes, n, best = episodes_to(run, args.threshold)
        if args.fresh:
            final = fresh_returns(run, n - 1, args.fresh)
            print(f"{run}: the last generation's best ({n - 1}) over {args.fresh} fresh resets: mean "
                  f"{statistics.mean(final):.1f}, min {min(final):.1f}")
        if g is None:
            print(f"{run}: not reached in {n} generations (best return {best:.1f})")
            continue
        pert = (g + 1) * 2 * args.pairs
        found.append((episodes, pert))
        line = f"{run}: generation {g}, {episodes} episodes ({pert} of perturbations); best return {best:.1f}"
        print(line + (fresh_words(run, g, args.fresh, "that policy") if args.fresh else ""))
    if found:
        eps, pert = zip(*found)
        print(f"reached by {len(found)} of {len(args.runs)}: median {statistics.median(eps):g} episodes "
              f"(range {min(eps)}-{max(eps)}); perturbations alone: median {statistics.median(pert):g}")


if __name__ == "__main__":
    main()
