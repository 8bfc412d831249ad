"""The pelvis assistance (a curriculum that holds the trunk upright, faded to zero) and the gait senses."""

import json

import numpy as np
import pytest

from evobiped.cli import main
from evobiped.episode import EpisodeConfig
from evobiped.optimizers.cma import CMAOptions
from evobiped.evaluation import make_evaluator
from evobiped.run.run import Run
from evobiped.run.run_config import RunConfig
from evobiped.files.genome_file import load_genome
from evobiped.episode.disturbances import assist_torque
from evobiped.physics.perturb import PerturbationOptions
from evobiped.physics.trials import Trials

from .conftest import WALKERS
from .test_evolve import fitness_history, whole_and_resumed


def _rot_x(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def test_assist_torque_restores_upright_and_damps_tilting_only():
    # a trunk rolled by +0.3 rad about x (its up axis towards -y): the torque turns it back, -k sin(0.3) about x
    R = _rot_x(0.3)
    tau = assist_torque(np.array([20.0]), 0.05, R.reshape(1, 9), np.zeros((1, 3)))
    assert tau[0] == pytest.approx([-20 * np.sin(0.3), 0.0, 0.0])
    # spinning about the vertical (turning) is not resisted; tilting rates are, by c = 0.05 s * k
    tau = assist_torque(np.array([20.0]), 0.05, np.eye(3).reshape(1, 9), np.array([[1.0, -2.0, 5.0]]))
    assert tau[0] == pytest.approx([-1.0, 2.0, 0.0])


def test_assistance_fades_to_zero_on_its_clock():
    p = PerturbationOptions(presentations=2, assist=30.0, assist_generations=10, assist_levels=[1.0, 0.5])
    assert [p.assist_at(c) for c in (0, 5, 10, 12)] == [30.0, 15.0, 0.0, 0.0]
    trials = p.draw((1, 4), seconds=10.0, n_actuators=6)
    assert trials.assist == pytest.approx([18.0, 9.0])  # generation 4 of 10: 0.6 of 30, at the two levels
    assert p.draw((1, 10), seconds=10.0, n_actuators=6).assist is None
    gated = PerturbationOptions(assist=30.0, assist_generations=10, assist_gate=2.0)
    # the clock counts the earlier generations whose best reached 2 m, and the third key element is that clock
    assert gated.assist_clock(4, [0.5, 2.5, 1.0, 3.0, 9.0]) == 2
    assert gated.draw((1, 4, 2), seconds=10.0, n_actuators=6).assist == pytest.approx([24.0])


def test_assistance_holds_a_pushed_walker_up():
    """A hard sideways shove fells the walker; held upright by the assistance, the same walker stays up."""
    g, cfg, _ = load_genome(WALKERS / "simbicon_seed1.json")
    ep = cfg.build()
    shove = dict(push_start=np.array([[2.0]]), push_force=np.array([[[0.0, 40.0, 0.0]]]), push_duration=0.2)
    free = ep.run(g, seconds=6.0, trials=Trials.nominal(1, 6, **shove))
    held = ep.run(g, seconds=6.0, trials=Trials.nominal(1, 6, assist=np.array([60.0]), **shove))
    assert free.fell[0] and not held.fell[0]


def test_gait_senses_follow_the_feet():
    """The stance leg switches exactly at a touchdown of the other foot after it was airborne, and the time
    since touchdown restarts there."""
    g, cfg, _ = load_genome(WALKERS / "simbicon_seed1.json")
    ep = cfg.build()
    rows = []

    class Log:
        def start(self, episode, sims):
            self.body = episode.body

        def tick(self, t, sims, ids, neurons, action, task_state):
            s = self.body.sensors(sims)
            rows.append((t, s["stance_leg"][0, 0], s["since_touchdown"][0, 0], *s["foot_contact"][0]))

        def end(self, result):
            pass

    ep.run(g, seconds=4.0, listener=Log())
    t, stance, since, left, right = np.array(rows).T
    switch = np.flatnonzero(np.diff(stance) != 0) + 1
    assert len(switch) >= 6  # steps in 4 s
    for i in switch:
        new = left if stance[i] > 0 else right
        assert new[i] == 1 and new[i - 1] == 0  # the new stance foot has just landed
        assert since[i] == pytest.approx(0.0, abs=1e-9)
    inside = np.setdiff1d(np.arange(1, len(t)), switch)
    assert np.allclose(np.diff(since)[inside - 1], 0.02)  # between touchdowns it counts control periods


SMALL = dict(controller="simbicon", seconds=1.0, task_options={"fitness": "forward"})


def _config(**perturbations) -> RunConfig:
    return RunConfig(episode=EpisodeConfig(**SMALL, perturbations=perturbations), optimizer="cma",
                     optimizer_options={"cma": CMAOptions(population=6)}, generations=4, seed=3, backend="serial")


def test_the_best_of_an_assisted_run_is_an_unassisted_generation(tmp_path):
    cfg = _config(presentations=2, assist=40.0, assist_generations=2, assist_levels=[1.0, 0.5])
    run = Run.create(tmp_path / "r", cfg)
    with make_evaluator(cfg.episode, "serial") as ev:
        run.evolve(ev)
    best = json.loads((tmp_path / "r" / "best.json").read_text())
    assert best["generation"] in (2, 3)  # generations 0 and 1 were assisted
    hist = [float(r[1]) for r in fitness_history(tmp_path / "r")]
    assert best["fitness"] == max(hist[2:])


def test_a_gated_assisted_run_resumes_bit_identically(tmp_path):
    """The gated clock comes from the committed history: a resumed run (on two workers) draws as the whole one."""
    cfg = _config(assist=40.0, assist_generations=2, assist_gate=0.1)
    whole, cut = whole_and_resumed(tmp_path, cfg)
    assert fitness_history(cut) == fitness_history(whole.dir)
    assert (cut / "best.json").read_text() == (whole.dir / "best.json").read_text()
    clocks = [cfg.episode.perturbations.key(3, g, [float(r[1]) for r in fitness_history(whole.dir)])[2]
              for g in range(4)]
    assert clocks[-1] > 0  # the gate was passed: the resumed run had to rebuild a clock that moved


@pytest.mark.parametrize("table, words", [
    ("assist = 20.0", "must fade to zero"),
    ("assist = 20.0\nassist_generations = -3", "assist_generations"),
    ("assist = -1.0\nassist_generations = 3", "assist"),
    ("assist = 20.0\nassist_generations = 3\nassist_levels = [1.0, 0.5]", "2 levels need as many presentations"),
    ("assist = 20.0\nassist_generations = 3\nassist_levels = [1.5]", "0 <= f <= 1"),
])
def test_a_bad_assistance_is_one_line_and_writes_nothing(tmp_path, capsys, table, words):
    (tmp_path / "c.toml").write_text(f"[episode]\ncontroller = \"simbicon\"\n[episode.perturbations]\n{table}\n")
    code = main(["evolve", "--config", str(tmp_path / "c.toml"), "--out", str(tmp_path / "out"), "--generations", "1"])
    err = capsys.readouterr().err
    assert code == 2 and words in err and len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert not (tmp_path / "out").exists()
