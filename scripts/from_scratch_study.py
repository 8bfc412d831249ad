"""Evolve walkers from scratch over many seeds and find when each seed first has a forward walker.

    python scripts/from_scratch_study.py --preset walker-es-linear --seeds 0-9 --out /tmp/study [--jobs 2]
        [--generations 600] [--deadline 1800] [--every 10]
    python scripts/from_scratch_study.py --figure /tmp/study/study.json --png docs/from_scratch_seeds.png

Each seed is one ``evobiped evolve --preset P --seed S --backend serial`` run (``--jobs`` at a time); a run still
going at ``--deadline`` s is stopped with SIGTERM (it checkpoints: resume it later with ``evobiped evolve --resume``).
Then every ``--every``-th generation file up to the first forward walker, and the last, whose walker stayed up in
training is tested alone,
nominally, by :func:`evobiped.analysis.selection.forward_walker`: no fall in 200 s, >= 20 m in its first 50 s within
+-30 degrees of its initial facing.  ``study.json`` records per seed the wall time, the generations run, the first
generation with a forward walker and what it cost (genomes evaluated, episodes, wall seconds of evolution), and the
fittest forward walker found (its file).  ``--figure`` draws the fraction of seeds with a walker against generations.
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import subprocess
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np


def seeds(text: str) -> list[int]:
    out = []
    for part in text.split(","):
        a, _, b = part.partition("-")
        out += list(range(int(a), int(b or a) + 1))
    return out


def evolve_all(preset: str, seed_list: list[int], out: Path, jobs: int, generations: int | None, deadline: float,
               config: str | None = None) -> dict:
    """Run every seed, ``jobs`` at a time, each stopped at ``deadline`` s after the study began; returns wall times."""
    t0, waiting, running, wall = time.time(), list(seed_list), {}, {}
    while waiting or running:
        while waiting and len(running) < jobs:
            s = waiting.pop(0)
            cmd = [sys.executable, "-m", "evobiped", "evolve", "--preset", preset, "--seed", str(s), "--backend",
                   "serial",
                   "--out", str(out / f"seed{s}"), "--quiet"] + (["--generations", str(generations)] if generations
                                                                 else []) \
                + (["--config", config] if config else [])
            running[s] = (subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=open(out / f"seed{s}.log", "w")),
                          time.time())
        for s, (p, started) in list(running.items()):
            if p.poll() is not None:
                wall[s] = time.time() - started
                del running[s]
        if time.time() - t0 > deadline:
            for s, (p, started) in running.items():
                p.send_signal(signal.SIGTERM)  # (a background job ignores SIGINT)
            for s, (p, started) in running.items():
                p.wait()
                wall[s] = time.time() - started
            running = {}
            waiting = []
        time.sleep(1.0)
    return wall


def check_run(args: tuple[Path, int]) -> dict:
    """Test a run's generation files for forward walkers (see the module docstring)."""
    from evobiped.files import rundir
    from evobiped.files.genome_file import load_genome
    from evobiped.analysis.selection import forward_walker

    run, every = args
    hist = rundir.read_history(run / rundir.HISTORY) if (run / rundir.HISTORY).is_file() else {"generation": np.zeros(
        0)}
    n = len(hist["generation"])
    config = json.loads((run / rundir.CONFIG).read_text())
    R = int(config["episode"].get("perturbations", {}).get("presentations", 1))
    found, best, checked = None, None, []
    for g in sorted(set(range(0, n, every)) | ({n - 1} if n else set())):
        if found is not None and g != n - 1:
            continue  # after the first walker, only the last generation
        genome, cfg, meta = load_genome(rundir.generation_file(run, g))
        if meta.get("fell", True):
            continue
        w = forward_walker(cfg, genome)
        checked.append({"generation": g, **w})
        if w["walker"]:
            if found is None:
                found = g
            if best is None or w["distance"] > best["distance"]:
                best = {"generation": g, "file": str(rundir.generation_file(run, g)), **w}
    evals = np.cumsum(hist.get("evaluations", np.zeros(n)))
    cost = None
    if found is not None:  # genomes evaluated up to and with that generation, and episodes (one per presentation)
        cost = {"evaluations": int(evals[found]), "episodes": int(evals[found]) * R,
                "wall_seconds": round(float(np.sum(hist["wall_seconds"][: found + 1])), 1)}
    return {"run": str(run), "generations": n, "first_walker": found, "cost": cost, "best_walker": best,
            "checked": checked}


def study(a) -> None:
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    seed_list = seeds(a.seeds)
    t0 = time.time()
    wall = evolve_all(a.preset, seed_list, out, a.jobs, a.generations, a.deadline, a.config)
    evolve_s = time.time() - t0
    with ProcessPoolExecutor(a.jobs) as pool:
        results = list(pool.map(check_run, [(out / f"seed{s}", a.every) for s in seed_list]))
    for s, r in zip(seed_list, results):
        r["seed"], r["wall_seconds"] = s, round(wall.get(s, float("nan")), 1)
    doc = {"preset": a.preset, "config": a.config, "seeds": seed_list, "jobs": a.jobs, "cores": os.cpu_count(),
           "evolve_seconds": round(evolve_s, 1), "load_average": os.getloadavg(), "every": a.every, "results": results}
    (out / "study.json").write_text(json.dumps(doc, indent=1))
    walkers = sum(r["first_walker"] is not None for r in results)
    print(f"{a.preset}: forward walkers in {walkers} of {len(results)} seeds ({evolve_s:.0f} s evolving, {a.jobs} jobs "
          f"on {os.cpu_count()} cores)")
    for r in results:
        b = r["best_walker"]
        print(f"  seed {r['seed']}: {r['generations']} generations in {r['wall_seconds']} s; first walker at "
              f"{r['first_walker']}; " + (f"best {b['distance']:.1f} m at {b['heading_deg']:+.0f} deg (generation "
                                          f"{b['generation']})" if b else "none"))


def figure(a) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 3.6), dpi=120)
    for path in a.figure:
        doc = json.loads(Path(path).read_text())
        res = doc["results"]
        top = max(r["generations"] for r in res)
        g = np.arange(top + 1)
        frac = [np.mean([r["first_walker"] is not None and r["first_walker"] <= x for r in res]) for x in g]
        ax.step(g, frac, where="post",
                label=f"{doc['preset']}{' + ' + Path(doc['config']).stem if doc.get('config') else ''} ({len(res)} "
                      "seeds)")
    ax.set_xlabel("generation")
    ax.set_ylabel("fraction of seeds with a forward walker")
    ax.set_ylim(-0.02, 1.02)
    ax.grid(alpha=0.3)
    ax.legend(loc="upper left")
    ax.set_title("Forward walkers from scratch (up 200 s, >= 20 m in 50 s within 30 deg)", fontsize=9)
    fig.tight_layout()
    fig.savefig(a.png)
    print(f"wrote {a.png}")


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--preset")
    p.add_argument("--config", help="a settings file over the preset (a variant)")
    p.add_argument("--seeds", default="0-9")
    p.add_argument("--out")
    p.add_argument("--jobs", type=int, default=os.cpu_count())
    p.add_argument("--generations", type=int)
    p.add_argument("--deadline", type=float, default=1800.0, help="s after which runs still going are stopped")
    p.add_argument("--every", type=int, default=10)
    p.add_argument("--figure", nargs="+", metavar="STUDY_JSON")
    p.add_argument("--png")
    a = p.parse_args()
    if a.figure:
        figure(a)
    else:
        study(a)


if __name__ == "__main__":
    main()
