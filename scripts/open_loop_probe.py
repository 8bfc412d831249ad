"""Can any open-loop rhythmic gait keep the Reil biped up?  A direct search.

Reil & Husbands' CTRNNs have no sensory input: a stable walker is an open-loop
rhythm that the body's own dynamics stabilise.  This probe searches families
of such rhythms directly for the longest survival (ties broken by distance):

  sine     the ``open-loop`` controller's sine form: each joint's PD target a
           sinusoid at a common frequency, the legs in antiphase (9 genes)
  fourier  the ``open-loop`` controller's fourier form: each of the 6 targets
           its own offset and first two harmonics of a common frequency, no
           symmetry imposed (31 genes)
  ctrnn    the package's CTRNN (Table III ranges, 120 genes), i.e. exactly the
           rhythms the paper's GA can reach

(evobiped/controllers/open_loop.py), by one of two searches: ``truncation``
(random sampling in each gene's range, then keep the best 10 % and mutate; for
``sine``, the search docs/reil.md first reported) or ``cma`` (CMA-ES from the
``cma`` library behind evobiped.optimizers.cma: bounded to the genes' ranges,
pycma's stopping rules, ``--restarts`` IPOP restarts).  It prints the longest
survival found as it goes and saves the best genome as a genome file
(``--save``), which ``evobiped replay FILE`` re-simulates.

    python scripts/open_loop_probe.py --seed 1 --rounds 12 --save sine.json
    evobiped replay sine.json --figures figs/
    python scripts/open_loop_probe.py --search cma --family fourier --rounds 800 --population 32
    python scripts/open_loop_probe.py --search cma --family ctrnn --rounds 500 --population 32 --restarts 2
    python scripts/open_loop_probe.py --planar                     # the pelvis held in the sagittal plane
    python scripts/open_loop_probe.py --body-option inertia=karma --body-option kp=5 --body-option kv=4
"""

from __future__ import annotations

import argparse
import re
import tempfile
import time
from pathlib import Path

import numpy as np

from evobiped.episode import EpisodeConfig
from evobiped.core.errors import UserError
from evobiped.optimizers.cma import CMAES, CMAOptions
from evobiped.files.genome_file import save_genome
from evobiped.physics.models import model_path


def planar_model() -> str:
    """The Reil MJCF with the free root replaced by slide-x, slide-z and a pitch hinge (a boom); a temp file."""
    xml = model_path("reil_biped").read_text()
    root = ('<joint name="root_x" type="slide" axis="1 0 0" limited="false"/>'
            '<joint name="root_z" type="slide" axis="0 0 1" limited="false"/>'
            '<joint name="root_pitch" type="hinge" axis="0 1 0" limited="false"/>')
    xml, n = re.subn(r'<freejoint name="root"/>', root, xml)
    assert n == 1, "models/reil_biped.xml has no free root to replace"
    path = Path(tempfile.mkdtemp(prefix="evobiped_planar_")) / "reil_planar.xml"
    path.write_text(xml)
    return str(path)


def episode_config(args, body_options: dict) -> EpisodeConfig:
    """The episode the probe searches: the open-loop controller in the family's form, or the CTRNN."""
    if args.family == "ctrnn":
        return EpisodeConfig(seconds=args.seconds, body_options=body_options)
    return EpisodeConfig(controller="open-loop", controller_options={"form": args.family}, seconds=args.seconds,
                         body_options=body_options)


def truncation(episode, score, args, rng) -> None:
    """Random genomes uniform in the genes' ranges, then rounds of keeping the best 10 % and mutating them."""
    lay = episode.controller.layout
    P, G, elite_n = args.population, lay.size, max(1, args.population // 10)
    genes = lambda u: np.clip(lay.low + u * (lay.high - lay.low), lay.low, lay.high)  # noqa: E731 - unit cube -> genome
    pop = rng.uniform(0, 1, (P, G))
    for r in range(args.rounds):
        g = genes(pop)
        res = episode.run(g)
        order = np.argsort(-score(g, res))
        print(f"round {r:2d}: longest survival {res.end_time[order[0]]:5.2f} s (distance {res.fitness[order[0]]:.2f} "
              f"m), top-10 mean {res.end_time[order[:10]].mean():5.2f} s", flush=True)
        elite = pop[order[:elite_n]]
        pop = np.clip(np.repeat(elite, -(-P // elite_n), axis=0)[:P] + rng.normal(0, 0.05, (P, G)), 0, 1)
        pop[:elite_n] = elite


def cma(episode, score, args) -> None:
    """CMA-ES (pycma) over the layout's bounded genes, stopping early when pycma's rules fire and no restart is left."""
    es = CMAES(episode.controller.layout, CMAOptions(population=args.population, sigma0=args.sigma0,
                                                     restarts=args.restarts), seed=args.seed)
    t0 = time.time()
    for g in range(args.rounds):
        pop, _ = es.ask()
        es.tell(score(pop, episode.run(pop)))
        es.next_generation()
        stop = es.stop()
        if g % 10 == 0 or g == args.rounds - 1 or stop:
            print(f"generation {g:4d}  {time.time() - t0:5.0f} s: longest survival {best['survival']:5.2f} s "
                  f"(distance {best['distance']:.2f} m), population {len(pop)}, restart {es.restart}", flush=True)
        if stop:
            print(f"pycma stopped: {', '.join(stop)}")
            return


#: the best genome seen: score, survival (s), distance (m), genome (G,)
best: dict = {"score": -np.inf, "survival": 0.0, "distance": 0.0, "genome": None}


def score(genomes: np.ndarray, res) -> np.ndarray:
    """Survival (s) + 0.01 distance (m) per genome; remembers the best seen."""
    s = res.end_time + 0.01 * res.fitness
    i = int(np.argmax(s))
    if s[i] > best["score"]:
        best.update(score=s[i], survival=float(res.end_time[i]), distance=float(res.fitness[i]),
                    genome=genomes[i].copy())
    return s


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--family", choices=("sine", "fourier", "ctrnn"), default="sine")
    ap.add_argument("--search", choices=("truncation", "cma"), default="truncation")
    ap.add_argument("--rounds", type=int, default=15, help="rounds (truncation) or CMA-ES generations")
    ap.add_argument("--population", type=int, default=200, help="gaits per round (CMA-ES: lambda)")
    ap.add_argument("--sigma0", type=float, default=0.2, help="CMA-ES initial step, a fraction of every gene's range")
    ap.add_argument("--restarts", type=int, default=0, help="CMA-ES IPOP restarts when pycma's stopping rules fire")
    ap.add_argument("--seconds", type=float, default=30.0)
    ap.add_argument("--planar", action="store_true", help="hold the pelvis in the sagittal plane (a diagnostic body; "
                    "its model is a temporary file, which a saved genome names)")
    ap.add_argument("--body-option", action="append", default=[], metavar="KEY=VALUE",
                    help="e.g. kp=5, fall_height=0.4, model_file=...")
    ap.add_argument("--save", metavar="FILE",
                    help="write the best genome found as a genome file (evobiped replay FILE)")
    args = ap.parse_args()
    opts: dict = {"model_file": planar_model()} if args.planar else {}
    for kv in args.body_option:
        k, sep, v = kv.partition("=")
        if not sep:
            ap.error(f"--body-option {kv!r}: expected KEY=VALUE")
        try:
            opts[k] = float(v)
        except ValueError:
            opts[k] = v  # model_file=..., inertia=karma
    try:
        cfg = episode_config(args, opts)
        episode = cfg.build()
        if args.search == "truncation":
            truncation(episode, score, args, np.random.default_rng(args.seed))
        else:
            cma(episode, score, args)
    except UserError as exc:
        ap.error(str(exc))
    res = episode.run(best["genome"])
    names = episode.controller.layout.names()
    genes = ", ".join(f"{n} {x:.3g}" for n, x in zip(names,
                                                     best["genome"])) if len(names) <= 12 else f"{len(names)} genes"
    print(f"best: survival {res.end_time[0]:.2f} s, distance {res.fitness[0]:.2f} m; {genes}")
    if args.save:
        save_genome(args.save, best["genome"], cfg, fitness=float(res.fitness[0]), fell=bool(res.fell[0]),
                    end_time=float(res.end_time[0]), seed=args.seed, search=args.search)
        print(f"saved {args.save}: evobiped replay {args.save}")


if __name__ == "__main__":
    main()
