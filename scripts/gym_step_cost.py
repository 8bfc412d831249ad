"""What the vector environment's step costs beyond the batch simulator's own step.

For the same batch of N walkers: (env) ``BipedVectorEnv.step`` (action check, clip, actuators,
one control period of physics, sensors, reward, fall test) against (sims) ``Sims.step`` of the
same control period alone (``Body.advance``: for Taga, its ground forces before every physics step),
interleaved repeats, medians.  Falls are switched off (``fall_height`` ~ 0) and the reset noise, so that every walker is
stepped in every call of both, from the same initial pose.

    python scripts/gym_step_cost.py --body reil --num-envs 64 --steps 200 --repeats 7
"""

import argparse
import time

import numpy as np

from evobiped.envs import ReilBipedVectorEnv, TagaBipedVectorEnv
from evobiped.physics.sim import Sims

ENVS = {"reil": (ReilBipedVectorEnv, dict(fall_height=1e-6, fall_tilt=np.pi)),
        "taga": (TagaBipedVectorEnv, dict(fall_height=1e-9))}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--body", choices=sorted(ENVS), default="reil")
    ap.add_argument("--num-envs", type=int, default=64)
    ap.add_argument("--steps", type=int, default=200, help="env steps per repeat")
    ap.add_argument("--repeats", type=int, default=7)
    a = ap.parse_args()
    if a.num_envs < 1 or a.steps < 1 or a.repeats < 1:
        ap.error("--num-envs, --steps and --repeats must be >= 1")
    cls, no_falls = ENVS[a.body]
    venv = cls(a.num_envs, seconds=1e4, reset_noise_scale=0.0, **no_falls)  # both start from the same pose
    w = venv.walkers
    sims = Sims(w.model, a.num_envs)
    ids = np.arange(a.num_envs)
    action = np.tile(((w.low + w.high) / 2).astype(np.float32), (a.num_envs, 1))

    def env_run():
        venv.reset(seed=0)
        t0 = time.perf_counter()
        for _ in range(a.steps):
            venv.step(action)
        return time.perf_counter() - t0

    def sims_run():
        w.body.reset(sims)
        w.body.apply(sims, ids, action)
        t0 = time.perf_counter()
        for _ in range(a.steps):
            w.body.advance(sims, ids, w.substeps)
        return time.perf_counter() - t0

    env_t, sims_t = [], []
    for _ in range(a.repeats):
        env_t.append(env_run())
        sims_t.append(sims_run())
    e, s = np.median(env_t), np.median(sims_t)
    print(f"{a.body}: {a.num_envs} walkers, {w.substeps} physics steps of {w.body.timestep * 1000:g} ms per env step, "
          f"{a.steps} steps x {a.repeats} interleaved repeats (medians)")
    print(f"vector env step {e / a.steps * 1e6:9.1f} us   Sims step {s / a.steps * 1e6:9.1f} us   "
          f"overhead {100 * (e / s - 1):5.1f} %")


if __name__ == "__main__":
    main()
