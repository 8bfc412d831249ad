"""Stable-Baselines3's PPO trained on one of this project's environments (docs/gym.md, "An RL library as a client").

    python scripts/sb3_ppo.py evobiped/ReilBiped-v0 --steps 500000 --out runs/ppo-reil

The environment is made with ``actions="unit"`` (each action in [-1, 1], mapped onto the body's bounds, as RL
libraries expect) and ``seconds`` s episodes; PPO (SB3's defaults but ``n_steps`` 512 per environment over 4
environments, ``log_std_init`` -1) runs on the observation and reward normalised by SB3's ``VecNormalize``.
Every ``--every`` steps the deterministic policy plays ``--episodes`` resets it never trained on (seeds 1000,
1001, ...), and so do a uniformly random policy and the untrained policy once at the start.  Written to ``--out``:
``curve.csv`` (timesteps, mean return, mean steps up, wall s) and ``curve.png`` (the learning curve with the
random policy's return beside it).  Needs the ``rl`` extra (``pip install -e ".[gym,rl]"``).
"""

from __future__ import annotations

import argparse
import csv
import sys
import time
from pathlib import Path

import numpy as np


def evaluate(name: str, kw: dict, policy, episodes: int) -> tuple[float, float]:
    """Mean return and mean steps of ``policy(obs) -> action`` over resets seeded 1000, 1001, ..."""
    import gymnasium as gym

    env = gym.make(name, **kw)
    returns, lengths = [], []
    for i in range(episodes):
        obs, _ = env.reset(seed=1000 + i)
        total, steps, done = 0.0, 0, False
        while not done:
            obs, r, terminated, truncated, _ = env.step(policy(obs))
            total, steps, done = total + r, steps + 1, terminated or truncated
        returns.append(total)
        lengths.append(steps)
    env.close()
    return float(np.mean(returns)), float(np.mean(lengths))


#: PPO's settings here (SB3's defaults otherwise): 4 environments of 512 steps per update, a first exploration
#: noise of exp(-1) = 0.37 of the unit box
PPO_OPTIONS = {"n_steps": 512, "batch_size": 64, "policy_kwargs": {"log_std_init": -1.0}}


def train(name: str, steps: int, *, seed: int = 0, seconds: float = 10.0, every: int = 10240, episodes: int = 10,
          ppo: dict | None = None, say=print) -> dict:
    """PPO on environment ``name`` for ``steps`` timesteps (``ppo``: settings over :data:`PPO_OPTIONS`); returns the
    curve: ``random`` and ``untrained`` (mean return, mean steps) and ``rows`` of (timesteps, mean return, mean
    steps, wall s)."""
    import gymnasium as gym
    import torch
    from stable_baselines3 import PPO
    from stable_baselines3.common.env_util import make_vec_env
    from stable_baselines3.common.logger import Logger
    from stable_baselines3.common.vec_env import VecNormalize

    import evobiped.envs  # noqa: F401  (registers the environments)

    torch.set_num_threads(1)
    kw = {"actions": "unit", "seconds": seconds}
    space = gym.make(name, **kw).action_space
    space.seed(seed)
    out = {"random": evaluate(name, kw, lambda o: space.sample(), episodes)}
    venv = VecNormalize(make_vec_env(name, n_envs=4, seed=seed, env_kwargs=kw))
    model = PPO("MlpPolicy", venv, seed=seed, device="cpu", **(PPO_OPTIONS | (ppo or {})))
    model.set_logger(Logger(None, []))  # SB3's own logger writes a folder into the temporary directory every learn()

    def policy(obs):
        return model.predict(venv.normalize_obs(obs), deterministic=True)[0]

    out["untrained"] = evaluate(name, kw, policy, episodes)
    say(f"random policy: return {out['random'][0]:.3f}, {out['random'][1]:.1f} steps up; untrained: "
        f"{out['untrained'][0]:.3f}, {out['untrained'][1]:.1f}")
    rows, t0 = [], time.perf_counter()
    while model.num_timesteps < steps:
        model.learn(min(every, steps - model.num_timesteps), reset_num_timesteps=False)
        ret, up = evaluate(name, kw, policy, episodes)
        rows.append((model.num_timesteps, ret, up, time.perf_counter() - t0))
        say(f"{model.num_timesteps} steps: return {ret:.3f}, {up:.1f} steps up ({rows[-1][3]:.0f} s)")
    out["rows"] = rows
    return out


def figure(curve: dict, name: str, path: Path, episodes: int, control_dt: float) -> None:
    """The learning curve: the deterministic policy's mean return and time up on ``episodes`` held-out resets
    against timesteps (the untrained policy at 0), the random policy's as a dashed line."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = [(0, *curve["untrained"], 0.0), *curve["rows"]]
    t, ret, up = (np.array([r[k] for r in rows]) for k in (0, 1, 2))
    fig, (a, b) = plt.subplots(1, 2, figsize=(10, 3.8))
    a.plot(t, ret, "o-", ms=3, label="PPO's deterministic policy")
    a.axhline(curve["random"][0], color="grey", ls="--", label="uniformly random actions")
    a.set(xlabel="timesteps", ylabel=f"mean return, {episodes} held-out resets", title=f"SB3 PPO on {name}")
    b.plot(t, up * control_dt, "o-", ms=3)
    b.axhline(curve["random"][1] * control_dt, color="grey", ls="--")
    b.set(xlabel="timesteps", ylabel="mean time up (s)", title="time up before a fall or the episode's end")
    a.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("env", help="a Gymnasium id, e.g. evobiped/ReilBiped-v0")
    p.add_argument("--steps", type=int, default=500_000)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--seconds", type=float, default=10.0)
    p.add_argument("--every", type=int, default=10240)
    p.add_argument("--episodes", type=int, default=10)
    p.add_argument("--out", type=Path, required=True)
    a = p.parse_args(argv)
    if a.steps <= 0 or a.every <= 0 or a.episodes <= 0 or not a.seconds > 0:
        p.error("--steps, --every, --episodes and --seconds must be above 0")
    try:
        import stable_baselines3  # noqa: F401
    except ImportError:
        print("sb3_ppo: needs stable-baselines3: pip install -e \".[gym,rl]\"", file=sys.stderr)
        return 2
    a.out.mkdir(parents=True, exist_ok=True)
    curve = train(a.env, a.steps, seed=a.seed, seconds=a.seconds, every=a.every, episodes=a.episodes,
                  say=lambda s: print(s, flush=True))
    with open(a.out / "curve.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["timesteps", "mean_return", "mean_steps_up", "wall_s"])
        w.writerow([0, *curve["untrained"], 0.0])
        w.writerows(curve["rows"])
    import gymnasium

    control_dt = gymnasium.make(a.env, actions="unit").unwrapped.walkers.control_dt  # s per step
    figure(curve, a.env, a.out / "curve.png", a.episodes, control_dt)
    print(f"random policy {curve['random'][0]:.3f}; results in {a.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
