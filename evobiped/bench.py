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

Each measurement is repeated ``repeats`` times, interleaved ((a), (b), (a), (b),
...; then (c 1), (c all), (c 1), ...), and reported as its fastest repeat, as
``timeit`` does: on a shared machine other jobs only ever slow a measurement
down, so the fastest repeat is the closest to the machine's own speed, and
interleaving exposes both sides of a ratio to the same background.  The
slowest repeat is reported too.
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


def _walls(fns: dict, repeats: int) -> dict:
    """Wall seconds of each callable, ``repeats`` times in turn: ``{name: [s, ...]}``."""
    walls = {k: [] for k in fns}
    for _ in range(repeats):
        for k, fn in fns.items():
            t0 = time.perf_counter()
            fn()
            walls[k].append(time.perf_counter() - t0)
    return walls


def bench(
    episode: EpisodeConfig | None = None,
    *,
    population: int = 50,
    workers: int | None = None,
    repeats: int = 3,
    seed: int = 0,
    progress=None,
) -> dict:
    """Measure (a), (b), (c) for ``population`` random genomes (Table III initialisation)."""
    say = progress or (lambda msg: None)
    episode = episode or EpisodeConfig()
    workers = workers or os.cpu_count() or 1
    if population < 1 or workers < 1 or repeats < 1:
        raise ConfigError("bench: population, workers and repeats must be >= 1")
    config = replace(episode, stop_on_fall=False)
    ep = config.build()
    if ep.body.has_custom_forces:
        raise ConfigError(f"bench: body {config.body!r} adds forces in Python between physics steps; (a) cannot replay it open-loop")
    genomes = GA(ep.controller.layout, GAConfig(population=max(2, population)), seed=seed).ask()[0][:population]
    sim_seconds = population * ep.n_ticks * ep.control_dt

    ep.run(genomes[:1], seconds=ep.control_dt)  # warm up (allocations)
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

    say(
        f"(a) raw MuJoCo stepping (mujoco.rollout of the same controls) and (b) closed-loop evaluation "
        f"of {population} walkers x {config.seconds:g} s in this process, {repeats} time(s) each ..."
    )
    walls = _walls({"raw": raw, "eval": lambda: ep.run(genomes)}, repeats)
    end_gap = float(np.max(np.abs(finals[:, :2] - result.end_position))) if population else 0.0

    sizes = sorted({1, workers})
    say(f"(c) process pools with {' and '.join(map(str, sizes))} worker(s), {repeats} time(s) each ...")
    pools = [ProcessPoolEvaluator(config, n) for n in sizes]
    try:
        for n, pool in zip(sizes, pools):
            pool.evaluate(genomes[: min(population, n)])  # start the workers, build their models
        walls.update(_walls({n: (lambda p=pool: p.evaluate(genomes)) for n, pool in zip(sizes, pools)}, repeats))
    finally:
        for pool in pools:
            pool.close()
    best = {k: sim_seconds / min(v) for k, v in walls.items()}
    worst = {k: sim_seconds / max(v) for k, v in walls.items()}
    rate_a, rate_b = best["raw"], best["eval"]
    rates_c = {n: best[n] for n in sizes}

    return {
        "body": config.body,
        "controller": config.controller,
        "timestep_s": model.opt.timestep,
        "control_dt_s": ep.control_dt,
        "population": population,
        "episode_seconds": config.seconds,
        "simulated_seconds": sim_seconds,
        "repeats": repeats,
        "raw_sim_s_per_s": rate_a,
        "eval_sim_s_per_s": rate_b,
        "pool_sim_s_per_s": {str(k): v for k, v in rates_c.items()},
        "slowest_repeat_sim_s_per_s": {str(k): v for k, v in worst.items()},
        "workers": workers,
        "cpu_count": os.cpu_count(),
        "ratio_eval_over_raw": rate_b / rate_a,
        "speedup_all_over_1": rates_c[workers] / rates_c[1],
        "replay_end_position_gap_m": end_gap,
        "wall_seconds": {str(k): v for k, v in walls.items()},
    }


def format_bench(r: dict) -> str:
    slow = r["slowest_repeat_sim_s_per_s"]
    lines = [
        f"{r['body']}/{r['controller']}: {r['population']} walker(s) x {r['episode_seconds']:g} s, "
        f"physics step {r['timestep_s'] * 1000:g} ms, control step {r['control_dt_s'] * 1000:g} ms, {r['cpu_count']} cores",
        f"fastest of {r['repeats']} interleaved repeat(s), sim-s/s (slowest repeat in brackets)",
        f"(a) raw MuJoCo stepping (rollout, 1 thread)   {r['raw_sim_s_per_s']:10.1f}  ({slow['raw']:.1f})",
        f"(b) episode evaluation (1 process)            {r['eval_sim_s_per_s']:10.1f}  ({slow['eval']:.1f})",
    ]
    for n, v in r["pool_sim_s_per_s"].items():
        lines.append(f"(c) process pool, {n:>2} worker(s)               {v:10.1f}  ({slow[n]:.1f})")
    lines += [
        f"b/a = {r['ratio_eval_over_raw']:.3f}   (c {r['workers']})/(c 1) = {r['speedup_all_over_1']:.2f}x",
        f"open-loop replay of (b)'s controls ends within {r['replay_end_position_gap_m']:.2g} m of (b)",
    ]
    return "\n".join(lines)
