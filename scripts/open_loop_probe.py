"""Can any open-loop rhythmic gait keep the Reil biped up?  A direct search.

Reil & Husbands' CTRNNs have no sensory input: a stable walker is an open-loop
rhythm that the body's own dynamics stabilise.  This probe searches a simple
family of such rhythms directly — each joint's PD target a sinusoid at a common
frequency, the two legs in antiphase (9 parameters: frequency; hip-pitch
amplitude/offset; knee amplitude/offset/phase; hip-roll amplitude/offset/phase)
— first by random sampling, then by truncation selection on survival time.
It prints the longest survival found per round.

    python scripts/open_loop_probe.py --seed 0 --rounds 15
    python scripts/open_loop_probe.py --body-option kp=5 --body-option kv=4
    python scripts/open_loop_probe.py --body-option inertia=karma
"""

from __future__ import annotations

import argparse

import numpy as np

from evobiped.bodies import ReilBiped
from evobiped.controllers.base import Controller
from evobiped.episode import Episode
from evobiped.genome import GeneBlock, GenomeLayout
from evobiped.tasks import WalkTask

# parameter ranges: Hz, rad, rad, rad, rad, rad(phase), rad, rad, rad(phase)
LOW = np.array([0.3, 0.0, -0.3, 0.0, -0.8, -np.pi, 0.0, -0.3, -np.pi])
HIGH = np.array([2.5, 0.8, 0.5, 0.8, 0.0, np.pi, 0.4, 0.3, np.pi])


class SineGait(Controller):
    """Sinusoidal PD targets, legs in antiphase; genome = 9 values in [0, 1] scaled onto LOW..HIGH."""

    name = "sine-gait"
    output_kind = "signed"
    dt = 0.02

    def __init__(self, low: np.ndarray, high: np.ndarray):
        self.n_outputs = 6
        self.target_low, self.target_high = low, high
        self._layout = GenomeLayout((GeneBlock(name="p", size=9, low=0.0, high=1.0, init_mean=0.5, init_sigma=0.3, mutation_sigma=0.05),))

    layout = property(lambda self: self._layout)

    def initial_state(self, params):
        return np.zeros(len(params["p"]))  # time, s

    def neuron_outputs(self, params, t):
        return np.zeros((len(t), 6))

    def step(self, params, t, inputs):
        q = LOW + params["p"] * (HIGH - LOW)
        w = 2 * np.pi * q[:, 0] * t
        hip = lambda ph: q[:, 2] + q[:, 1] * np.sin(w + ph)  # noqa: E731
        knee = lambda ph: np.minimum(0.0, q[:, 4] + q[:, 3] * np.sin(w + ph + q[:, 5]))  # noqa: E731
        roll = lambda ph: q[:, 7] + q[:, 6] * np.sin(w + ph + q[:, 8])  # noqa: E731
        target = np.stack([hip(0), roll(0), knee(0), hip(np.pi), roll(np.pi), knee(np.pi)], axis=1)
        mid, half = 0.5 * (self.target_low + self.target_high), 0.5 * (self.target_high - self.target_low)
        # "signed" outputs reach PD targets through mid + half tanh(y): invert it
        return t + self.dt, np.arctanh(np.clip((target - mid) / half, -0.999, 0.999))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--rounds", type=int, default=15)
    ap.add_argument("--population", type=int, default=200)
    ap.add_argument("--seconds", type=float, default=30.0)
    ap.add_argument("--body-option", action="append", default=[], metavar="KEY=VALUE", help="e.g. kp=5, fall_height=0.4, model_file=...")
    args = ap.parse_args()
    opts = {}
    for kv in args.body_option:
        k, v = kv.split("=", 1)
        try:
            opts[k] = float(v)
        except ValueError:
            opts[k] = v  # model_file=..., inertia=karma
    body = ReilBiped(**opts)
    low, high = body.action_bounds()
    episode = Episode(body, SineGait(low, high), WalkTask(), seconds=args.seconds)
    rng = np.random.default_rng(args.seed)
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
    best = LOW + elite[0] * (HIGH - LOW)
    print("best parameters:", np.round(best, 3).tolist())


if __name__ == "__main__":
    main()
