"""``evobiped bench``: evaluation speed as ratios against raw MuJoCo stepping.

Three measurements in one process, on the same model, time step and genomes:

(a) raw: ``mujoco.rollout`` replays the controls recorded from (b) open-loop,
    one thread, no Python between physics steps: the limit to measure against;
(b) evaluation: the full episode (controller in the loop, every tick through
    Python/numpy, ``mujoco.batch`` stepping in C) in this process, one thread;
(c) the process-pool evaluator with 1 worker and with ``workers`` workers.

Episodes run to the full length (``EpisodeConfig.stop_on_fall=False``) so that (a), (b)
and (c) integrate exactly the same physics.
Every figure is simulated seconds per wall-clock second (sim-s/s), summed
over all walkers.
"""

from __future__ import annotations

import os
import time
from dataclasses import replace

import mujoco
import numpy as np
from mujoco import rollout

from .episode import EpisodeConfig
from .errors import ConfigError
from .evolution.evaluate import ProcessPoolEvaluator
from .evolution.ga import GA, GAConfig

class _ControlRecorder:
    """Listener: the actuator controls of every walker at every tick, ``(ticks, P, nu)``."""

    def start(self, episode, sims):
        self.ctrl = []

    def tick(self, t, sims, ids, neurons, action, task_state):
        self.ctrl.append(sims.ctrl.copy())

    def end(self, result):
        pass


def _rate(sim_seconds: float, fn) -> tuple[float, float]:
    t0 = time.perf_counter()
    fn()
    wall = time.perf_counter() - t0
    return sim_seconds / wall, wall


def bench(episode: EpisodeConfig | None = None, *, population: int = 50, workers: int | None = None, seed: int = 0, progress=None) -> dict:
    """Measure (a), (b), (c) for ``population`` random genomes (Table III initialisation)."""
    say = progress or (lambda msg: None)
    episode = episode or EpisodeConfig()
    workers = workers or os.cpu_count() or 1
    if population < 1 or workers < 1:
        raise ConfigError("bench: population and workers must be >= 1")
    config = replace(episode, stop_on_fall=False)
    ep = config.build()
    if ep.body.has_custom_forces:
        raise ConfigError(f"bench: body {config.body!r} adds forces in Python between physics steps; (a) cannot replay it open-loop")
    genomes = GA(ep.controller.layout, GAConfig(population=max(2, population)), seed=seed).ask()[0][:population]
    sim_seconds = population * ep.n_ticks * ep.control_dt

    say(f"(b) closed-loop evaluation of {population} walkers x {config.seconds:g} s in this process ...")
    ep.run(genomes[:1], seconds=ep.control_dt)  # warm up (allocations)
    rate_b, wall_b = _rate(sim_seconds, lambda: ep.run(genomes))

    rec = _ControlRecorder()
    result = ep.run(genomes, listener=rec)
    ctrl = np.repeat(np.stack(rec.ctrl, axis=1), ep.substeps, axis=1)  # (P, nstep, nu)
    model, data = ep.model, mujoco.MjData(ep.model)
    sims = ep.sims(1)
    ep.body.reset(sims)
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    initial = np.empty(mujoco.mj_stateSize(model, spec))
    mujoco.mj_resetData(model, data)
    data.qpos[:], data.qvel[:] = sims.qpos[0], sims.qvel[0]
    mujoco.mj_getState(model, data, initial, spec)
    nstep = ctrl.shape[1]
    finals = np.empty((population, model.nq))

    def raw():
        for p in range(population):  # one walker at a time keeps the output buffer small
            state, _ = rollout.rollout(model, data, initial[None], ctrl[p : p + 1], nstep=nstep)
            finals[p] = state[0, -1, 1 : 1 + model.nq]

    say(f"(a) raw MuJoCo stepping: mujoco.rollout of the same controls, {population * nstep} steps ...")
    rate_a, wall_a = _rate(sim_seconds, raw)
    end_gap = float(np.max(np.abs(finals[:, :2] - result.end_position))) if population else 0.0

    rates_c = {}
    for n in sorted({1, workers}):
        say(f"(c) process pool with {n} worker(s) ...")
        with ProcessPoolEvaluator(config, n) as pool:
            pool.evaluate(genomes[: min(population, n)])  # start the workers, build their models
            rates_c[n], _ = _rate(sim_seconds, lambda: pool.evaluate(genomes))

    return {
        "body": config.body,
        "controller": config.controller,
        "timestep_s": model.opt.timestep,
        "control_dt_s": ep.control_dt,
        "population": population,
        "episode_seconds": config.seconds,
        "simulated_seconds": sim_seconds,
        "raw_sim_s_per_s": rate_a,
        "eval_sim_s_per_s": rate_b,
        "pool_sim_s_per_s": {str(k): v for k, v in rates_c.items()},
        "workers": workers,
        "cpu_count": os.cpu_count(),
        "ratio_eval_over_raw": rate_b / rate_a,
        "speedup_all_over_1": rates_c[workers] / rates_c[1],
        "replay_end_position_gap_m": end_gap,
        "wall_seconds": {"raw": wall_a, "eval": wall_b},
    }


def format_bench(r: dict) -> str:
    lines = [
        f"{r['body']}/{r['controller']}: {r['population']} walker(s) x {r['episode_seconds']:g} s, "
        f"physics step {r['timestep_s'] * 1000:g} ms, control step {r['control_dt_s'] * 1000:g} ms, {r['cpu_count']} cores",
        f"(a) raw MuJoCo stepping (rollout, 1 thread)   {r['raw_sim_s_per_s']:10.1f} sim-s/s",
        f"(b) episode evaluation (1 process)            {r['eval_sim_s_per_s']:10.1f} sim-s/s",
    ]
    for n, v in r["pool_sim_s_per_s"].items():
        lines.append(f"(c) process pool, {n:>2} worker(s)               {v:10.1f} sim-s/s")
    lines += [
        f"b/a = {r['ratio_eval_over_raw']:.3f}   (c {r['workers']})/(c 1) = {r['speedup_all_over_1']:.2f}x",
        f"open-loop replay of (b)'s controls ends within {r['replay_end_position_gap_m']:.2g} m of (b)",
    ]
    return "\n".join(lines)
