"""The gravity curriculum ([episode.perturbations] gravity): a share of the model's gravity, scheduled over the
generations, under which an inverted pendulum falls more slowly; a run's stopping rule waits for the full gravity."""

import dataclasses

import numpy as np
import pytest

from evobiped.cli import main
from evobiped.episode import Context
from evobiped.flags import run_config
from evobiped.physics.perturb import PerturbationOptions
from evobiped.physics.trials import Trials


def test_the_ground_s_model_has_that_share_of_the_gravity_on_the_flat_and_on_a_slope():
    ep = dataclasses.replace(run_config(preset="walker-ctrnn-walk").episode.nominal(), seconds=1.0).build()
    g0 = ep.model.opt.gravity.copy()
    assert ep.sims(1, gravity=0.25).model.opt.gravity == pytest.approx(0.25 * g0)
    tilted = ep.sims(1, slope=0.1, gravity=0.5).model.opt.gravity
    assert np.linalg.norm(tilted) == pytest.approx(0.5 * np.linalg.norm(g0))
    assert np.arctan2(-tilted[0], -tilted[2]) == pytest.approx(np.arctan(0.1))  # tilted down the 10 % grade
    assert np.array_equal(ep.model.opt.gravity, g0) and ep.sims(1).model is ep.model  # the episode's own is as built


def test_a_standing_network_falls_about_twice_as_slowly_under_a_quarter_of_the_gravity():
    """The preset's start network holds its pose and topples as an inverted pendulum, whose fall scales with
    sqrt(L / g): a quarter of g, twice the time (the PD servos and the contacts do not scale, hence the margin)."""
    ep = dataclasses.replace(run_config(preset="walker-ctrnn-walk").episode.nominal(), seconds=12.0).build()
    genome = np.asarray(ep.controller.layout.init_mean, float)[None]
    offsets = np.random.default_rng(0).normal(0.0, 0.01, (4, 6))
    up = {s: np.mean([ep.run(genome, context=Context(observe=False),
                             trials=Trials.nominal(1, 6, pose_offset=o[None], gravity=s)).end_time[0]
                      for o in offsets]) for s in (1.0, 0.25)}
    assert up[1.0] < 3.0 and 1.6 < up[0.25] / up[1.0] < 4.0


def test_the_gravity_follows_its_schedule_and_its_generations_do_not_compare():
    p = PerturbationOptions(gravity={"start": 0.25, "end": 1.0, "generations": 10})
    assert p.active and p.comparable_from == 10
    assert [p.draw((1, g), seconds=5.0, n_actuators=6).gravity for g in (0, 5, 10, 20)] == [0.25, 0.625, 1.0, 1.0]
    plain = PerturbationOptions(pose_noise=0.01)
    assert plain.draw((1, 3), seconds=5.0, n_actuators=6).gravity == 1.0 and not PerturbationOptions().active


@pytest.mark.parametrize("value, words", [("0.0", "gravity"), ("1.5", "gravity"),
                                          ("{start = -0.5, end = 1.0, generations = 5}", "gravity")])
def test_a_bad_gravity_is_one_line_and_writes_nothing(tmp_path, capsys, value, words):
    (tmp_path / "c.toml").write_text(f"[episode.perturbations]\ngravity = {value}\n")
    code = main(["evolve", "--config", str(tmp_path / "c.toml"), "--out", str(tmp_path / "out"), "--generations", "1"])
    err = capsys.readouterr().err
    assert code == 2 and words in err and len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert not (tmp_path / "out").exists()
