"""``evobiped bench``: evaluation speed as ratios against raw MuJoCo stepping on the same cores.

Measurements in one process, on the same model, time step and genomes:

(a) raw: ``mujoco.rollout`` replays the controls recorded from (b) open-loop, no
    Python between physics steps: the limit to measure against; on one thread
    (a 1) and with one thread per worker (a N);
(b) evaluation: the full episode (controller in the loop, every tick through
    Python/numpy, ``mujoco.batch`` stepping in C) in this process, one thread;
(c) the process-pool evaluator with 1 worker and with ``workers`` workers;
(d) the thread evaluator with ``workers`` threads (one Episode each);
(e) with ``presentations`` R > 1: evaluation in this process of the same genomes on R
    perturbed presentations side by side in one batch (a push, target and pose noise),
    counted as R x the simulated seconds, so (b) / (e) is the cost of perturbed
    evaluation per simulated second relative to one presentation (1 = no extra cost);
    (a e) replays each of its rows open-loop with ``mujoco.rollout`` on 1 thread (its own
    initial state, controls and push forces), so (e) / (a e) is its efficiency against
    the physics it integrates (disturbed walkers move differently, and their physics
    alone may cost more per step than undisturbed ones).

Episodes run to the full length (``EpisodeConfig.stop_on_fall=False``) so that every
measurement integrates exactly the same physics.  Every figure is simulated seconds per
wall-clock second (sim-s/s), summed over all walkers.

Each measurement is repeated ``repeats`` times, interleaved ((a 1), (b), (a N), (c N),
(d N), (c 1), then again ...), and reported as its median: interleaving exposes both
sides of a ratio to the same background, and the median neither rewards a lucky
repeat nor punishes one disturbed by another job.  The efficiencies are
(b) / (a 1) for one core and (c N) / (a N), (d N) / (a N) for all; the scaling is
(a N) / (a 1) and (c N) / (c 1).
"""

from __future__ import annotations

import os
import time
from dataclasses import replace

import mujoco
import numpy as np
from mujoco import rollout

from ..episode import Context, EpisodeConfig
from ..core.errors import ConfigError
from ..evaluation import ProcessPoolEvaluator, ThreadEvaluator
from ..optimizers import GA, GAOptions
from ..core.progress import Progress

#: the disturbances of measurement (e), per presentation (see evobiped.physics.perturb)
PERTURBED = dict(pushes=1, push_force=5.0, push_after=1.0, target_noise=0.01, pose_noise=0.01)

#: ``bench(..., **QUICK)``: a run of well under 30 s
QUICK = dict(population=16, seconds=4.0, repeats=5)


class _ControlRecorder:
    """Listener: the model, each walker's initial full-physics state ``(P, nstate)``, and its actuator
    controls at every tick ``(ticks, P, nu)``; with ``forces`` also the applied body forces ``(ticks, P, nbody * 6)``:
    everything ``mujoco.rollout`` needs to replay the episode open-loop."""

    SPEC = mujoco.mjtState.mjSTATE_FULLPHYSICS

    def __init__(self, forces: bool = False):
        self.forces = forces

    def start(self, episode, sims):
        self.ctrl, self.xfrc, self.model = [], [], sims.model
        d = mujoco.MjData(sims.model)
        self.initial = np.empty((sims.n, mujoco.mj_stateSize(sims.model, self.SPEC)))
        for i in range(sims.n):
            mujoco.mj_resetData(sims.model, d)
            d.qpos[:], d.qvel[:] = sims.qpos[i], sims.qvel[i]
            mujoco.mj_getState(sims.model, d, self.initial[i], self.SPEC)

    def tick(self, t, sims, ids, neurons, action, task_state):
        self.ctrl.append(sims.ctrl.copy())
        if self.forces:
            self.xfrc.append(sims.xfrc_applied.reshape(sims.n, -1).copy())

    def end(self, result):
        pass


def _walls(fns: dict, repeats: int, progress: Progress | None = None) -> dict:
    """Wall seconds of each callable, ``repeats`` times in turn: ``{name: [s, ...]}``."""
    walls = {k: [] for k in fns}
    for r in range(repeats):
        for i, (k, fn) in enumerate(fns.items()):
            t0 = time.perf_counter()
            fn()
            walls[k].append(time.perf_counter() - t0)
            if progress is not None:
                progress.update(r * len(fns) + i + 1, f"{k} took {walls[k][-1]:.1f} s")
    return walls


def bench(
    episode: EpisodeConfig | None = None,
    *,
    population: int = 50,
    workers: int | None = None,
    repeats: int = 5,
    seed: int = 0,
    presentations: int = 1,
    progress: Progress | None = None,
    context: Context | None = None,
) -> dict:
    """Measure (a)-(e) for ``population`` random genomes (Table III initialisation); ``progress``
    (optional) hears each finished measurement; ``context``: what a run sets for its evaluations (e.g. senses
    collected for a running normaliser), in (b)-(d)."""
    say = progress.say if progress is not None else (lambda msg: None)
    episode = episode or EpisodeConfig()
    workers = workers or os.cpu_count() or 1
    if population < 1 or workers < 1 or repeats < 1 or presentations < 1:
        raise ConfigError("bench: population, workers, repeats and presentations must be >= 1")
    config = replace(episode, stop_on_fall=False)
    ep = config.build()
    if ep.body.has_custom_forces:
        raise ConfigError(f"bench: body {config.body!r} adds forces in Python between physics steps; (a) cannot replay "
                          "it open-loop")
    genomes = GA(ep.controller.layout, GAOptions(population=max(2, population)), seed=seed).ask()[0][:population]

    ep.run(genomes[:1], seconds=ep.control_dt)  # warm up (allocations)
    rec = _ControlRecorder()
    result = ep.run(genomes, listener=rec)
    ctrl = np.repeat(np.stack(rec.ctrl, axis=1), ep.substeps, axis=1)  # (P, nstep, nu)
    model, initial = ep.model, rec.initial  # a row for each walker and each of the task's presentations
    rows = len(initial)
    sim_seconds = rows * ep.n_ticks * ep.control_dt
    data = [mujoco.MjData(model) for _ in range(workers)]
    nstep = ctrl.shape[1]
    finals = np.empty((rows, model.nq))
    threads = rollout.Rollout(nthread=workers) if workers > 1 else None

    def raw(n: int):
        """1 thread: one walker at a time; n threads: groups of 4 n walkers shared out one at a time
        (a group's whole trajectory is held in memory; several walkers per thread balance the load)."""
        group = 1 if n == 1 else 4 * n

        def go():
            for p in range(0, rows, group):
                if n == 1:
                    state, _ = rollout.rollout(model, data[0], initial[p : p + 1], ctrl[p : p + 1], nstep=nstep)
                else:
                    state, _ = threads.rollout(model, data[:n], initial[p : p + group], ctrl[p : p + group],
                                               nstep=nstep, chunk_size=1)
                finals[p : p + len(state)] = state[:, -1, 1 : 1 + model.nq]
        return go

    gaps: list[float] = []  # (a e)'s end positions against (e)'s, m

    def raw_perturbed(perturbed, trials):
        """1 thread, one row at a time: each perturbed row's own start, controls and pushes replayed open-loop
        (the physics (e) integrates, without the controller), on the model of the generation's friction."""
        rec = _ControlRecorder(forces=True)
        rows = perturbed.run(genomes, trials=trials, listener=rec).rows
        spec = mujoco.mjtState.mjSTATE_CTRL | mujoco.mjtState.mjSTATE_XFRC_APPLIED
        controls = np.repeat(np.concatenate([np.stack(rec.ctrl, axis=1), np.stack(rec.xfrc, axis=1)], axis=2),
                             perturbed.substeps, axis=1)
        d = mujoco.MjData(rec.model)
        ends = np.empty((len(controls), 2))

        def go():
            for p in range(len(controls)):
                state, _ = rollout.rollout(rec.model, d, rec.initial[p : p + 1], controls[p : p + 1], control_spec=spec,
                                           nstep=controls.shape[1])
                ends[p] = state[0, -1, 1:3]
            gaps.append(float(np.max(np.abs(ends - rows.end_position))))
        return go

    say(f"{population} walkers x {config.seconds:g} s, {repeats} interleaved repeat(s) of: raw stepping "
        f"(mujoco.rollout) on 1 and {workers} thread(s), evaluation in this process, process pools of 1 and {workers}, "
        f"{workers} thread(s) ...")
    sizes = sorted({1, workers})
    pools = {n: ProcessPoolEvaluator(config, n) for n in sizes}
    thread_ev = ThreadEvaluator(config, workers)
    try:
        for pool in (*pools.values(), thread_ev):
            pool.evaluate(genomes[: min(population, workers)], context=context)  # start the workers, build their models
        fns = {"raw 1": raw(1), "eval": lambda: ep.run(genomes, context=context)}
        if workers > 1:
            fns[f"raw {workers}"] = raw(workers)
        fns[f"pool {workers}"] = lambda: pools[workers].evaluate(genomes, context=context)
        fns[f"threads {workers}"] = lambda: thread_ev.evaluate(genomes, context=context)
        if workers > 1:
            fns["pool 1"] = lambda: pools[1].evaluate(genomes, context=context)
        if presentations > 1:
            perturbed = replace(config, perturbations=dict(PERTURBED, presentations=presentations)).build()
            trials = perturbed.trials_for((seed, 0))
            fns[f"eval x{presentations}"] = lambda: perturbed.run(genomes, trials=trials)
            fns[f"raw x{presentations}"] = raw_perturbed(perturbed, trials)
        if progress is not None:
            progress.total = float(len(fns) * repeats)
            progress.unit = "measurements"
        walls = _walls(fns, repeats, progress)
        by_row = result.rows if result.rows is not None else result
        stable = ~np.asarray(by_row.unstable, bool).reshape(rows)  # a blow-up ends the episode's row, not the replay's
        end_gap = float(np.max(np.abs(finals[stable, :2] - by_row.end_position.reshape(rows, 2)[stable]),
                               initial=0.0))
    finally:
        for pool in (*pools.values(), thread_ev):
            pool.close()
        if threads is not None:
            threads.close()
    simulated = {k: sim_seconds * (presentations if " x" in k else 1) for k in walls}
    median = {k: simulated[k] / float(np.median(v)) for k, v in walls.items()}
    raw_n = median[f"raw {workers}"] if workers > 1 else median["raw 1"]
    pool_1 = median["pool 1"] if workers > 1 else median[f"pool {workers}"]
    return {
        "body": config.body,
        "controller": config.controller,
        "kernel": "compiled" if ep.compiled else "numpy",
        "timestep_s": model.opt.timestep,
        "control_dt_s": ep.control_dt,
        "population": population,
        "rows": rows,
        "episode_seconds": config.seconds,
        "simulated_seconds": sim_seconds,
        "simulated_seconds_each": simulated,
        "repeats": repeats,
        "workers": workers,
        "cpu_count": os.cpu_count(),
        "median_sim_s_per_s": median,
        "efficiency_one_core": median["eval"] / median["raw 1"],
        "efficiency_pool": median[f"pool {workers}"] / raw_n,
        "efficiency_threads": median[f"threads {workers}"] / raw_n,
        "scaling_raw": raw_n / median["raw 1"],
        "scaling_pool": median[f"pool {workers}"] / pool_1,
        "presentations": presentations,
        "presentation_cost": median["eval"] / median[f"eval x{presentations}"] if presentations > 1 else None,
        "efficiency_presentations": median[f"eval x{presentations}"] / median[f"raw x{presentations}"]
            if presentations > 1 else None,
        "replay_end_position_gap_m": end_gap,
        "replay_blow_ups": int(rows - stable.sum()),
        "replay_presentations_gap_m": max(gaps) if gaps else None,
        "wall_seconds": walls,
    }


def format_bench(r: dict) -> str:
    m, w = r["median_sim_s_per_s"], r["workers"]
    sim = r["simulated_seconds_each"]
    spread = {k: (sim[k] / max(v), sim[k] / min(v)) for k, v in r["wall_seconds"].items()}
    names = {"raw 1": "(a) raw stepping, rollout 1 thread", f"raw {w}": f"(a) raw stepping, rollout {w} threads",
             "eval": "(b) evaluation, 1 process", "pool 1": "(c) process pool, 1 worker",
             f"pool {w}": f"(c) process pool, {w} workers", f"threads {w}": f"(d) thread evaluator, {w} threads",
             f"raw x{r['presentations']}": "(a e) raw stepping of (e)'s rows, 1 thread",
             f"eval x{r['presentations']}": f"(e) evaluation, {r['presentations']} presentations"}
    lines = [
        f"{r['body']}/{r['controller']}: {r['population']} walker(s)"
        + (f" x {r['rows'] // r['population']} presentations" if r["rows"] != r["population"] else "")
        + f" x {r['episode_seconds']:g} s, "
        f"physics step {r['timestep_s'] * 1000:g} ms, control step {r['control_dt_s'] * 1000:g} ms, "
        f"{r['cpu_count']} cores, {r['kernel']} kernel",
        f"median of {r['repeats']} interleaved repeat(s), sim-s/s [slowest, fastest repeat]",
    ]
    for k in names:
        if k in m:
            lines.append(f"{names[k]:<40} {m[k]:9.1f}  [{spread[k][0]:.1f}, {spread[k][1]:.1f}]")
    lines += [
        f"efficiency: 1 core (b)/(a 1) = {r['efficiency_one_core']:.3f}   {w} cores: pool (c {w})/(a {w}) = "
        f"{r['efficiency_pool']:.3f}, threads (d {w})/(a {w}) = {r['efficiency_threads']:.3f}",
        f"scaling 1 -> {w}: raw {r['scaling_raw']:.2f}x, pool {r['scaling_pool']:.2f}x",
        *([f"{r['presentations']} perturbed presentations: cost per simulated second vs one (b)/(e) = "
           f"{r['presentation_cost']:.3f}; efficiency against the raw stepping of their own physics (e)/(a e) = "
           f"{r['efficiency_presentations']:.3f} (one presentation: (b)/(a 1) = {r['efficiency_one_core']:.3f})"]
          if r["presentations"] > 1 else []),
        f"open-loop replay of (b)'s controls ends within {r['replay_end_position_gap_m']:.2g} m of (b)"
        + (f" (its {r['replay_blow_ups']} blown-up row(s) left out: a blow-up ends a row of (b), not its replay)"
           if r["replay_blow_ups"] else "")
        + (f", of (e)'s within {r['replay_presentations_gap_m']:.2g} m of (e)" if r["presentations"] > 1 else ""),
    ]
    return "\n".join(lines)
