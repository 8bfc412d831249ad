"""Perturbed presentations: drawn from (seed, generation) alone, physically right, batch-independent."""

import dataclasses

import numpy as np
import pytest

from evobiped.cli import main
from evobiped.episode import EpisodeConfig
from evobiped.errors import ConfigError
from evobiped.genome_file import load_genome
from evobiped.models import model_path
from evobiped.perturb import PerturbationOptions, Trials

from .conftest import WALKERS

WALKER = str(WALKERS / "simbicon_seed1.json")
PERTURBED = dict(presentations=3, pushes=2, push_force=10.0, target_noise=0.01, target_offset=0.02, pose_noise=0.02, friction=[0.8, 1.2])


def test_trials_depend_on_seed_and_generation_only():
    cfg = PerturbationOptions(**PERTURBED)
    a, b, c = (cfg.draw(k, seconds=20.0, n_actuators=6) for k in ((1, 4), (1, 4), (1, 5)))
    assert np.array_equal(a.push_start, b.push_start) and a.friction == b.friction and a.noise_seed == b.noise_seed
    assert not np.array_equal(a.push_start, c.push_start)
    assert a.push_start.shape == (3, 2) and (a.push_start >= 2.0).all() and (a.push_start <= 20.0 - 0.1).all()
    assert np.allclose(np.linalg.norm(a.push_force, axis=2), 10.0) and np.all(a.push_force[..., 2] == 0)
    assert 0.8 <= a.friction <= 1.2


def test_undisturbed_presentations_equal_the_nominal_episode():
    g, cfg, _ = load_genome(WALKER)
    ep = cfg.build()
    nominal = ep.run(g, seconds=3.0)
    r = ep.run(g, seconds=3.0, trials=Trials.nominal(3, 6))
    assert np.array_equal(r.rows.fitness, np.repeat(nominal.fitness, 3))
    # the mean of three equal floats may differ from them in the last bit (sum, then divide)
    assert r.fitness[0] == pytest.approx(nominal.fitness[0], rel=1e-15, abs=0)


def test_a_genome_scores_the_same_alone_or_in_a_batch():
    g, cfg, _ = load_genome(WALKER)
    ep = dataclasses.replace(cfg, perturbations=PERTURBED).build()
    trials = ep.trials_for((0, 3))
    rng = np.random.default_rng(0)
    lay = ep.controller.layout
    others = lay.sample(rng, 3)
    alone = ep.run(g, seconds=4.0, trials=trials)
    batch = ep.run(np.vstack([others[:2], g, others[2:]]), seconds=4.0, trials=trials)
    assert batch.fitness[2] == alone.fitness[0]
    assert np.array_equal(batch.rows.fitness[6:9], alone.rows.fitness)


def test_aggregates():
    t = Trials.nominal(4, 6)
    f = np.array([[1.0, 2.0, 3.0, 10.0]])
    assert t.combine(f)[0] == 4.0
    assert dataclasses.replace(t, aggregate="worst").combine(f)[0] == 1.0
    assert dataclasses.replace(t, aggregate="q25").combine(f)[0] == pytest.approx(1.75)


def test_push_changes_momentum_by_the_impulse(tmp_path):
    """In a weightless world with the walker clear of the floor, a push F for T changes the
    centre-of-mass velocity by F T / M against the same motion unpushed (within 1 %: the joints'
    armature, 0.01 kg m^2 on every degree of freedom, the free root's too, adds a little inertia)."""
    xml = model_path("reil_biped").read_text()
    xml = xml.replace('<option timestep="0.002"', '<option gravity="0 0 0" timestep="0.002"').replace('<body name="pelvis" pos="0 0 1.08">', '<body name="pelvis" pos="0 0 3.0">')
    path = tmp_path / "float.xml"
    path.write_text(xml)
    ep = EpisodeConfig(controller="ctrnn", seconds=0.6, body_options={"model_file": str(path)}).build()
    g = ep.controller.layout.init_mean
    force = np.array([[[6.0, -4.0, 0.0]]])
    trials = Trials.nominal(1, 6, push_start=np.array([[0.2]]), push_force=force, push_duration=0.1)

    class Velocity:
        def start(self, episode, sims):
            self.body, self.v = episode.body, []

        def tick(self, t, sims, ids, neurons, action, task_state):
            self.v.append(self.body._com_velocity(sims)[0].copy())

        def end(self, result):
            pass

    pushed, still = Velocity(), Velocity()
    ep.run(g, trials=trials, listener=pushed)
    ep.run(g, trials=Trials.nominal(1, 6), listener=still)
    dv = np.array(pushed.v) - np.array(still.v)
    mass = ep.model.body_subtreemass[1]
    assert np.abs(dv[:10]).max() < 1e-12  # before the push (ticks up to 0.2 s)
    assert np.allclose(dv[-1], force[0, 0] * 0.1 / mass, rtol=0.01, atol=1e-3)
    assert np.linalg.norm(dv[-1]) > 0.05


def test_slope_and_friction_change_the_model_of_their_batch_only():
    g, cfg, _ = load_genome(WALKER)
    ep = cfg.build()
    s = ep.sims(2, friction=0.5, slope=0.03)
    gx, _, gz = s.model.opt.gravity
    assert np.arctan2(-gx, -gz) == pytest.approx(np.arctan(0.03)) and np.hypot(gx, gz) == pytest.approx(9.81)
    assert s.model.geom_friction[0, 0] == 0.5
    assert ep.model.geom_friction[0, 0] == 1.0 and ep.model.opt.gravity[0] == 0.0


@pytest.mark.parametrize("bad", [{"nope": 1}, {"push_force": 0}, {"push_force": -1.0}, {"presentations": 0},
                                 {"friction": [2.0, 1.0]}, {"aggregate": "median"}, {"target_noise": float("nan")}])
def test_bad_perturbations(bad):
    with pytest.raises(ConfigError, match=f"^episode.perturbations.{next(iter(bad))}: (must|unknown option)"):
        EpisodeConfig(perturbations=bad)


def test_bad_perturbation_config_file_one_line_nothing_written(tmp_path, capsys):
    cfg = tmp_path / "p.toml"
    cfg.write_text("[episode.perturbations]\npush_force = -3\n")
    assert main(["evolve", "--config", str(cfg), "--out", str(tmp_path / "run"), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "push_force" in err[0]
    assert not (tmp_path / "run").exists()
