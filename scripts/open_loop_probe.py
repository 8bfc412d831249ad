"""Can any open-loop rhythmic gait keep the Reil biped up?  A direct search.

Reil & Husbands' CTRNNs have no sensory input: a stable walker is an open-loop
rhythm that the body's own dynamics stabilise.  This probe searches families
of such rhythms directly for the longest survival (ties broken by distance):

  sine     each joint's PD target a sinusoid at a common frequency, the legs in
           antiphase (9 parameters: frequency; hip-pitch amplitude/offset; knee
           amplitude/offset/phase; hip-roll amplitude/offset/phase)
  fourier  each of the 6 targets its own offset and first two harmonics of a
           common frequency, no symmetry imposed (31 parameters)
  ctrnn    the package's CTRNN (Table III ranges, 120 genes), i.e. exactly the
           rhythms the paper's GA can reach

by one of two searches: ``truncation`` (random sampling, then keep the best
10 % and mutate; for ``sine``, the search docs/reil.md first reported) or
``cma`` (CMA-ES, Hansen's standard (mu/mu_w, lambda) form, on unbounded
coordinates that are squashed into the family's ranges).  It prints the
longest survival found as it goes.

    python scripts/open_loop_probe.py --seed 1 --rounds 12
    python scripts/open_loop_probe.py --search cma --family fourier --rounds 800 --population 32
    python scripts/open_loop_probe.py --search cma --family ctrnn --rounds 500 --population 32
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

from evobiped.bodies import ReilBiped
from evobiped.controllers.base import Controller
from evobiped.episode import Episode, EpisodeConfig
from evobiped.errors import UserError
from evobiped.genome import GeneBlock, GenomeLayout
from evobiped.models import model_path
from evobiped.tasks import WalkTask

# sine parameter ranges: Hz, rad, rad, rad, rad, rad(phase), rad, rad, rad(phase)
LOW = np.array([0.3, 0.0, -0.3, 0.0, -0.8, -np.pi, 0.0, -0.3, -np.pi])
HIGH = np.array([2.5, 0.8, 0.5, 0.8, 0.0, np.pi, 0.4, 0.3, np.pi])
FOURIER_HZ = (0.3, 2.5)


class OpenLoop(Controller):
    """PD targets (rad) as a function of time only; the episode clips them to Table II's ranges."""

    output_kind = "angle"
    dt = 0.02
    n_params = 0

    def __init__(self, low: np.ndarray, high: np.ndarray):
        self.n_outputs = 6
        self.mid, self.half = 0.5 * (low + high), 0.5 * (high - low)
        self._layout = GenomeLayout((GeneBlock(name="p", size=self.n_params, low=-1e9, high=1e9, init_mean=0.0, init_sigma=1.0, mutation_sigma=0.1),))

    layout = property(lambda self: self._layout)

    def initial_state(self, params):
        return np.zeros(len(params["p"]))  # time, s

    def neuron_outputs(self, params, t):
        return np.zeros((len(t), 6))

    def step(self, params, t, inputs):
        return t + self.dt, self.targets(params["p"], t)  # (P, 6) rad


class SineGait(OpenLoop):
    """Genome = 9 values in [0, 1] scaled onto LOW..HIGH."""

    name = "sine-gait"
    n_params = 9

    def targets(self, p, t):
        q = LOW + p * (HIGH - LOW)
        w = 2 * np.pi * q[:, 0] * t
        hip = lambda ph: q[:, 2] + q[:, 1] * np.sin(w + ph)  # noqa: E731
        knee = lambda ph: np.minimum(0.0, q[:, 4] + q[:, 3] * np.sin(w + ph + q[:, 5]))  # noqa: E731
        roll = lambda ph: q[:, 7] + q[:, 6] * np.sin(w + ph + q[:, 8])  # noqa: E731
        return np.stack([hip(0), roll(0), knee(0), hip(np.pi), roll(np.pi), knee(np.pi)], axis=1)


class FourierGait(OpenLoop):
    """Genome = frequency coordinate, then per joint (offset, sin, cos, sin 2, cos 2) in half-ranges from its mid-range."""

    name = "fourier-gait"
    n_params = 31

    def targets(self, p, t):
        f = FOURIER_HZ[0] + (FOURIER_HZ[1] - FOURIER_HZ[0]) / (1 + np.exp(-p[:, 0]))
        w = (2 * np.pi * f * t)[:, None]
        c = p[:, 1:].reshape(-1, 6, 5)
        u = c[..., 0] + c[..., 1] * np.sin(w) + c[..., 2] * np.cos(w) + c[..., 3] * np.sin(2 * w) + c[..., 4] * np.cos(2 * w)
        return self.mid + self.half * u


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


def cma_es(evaluate, x0: np.ndarray, sigma: float, lam: int, iterations: int, rng, report) -> None:
    """Maximise ``evaluate(X (lam, n)) -> (lam,)`` by CMA-ES (Hansen 2016, "The CMA Evolution Strategy: A Tutorial")."""
    n, mu = len(x0), lam // 2
    w = np.log(mu + 0.5) - np.log(np.arange(1, mu + 1))
    w /= w.sum()
    mueff = 1 / (w**2).sum()
    cc, cs = (4 + mueff / n) / (n + 4 + 2 * mueff / n), (mueff + 2) / (n + mueff + 5)
    c1 = 2 / ((n + 1.3) ** 2 + mueff)
    cmu = min(1 - c1, 2 * (mueff - 2 + 1 / mueff) / ((n + 2) ** 2 + mueff))
    damps = 1 + 2 * max(0.0, np.sqrt((mueff - 1) / (n + 1)) - 1) + cs
    chi_n = np.sqrt(n) * (1 - 1 / (4 * n) + 1 / (21 * n * n))
    m, C, pc, ps = x0.copy(), np.eye(n), np.zeros(n), np.zeros(n)
    for g in range(iterations):
        d2, B = np.linalg.eigh(C)
        d = np.sqrt(np.maximum(d2, 1e-20))
        y = rng.standard_normal((lam, n)) @ (B * d).T
        x = m + sigma * y
        order = np.argsort(-evaluate(x))
        report(g, sigma)
        ysel = y[order[:mu]]
        yw = w @ ysel
        m = m + sigma * yw
        ps = (1 - cs) * ps + np.sqrt(cs * (2 - cs) * mueff) * (B @ ((B.T @ yw) / d))
        hs = np.linalg.norm(ps) / np.sqrt(1 - (1 - cs) ** (2 * (g + 1))) / chi_n < 1.4 + 2 / (n + 1)
        pc = (1 - cc) * pc + hs * np.sqrt(cc * (2 - cc) * mueff) * yw
        C = (1 - c1 - cmu) * C + c1 * (np.outer(pc, pc) + (1 - hs) * cc * (2 - cc) * C) + cmu * (ysel.T * w) @ ysel
        sigma *= np.exp((cs / damps) * (np.linalg.norm(ps) / chi_n - 1))


def build(args, opts: dict):
    """The episode, the decoding of search coordinates into genomes, the start point and step size, the RNG."""
    rng = np.random.default_rng(args.seed)
    if args.family == "ctrnn":
        episode = EpisodeConfig(seconds=args.seconds, body_options=opts).build()
        lay = episode.controller.layout
        decode = lambda x: lay.low + (lay.high - lay.low) / (1 + np.exp(-x))  # noqa: E731
        x0, sigma = rng.normal(0.0, 0.5, lay.size), 0.5
    else:
        body = ReilBiped(**opts)
        family = SineGait if args.family == "sine" else FourierGait
        episode = Episode(body, family(*body.action_bounds()), WalkTask(), seconds=args.seconds)
        if args.family == "sine":
            decode = lambda x: 1 / (1 + np.exp(-x))  # noqa: E731
            x0, sigma = np.zeros(9), 1.0
        else:
            decode = lambda x: x  # noqa: E731
            x0, sigma = np.concatenate([[0.0], rng.normal(0.0, 0.2, 30)]), 0.3
    return episode, decode, x0, sigma, rng


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--family", choices=("sine", "fourier", "ctrnn"), default="sine")
    ap.add_argument("--search", choices=("truncation", "cma"), default="truncation")
    ap.add_argument("--rounds", type=int, default=15, help="rounds (truncation) or CMA-ES generations")
    ap.add_argument("--population", type=int, default=200, help="gaits per round (CMA-ES: lambda)")
    ap.add_argument("--seconds", type=float, default=30.0)
    ap.add_argument("--planar", action="store_true", help="hold the pelvis in the sagittal plane (a diagnostic body)")
    ap.add_argument("--body-option", action="append", default=[], metavar="KEY=VALUE", help="e.g. kp=5, fall_height=0.4, model_file=...")
    args = ap.parse_args()
    if args.search == "truncation" and args.family != "sine":
        ap.error("--search truncation is for --family sine (use --search cma)")
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
        episode, decode, x0, sigma, rng = build(args, opts)
    except (UserError, TypeError) as exc:
        ap.error(str(exc))
    t0, best = time.time(), {"score": -np.inf}

    def evaluate(genomes: np.ndarray) -> np.ndarray:
        res = episode.run(genomes)
        score = res.end_time + 0.01 * res.fitness
        i = int(np.argmax(score))
        if score[i] > best["score"]:
            best.update(score=score[i], survival=res.end_time[i], distance=res.fitness[i])
        return score

    if args.search == "truncation":
        P, elite_n = args.population, args.population // 10
        pop = rng.uniform(0, 1, (P, 9))
        for r in range(args.rounds):
            res = episode.run(pop)
            order = np.argsort(-(res.end_time + 0.01 * res.fitness))
            print(f"round {r:2d}: longest survival {res.end_time[order[0]]:5.2f} s (distance {res.fitness[order[0]]:.2f} m), "
                  f"top-10 mean {res.end_time[order[:10]].mean():5.2f} s", flush=True)
            elite = pop[order[:elite_n]]
            pop = np.clip(np.repeat(elite, P // elite_n, axis=0) + rng.normal(0, 0.05, (P, 9)), 0, 1)
            pop[:elite_n] = elite
        print("best parameters:", np.round(LOW + elite[0] * (HIGH - LOW), 3).tolist())
        return

    def report(g: int, s: float) -> None:
        if g % 10 == 0 or g == args.rounds - 1:
            print(f"generation {g:4d}  {time.time() - t0:5.0f} s: longest survival {best['survival']:5.2f} s "
                  f"(distance {best['distance']:.2f} m), step size {s:.3g}", flush=True)

    cma_es(lambda x: evaluate(decode(x)), x0, sigma, args.population, args.rounds, rng, report)
    print(f"{args.rounds * args.population} gaits: longest survival {best['survival']:.2f} s, distance {best['distance']:.2f} m")


if __name__ == "__main__":
    main()
