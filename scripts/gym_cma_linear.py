"""Evolve a linear policy for the Reil biped on its vector environment with CMA-ES (pycma).

The policy maps the 24 sensor readings to the 6 PD targets,
``action = mid + half * tanh(W obs + b)`` (``mid``, ``half``: centre and half-width of
Table II's ranges), 150 parameters.  Each CMA-ES generation is one batch: candidate i
drives walker i of a ``ReilBipedVectorEnv`` with ``num_envs = popsize`` for one episode
(its return: the increments of the walk task's forward fitness, F = (forward m + credit) * time up / T,
summed: F at the end minus the credit), all stepped together.

    python scripts/gym_cma_linear.py --generations 60 --popsize 24 --seconds 5 --seed 0
"""

import argparse
import time

import cma
import numpy as np

from evobiped.envs import ReilBipedVectorEnv


def episode_returns(venv: ReilBipedVectorEnv, params: np.ndarray, seed: int):
    """Run one episode of each row's policy ``params`` ``(N, 150)``; returns (return, steps up, progress m), each
    ``(N,)``."""
    w = venv.walkers
    n, n_obs, n_act = params.shape[0], w.obs_size, len(w.low)
    W = params[:, : n_act * n_obs].reshape(n, n_act, n_obs)
    b = params[:, n_act * n_obs :]
    mid, half = (w.high + w.low) / 2, (w.high - w.low) / 2
    obs, _ = venv.reset(seed=seed)
    total, progress = np.zeros(n), np.zeros(n)
    steps = np.zeros(n, int)
    live = np.ones(n, bool)
    while live.any():
        action = mid + half * np.tanh(np.einsum("nij,nj->ni", W, obs) + b)
        obs, r, te, tr, info = venv.step(action)
        total += np.where(live, r, 0.0)
        progress = np.where(live, info["forward"], progress)
        steps += live & ~te
        live &= ~(te | tr)
    return total, steps, progress


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--generations", type=int, default=60)
    ap.add_argument("--popsize", type=int, default=24)
    ap.add_argument("--seconds", type=float, default=5.0, help="episode length (s)")
    ap.add_argument("--survival-credit", type=float, default=5.0,
                    help="the forward fitness's survival credit (m, default 5)")
    ap.add_argument("--sigma", type=float, default=0.1, help="CMA-ES initial step")
    ap.add_argument("--seed", type=int, default=0)
    a = ap.parse_args()
    if a.generations < 1 or a.popsize < 2 or not a.seconds > 0 or not a.sigma > 0 or not a.survival_credit >= 0:
        ap.error("--generations must be >= 1, --popsize >= 2, --seconds and --sigma > 0, --survival-credit >= 0")
    venv = ReilBipedVectorEnv(a.popsize, seconds=a.seconds,
                              task_options={"fitness": "forward", "survival_credit": a.survival_credit})
    n_params = (venv.walkers.obs_size + 1) * len(venv.walkers.low)
    es = cma.CMAEvolutionStrategy(np.zeros(n_params), a.sigma,
                                  {"popsize": a.popsize, "seed": a.seed + 1, "verbose": -9})
    t0 = time.perf_counter()
    max_steps = venv.walkers.episode.n_ticks
    for g in range(a.generations):
        X = np.array(es.ask())
        ret, steps, prog = episode_returns(venv, X, seed=a.seed * 100_003 + g)
        es.tell(list(X), list(-ret))  # pycma minimises
        i = int(np.argmax(ret))
        print(f"gen {g:3d}  best return {ret[i]:6.2f} (up {steps[i] * venv.walkers.control_dt:4.2f} s, "
              f"{prog[i]:5.2f} m)  mean {ret.mean():6.2f}  up the whole episode "
              f"{int((steps == max_steps).sum()):2d}/{len(ret)}  {time.perf_counter() - t0:6.1f} s", flush=True)
    mean = np.tile(es.mean, (a.popsize, 1))
    ret, steps, prog = episode_returns(venv, mean, seed=12345)  # the final mean on fresh reset noise
    print(f"final mean policy on {a.popsize} fresh resets: return {ret.mean():.2f} (min {ret.min():.2f}), "
          f"up the whole {a.seconds:g} s in {int((steps == max_steps).sum())}/{a.popsize}, "
          f"forward progress {prog.mean():.2f} m (min {prog.min():.2f}); wall {time.perf_counter() - t0:.1f} s")


if __name__ == "__main__":
    main()
