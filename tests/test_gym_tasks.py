"""Gymnasium environments as tasks: ``EpisodeConfig(env=ID)`` and ``evolve --env ID``; the return is the fitness, the
same on every backend and worker count, across a resume, and equal to a rollout of the same policy by hand."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("gymnasium")

from evobiped.core.errors import ConfigError  # noqa: E402
from evobiped.episode import EpisodeConfig  # noqa: E402
from evobiped.episode.gym_episode import reset_seeds  # noqa: E402
from evobiped.evaluation import make_evaluator  # noqa: E402
from evobiped.run import Run, RunConfig  # noqa: E402

from .conftest import cli  # noqa: E402
from .test_evolve import evolve_with, fitness_history  # noqa: E402
from .test_stopping import _evolve  # noqa: E402

HOPPER = EpisodeConfig(env="Hopper-v5", controller="linear", env_options={"max_steps": 150})
#: ARS V2-t on a short Hopper: 4 pairs, the running normaliser, 4 generations
ARS_TABLE = {"episode": HOPPER.to_dict(), "optimizer": "es", "generations": 4, "seed": 3, "backend": "serial",
             "normalise": {"running": True, "floor": 1e-3},
             "es": {"method": "ars", "pairs": 4, "top": 2, "sigma": 0.025, "learning_rate": 0.02}}
ARS = RunConfig.from_dict(ARS_TABLE)


def by_hand(env_id: str, genome: np.ndarray, seed: int, max_steps: int) -> float:
    """The return of the linear policy ``genome`` (biases, then weights input-major) in ``gymnasium.make(env_id)``
    from ``reset(seed=seed)``, each action clipped to the box, written here without the package's episode."""
    import gymnasium

    env = gymnasium.make(env_id, max_episode_steps=max_steps)
    obs, _ = env.reset(seed=seed)
    n = env.action_space.shape[0]
    b, W = genome[:n], genome[n:].reshape(len(obs), n)
    total = 0.0
    for _ in range(max_steps):
        action = np.clip(b + (obs[:, None] * W).sum(axis=0), env.action_space.low, env.action_space.high)
        obs, reward, terminated, truncated, _ = env.step(action)
        total += reward
        if terminated or truncated:
            break
    env.close()
    return total


def test_the_return_is_that_of_the_same_policy_rolled_out_by_hand():
    episode = HOPPER.build()
    genomes = np.random.default_rng(1).normal(0.0, 0.3, (3, HOPPER.layout().size))
    result = episode.run(genomes, trials=episode.trials_for((5, 2)))
    seeds = reset_seeds((5, 2), genomes)
    for g, s, f in zip(genomes, seeds, result.fitness):
        assert f == by_hand("Hopper-v5", g, s, 150)
    assert set(result.terms) == {"return", "length", "terminated"}
    assert (result.terms["return"] == result.fitness).all()
    assert (result.end_time == result.terms["length"] * 0.008).all()
    alone = episode.run(genomes[2], trials=(5, 2))  # a genome's return is its own, in any batch
    assert alone.fitness[0] == result.fitness[2]


def test_a_reward_shift_lowers_the_fitness_by_the_steps_and_leaves_the_return():
    shifted = EpisodeConfig(env="Hopper-v5", controller="linear", env_options={"max_steps": 150, "reward_shift": 1.0})
    genomes = np.random.default_rng(2).normal(0.0, 0.3, (2, HOPPER.layout().size))
    plain, less = HOPPER.build().run(genomes, trials=(0, 0)), shifted.build().run(genomes, trials=(0, 0))
    assert (less.terms["return"] == plain.fitness).all()
    assert (less.fitness == plain.fitness - less.terms["length"]).all()


def test_a_short_ars_run_improves_the_return(tmp_path):
    """The policy of zeros falls after about 135 steps; within 6 generations ARS stands the 400 steps and goes on."""
    episode = {**HOPPER.to_dict(), "env_options": {"max_steps": 400}}
    config = RunConfig.from_dict({**ARS_TABLE, "episode": episode, "generations": 6})
    run = Run.create(tmp_path / "ars", config)
    with make_evaluator(config.episode, "serial") as ev:
        summary = run.evolve(ev)
    best = [float(r[1]) for r in fitness_history(run.dir)]
    assert summary["best"]["fitness"] > best[0] + 200, best
    config = json.loads((run.dir / "config.json").read_text())
    assert config["episode"] == {"env": "Hopper-v5", "env_options": {"max_steps": 400}, "controller": "linear",
                                 "controller_options": {}}
    assert EpisodeConfig(**config["episode"]).to_dict() == config["episode"]


def test_history_identical_on_every_backend_and_worker_count(tmp_path):
    ref, best = evolve_with(tmp_path, "serial", "serial", config=ARS)
    runs = [evolve_with(tmp_path, name, backend, workers, config=ARS)
            for name, backend, workers in (("p1", "process", 1), ("p2", "process", 2), ("t2", "thread", 2))]
    pytest.importorskip("ray")
    runs.append(evolve_with(tmp_path, "ray", "ray", 2, config=ARS))
    for hist, b in runs:
        assert hist == ref
        assert b["genome"] == best["genome"] and b["fitness"] == best["fitness"]


def test_resume_equals_uninterrupted(tmp_path):
    ref, ref_best = evolve_with(tmp_path, "whole", "serial", config=ARS)
    run = _evolve(tmp_path / "cut", ARS, stop_at=1)
    assert len(fitness_history(run.dir)) == 2  # interrupted after its second generation
    resumed = Run.resume(run.dir)
    with make_evaluator(ARS.episode, "process", 2) as ev:
        resumed.evolve(ev)
    assert fitness_history(run.dir) == ref
    assert json.loads((run.dir / "best.json").read_text())["genome"] == ref_best["genome"]


@pytest.mark.parametrize("env, words", [("Nope-v0", "'Nope-v0' is no Gymnasium environment"),
                                         ("CartPole-v1", "Discrete action space")])
def test_evolve_refuses_an_unknown_id_or_a_space_that_is_no_box_in_one_line(tmp_path, capsys, env, words):
    assert cli("evolve", "--env", env, "--controller", "linear", "--generations", "1", "--out", tmp_path / "r") == 2
    err = capsys.readouterr().err
    assert words in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "r").exists()


def test_evolve_env_on_the_command_line(tmp_path, capsys):
    out = tmp_path / "cli"
    assert cli("evolve", "--env", "Hopper-v5", "--controller", "ctrnn", "--optimizer", "cma", "--generations", "2",
               "--backend", "serial", "--out", out) == 0
    assert "evolving Hopper-v5: ctrnn with cma" in capsys.readouterr().err
    assert json.loads((out / "best.json").read_text())["fitness"] > 0
    assert cli("replay", out) == 0  # the best's episode again, into a Rerun recording
    said = capsys.readouterr().out
    assert "the replay equals it bit for bit" in said and f"recording: {out / 'replay_best.rrd'}" in said
    data = (out / "replay_best.rrd").read_bytes()
    assert all(name in data for name in (b"world/bodies/torso", b"observation", b"action", b"reward", b"return"))
    assert cli("replay", out, "--video", tmp_path / "v.mp4") == 2


def test_a_run_its_budget_ends_counts_episodes_in_its_progress(tmp_path, capsys):
    """A run whose episode budget ends it long before its generations would says so and counts episodes, its time
    left from the budget (not from 100,000 generations)."""
    config = tmp_path / "b.toml"
    config.write_text('optimizer = "es"\ngenerations = 100000\nbudget = 34\n[episode]\nenv = "Hopper-v5"\n'
                      'controller = "linear"\n[episode.env_options]\nmax_steps = 20\n[es]\npairs = 8\n')
    assert cli("evolve", "--config", config, "--backend", "serial", "--out", tmp_path / "r") == 0
    err = capsys.readouterr().err
    assert "population 17, 34 episodes (its budget)" in err
    assert "evolve:  50% (17 of 34 episodes; generation 1;" in err and "(34 of 34 episodes; generation 2;" in err
    assert "generations;" not in err


BENCHMARKS = sorted(Path(__file__).parent.parent.glob("docs/benchmarks/*.toml"))


@pytest.mark.parametrize("path", BENCHMARKS, ids=lambda p: p.name)
def test_the_benchmark_settings_are_accepted(path):
    from evobiped.flags import run_config

    config = run_config(config=str(path))
    assert config.episode.env == {"hopper": "Hopper-v5", "walker2d": "Walker2d-v5"}[path.name.split("-")[0]]
    assert config.normalise.running and config.budget


def test_an_environment_episode_takes_no_body_settings():
    with pytest.raises(ConfigError, match="episode.seconds: .*env_options.max_steps"):
        EpisodeConfig(env="Hopper-v5", controller="linear", seconds=3.0)
    with pytest.raises(ConfigError, match="needs a controller"):
        EpisodeConfig(env="Hopper-v5", controller=None, control_dt=0.01)
    with pytest.raises(ConfigError, match="max_steps"):
        EpisodeConfig(env="Hopper-v5", controller="linear", env_options={"max_steps": 0})


def test_an_environment_without_a_mujoco_model_records_its_time_series_alone(tmp_path):
    from evobiped.record.recordings.gym_recording import GymRecorder, write_gym_recording

    episode = EpisodeConfig(env="Pendulum-v1", controller="linear", env_options={"max_steps": 30}).build()
    recorder = GymRecorder()
    result = episode.run(np.zeros((1, episode.controller.layout.size)), trials=(0, 0), listener=recorder)
    assert recorder.model is None and len(recorder.rewards) == 30 and result.terms["terminated"][0] == 0
    data = write_gym_recording(tmp_path / "p.rrd", recorder, name="pendulum").read_bytes()
    assert b"observation" in data and b"world/bodies" not in data


@pytest.mark.parametrize("env", ["evobiped/ReilBiped-v0", "evobiped/TagaBiped-v0"])
def test_this_package_s_own_environments_are_tasks_too(env):
    config = EpisodeConfig(env=env, controller="linear", env_options={"max_steps": 10})
    genomes = np.zeros((2, config.layout().size))
    result = config.build().run(genomes, trials=(0, 0))
    assert (result.terms["length"] == 10).all() and np.isfinite(result.fitness).all()
