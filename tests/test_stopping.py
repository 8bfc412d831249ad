"""The stopping rule ([stop]): a run ends when its evaluation walkers met the condition for k generations running, at
the same generation uninterrupted and resumed; the walking rule is the gait lab's criteria; bad rules are one line."""

import json

import numpy as np
import pytest

from evobiped.core.errors import ConfigError
from evobiped.episode import EpisodeConfig
from evobiped.run import Run, RunConfig
from evobiped.evaluation import make_evaluator
from evobiped.run.stopping import StopOptions, streak

from .conftest import cli
from .test_evolve import Stop, fitness_history


def _config(**stop) -> RunConfig:
    ga = {"population": 8}
    return RunConfig.from_dict({"episode": {"seconds": 1.5}, "ga": ga, "generations": 12, "seed": 3,
                                "backend": "serial", "stop": stop})


def _evolve(path, config, stop_at=None) -> Run:
    run = Run.create(path, config)

    def hook(stats):
        if stats.generation == stop_at:
            raise Stop

    with make_evaluator(config.episode, "serial") as ev:
        try:
            run.evolve(ev, hook)
        except Stop:
            pass
    return run


def test_a_fitness_rule_stops_where_the_history_says_and_a_resume_stops_there_too(tmp_path):
    plain = _evolve(tmp_path / "plain", _config())
    # the GA's fittest of each generation is its evaluation walker
    best = [float(r[1]) for r in fitness_history(plain.dir)]
    above = float(np.quantile(best, 0.4))
    met = [b >= above for b in best]
    want = next(g for g in range(1, len(met)) if met[g] and met[g - 1])  # the first of two generations running
    config = _config(when="fitness", above=above, generations=2)
    whole = _evolve(tmp_path / "whole", config)
    assert len(fitness_history(whole.dir)) == want + 1 < 12
    assert json.loads((whole.dir / "summary.json").read_text())["stopped_early"] is True
    cut = _evolve(tmp_path / "cut", config, stop_at=max(want - 1, 0))
    resumed = Run.resume(cut.dir)
    with make_evaluator(config.episode, "serial") as ev:
        resumed.evolve(ev)
    assert fitness_history(cut.dir) == fitness_history(whole.dir)
    assert cli("evolve", "--resume", whole.dir, "--quiet") == 0  # already complete: nothing more


def test_the_walking_rule_reads_the_gait_terms():
    rule = StopOptions(when="walking", generations=2)
    walk = {"duty_min": np.array([0.55]), "airborne": np.array([0.0]), "duty_asymmetry": np.array([0.01]),
            "slip_share": np.array([0.03]), "forward": np.array([8.0]), "time_up": np.array([20.0])}
    assert rule.met(walk, np.array([False]), np.array([1.0]))
    assert not rule.met(walk, np.array([True]), np.array([1.0]))  # a fall
    assert not rule.met({**walk, "airborne": np.array([0.05])}, np.array([False]), np.array([1.0]))  # a flight phase
    assert not rule.met({**walk, "forward": np.array([4.0])}, np.array([False]), np.array([1.0]))  # 0.2 m/s: too slow
    assert streak([{"stop_met": True}, {"stop_met": False}, {"stop_met": True}, {"stop_met": True}]) == 2


def test_bad_stopping_rules_are_one_line(tmp_path, capsys):
    with pytest.raises(ConfigError, match="gait terms"):
        RunConfig(episode=EpisodeConfig(), stop=StopOptions(when="walking"))
    with pytest.raises(ConfigError, match="finite"):
        StopOptions(when="fitness", above=float("nan"))
    bad = tmp_path / "bad.toml"
    bad.write_text('[stop]\nwhen = "walking"\n')
    assert cli("evolve", "--config", bad, "--out", tmp_path / "r", "--quiet") == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "gait terms" in err[0] and not (tmp_path / "r").exists()


def test_the_walking_rule_reads_each_presentation_of_a_perturbed_es_run(tmp_path):
    """ES's evaluation walkers under per-generation perturbations have terms per presentation ((genomes, R)): the rule
    reads every presentation (it once raised a TypeError there)."""
    config = RunConfig.from_dict({
        "optimizer": "es", "es": {"pairs": 2}, "generations": 2, "seed": 1, "backend": "serial",
        "stop": {"when": "walking", "generations": 1},
        "episode": {"seconds": 0.5, "task_options": {"fitness": "weighted", "gait_terms": True,
                                                     "weights": {"forward": 1.0, "airborne": -1.0}},
                    "perturbations": {"presentations": 2, "pose_noise": 0.01}}})
    run = _evolve(tmp_path / "es", config)
    history = fitness_history(run.dir)
    assert len(history) == 2 and json.loads((run.dir / "summary.json").read_text())["stopped_early"] is False


def test_a_run_stopped_by_its_rule_is_read_and_selected_like_any_other(tmp_path):
    from evobiped.files.rundir import read_history

    plain = _evolve(tmp_path / "plain", _config())
    above = float(np.quantile([float(r[1]) for r in fitness_history(plain.dir)], 0.4))
    run = _evolve(tmp_path / "stopped", _config(when="fitness", above=above, generations=2))
    history = read_history(run.dir / "history.csv")  # stop_met is a number like every column
    assert set(history["stop_met"]) <= {0.0, 1.0} and history["stop_met"][-1] == 1.0
    assert cli("select", run.dir, "--top", 2, "--seconds", 3) == 0 and (run.dir / "selected.json").is_file()


@pytest.mark.parametrize("help", [{"assist": 10.0, "assist_generations": 4},
                                  {"gravity": {"start": 0.5, "end": 1.0, "generations": 4}}])
def test_no_rule_is_met_while_the_walkers_are_helped(tmp_path, help):
    """A walker held up by the assistance, or under less than the model's gravity, does not walk: the stopping rule
    counts only generations without help (met in every generation here, it stops two generations after the help
    has gone at generation 4)."""
    config = _config(when="fitness", above=-1e9, generations=2)
    assert len(fitness_history(_evolve(tmp_path / "plain", config).dir)) == 2
    helped = RunConfig.from_dict({**config.to_dict(), "episode": {"seconds": 1.5, "perturbations": help}})
    assert len(fitness_history(_evolve(tmp_path / "helped", helped).dir)) == 6
