"""Intelligent trial and error's sensitivity to its kernel length rho and exploration weight kappa, against two
searches without the GP: the elites in order of their prior, and in a random order.

    python scripts/ite_sensitivity.py docs/repertoire --seeds 5 --out ite_study     # about 20 min on one core

Every setting searches the same damages (the six of docs/repertoire.md's table and two more), each with ``--seeds``
seeds: every trial starts off the nominal pose by Gaussian noise of ``--pose-noise`` rad, the n-th trial of a
search drawn under (seed, n) whichever elite it tries, so every setting meets the same noise (common random numbers),
and the random order draws its permutation from the seed.  Per setting, over damages x seeds: how many searches
found a walking gait (>= 10 m in 50 s, no fall) within ``--trials`` trials (Wilson 95 % interval), the trials
until the first walking trial (a search that found none counts trials + 1), and the trials until the search
stopped; per baseline, Vargha and Delaney's A and the Mann-Whitney p of its trials to a walk against the default
(rho 0.15, kappa 0.05; A < 0.5: the baseline needs fewer).  Writes ``OUT/results.md`` and ``OUT/results.json``.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from evobiped.analysis.compare_stats import mann_whitney_p, median_iqr, vargha_delaney, wilson_ci
from evobiped.repertoire.adaptation import adapt, walks
from evobiped.repertoire.damage import parse_damage
from evobiped.repertoire.elites import load_repertoire
from evobiped.repertoire.trial_error import TrialAndError

DAMAGES = ("weak:left_knee:0.5", "weak:right_hip_pitch:0.5", "short:left:0.05", "short:right:0.03",
           "locked:left_hip_roll", "locked:right_knee", "weak:right_knee:0.5", "weak:left_hip_roll:0.5")
#: (label, search settings): the default first, then the rho sweep, the kappa sweep at two rho, the two baselines
SETTINGS = (("ucb rho 0.15 kappa 0.05 (default)", dict(rho=0.15, kappa=0.05)),
            *((f"ucb rho {r} kappa 0.05", dict(rho=r, kappa=0.05)) for r in (0.05, 0.1, 0.25, 0.4)),
            *((f"ucb rho {r} kappa {k}", dict(rho=r, kappa=k)) for r in (0.15, 0.4) for k in (0.3, 1.0)),
            ("prior order (no GP)", dict(order="prior")),
            ("random order (no GP)", dict(order="random")))


def search_once(rep, damage, settings: dict, seed: int, trials: int, pose_noise: float) -> dict:
    attempts, _ = adapt(rep, damage, search=TrialAndError(trials=trials, seed=seed, **settings), pose_noise=pose_noise,
                        seed=seed)
    first = next((n for n, t in enumerate(attempts, 1) if walks(t)), None)
    return {"found": first is not None, "first_walk": first if first is not None else trials + 1,
            "stopped_after": len(attempts),
            "best_distance": max(t.distance for t in attempts if not t.fell) if any(not t.fell for t in attempts)
                else 0.0}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("run", help="a map-elites run directory or a shipped archive (docs/repertoire)")
    p.add_argument("--seeds", type=int, default=5)
    p.add_argument("--trials", type=int, default=20)
    p.add_argument("--pose-noise", type=float, default=0.02)
    p.add_argument("--out", required=True)
    a = p.parse_args(argv)
    if a.seeds < 1 or a.trials < 1 or not (np.isfinite(a.pose_noise) and a.pose_noise >= 0):
        print("ite_sensitivity: --seeds and --trials must be >= 1, --pose-noise a finite number >= 0", file=sys.stderr)
        return 2
    rep = load_repertoire(a.run)
    damages = [parse_damage(d, rep.episode) for d in DAMAGES]
    rows = []
    for label, settings in SETTINGS:
        runs = [dict(damage=str(d), seed=s, **search_once(rep, d, settings, s, a.trials, a.pose_noise))
                for d in damages for s in range(a.seeds)]
        rows.append({"setting": label, "options": settings, "runs": runs})
        print(f"{label}: {sum(r['found'] for r in runs)} of {len(runs)} found a walking gait", file=sys.stderr,
              flush=True)
    base = [r["first_walk"] for r in rows[0]["runs"]]
    lines = [f"Archive {a.run}; {len(damages)} damages x {a.seeds} seeds; trials of 50 s, each off the nominal pose by "
             f"Gaussian noise of {a.pose_noise} rad; at most {a.trials} trials.", "",
             "| setting | found a walk | Wilson 95 % | trials to the first walk, median (IQR) | trials until stopped, "
             "median | A vs default | p vs default |",
             "|---|---|---|---|---|---|---|"]
    for row in rows:
        runs = row["runs"]
        k, n = sum(r["found"] for r in runs), len(runs)
        lo, hi = wilson_ci(k, n)
        med, q1, q3 = median_iqr([r["first_walk"] for r in runs])
        stop = median_iqr([r["stopped_after"] for r in runs])[0]
        mine = [r["first_walk"] for r in runs]
        same = row is rows[0]
        row.update(found=k, n=n, wilson=[lo, hi], first_walk_median=med, first_walk_iqr=[q1, q3], stopped_median=stop,
                   a_vs_default=None if same else vargha_delaney(mine, base), p_vs_default=None if same
                       else mann_whitney_p(mine, base))
        lines.append(f"| {row['setting']} | {k} of {n} | {lo:.2f}–{hi:.2f} | {med:g} ({q1:g}–{q3:g}) | {stop:g} | "
                     + ("– | – |" if same else f"{row['a_vs_default']:.2f} | {row['p_vs_default']:.3f} |"))
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "results.md").write_text("\n".join(lines) + "\n")
    (out / "results.json").write_text(json.dumps({"archive": a.run, "damages": list(DAMAGES), "seeds": a.seeds,
                                                  "trials": a.trials,
                                                  "pose_noise": a.pose_noise, "settings": rows}, indent=1) + "\n")
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
