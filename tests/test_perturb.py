"""Perturbed presentations: drawn from (seed, generation) alone, physically right, batch-independent."""

import dataclasses

import numpy as np
import pytest

from evobiped.cli import main
from evobiped.episode import EpisodeConfig
from evobiped.core.errors import ConfigError
from evobiped.files.genome_file import load_genome
from evobiped.physics.models import model_path
from evobiped.physics.perturb import PerturbationOptions
from evobiped.physics.trials import Trials
from evobiped.core.schedule import Schedule

from .conftest import WALKERS

WALKER = str(WALKERS / "simbicon_seed1.json")
PERTURBED = dict(presentations=3, pushes=2, push_force=10.0, target_noise=0.01, target_offset=0.02, pose_noise=0.02,
                 friction=[0.8, 1.2])


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
    xml = xml.replace('<option timestep="0.002"',
                      '<option gravity="0 0 0" timestep="0.002"').replace('<body name="pelvis" pos="0 0 1.08">',
                                                                          '<body name="pelvis" pos="0 0 3.0">')
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


RAMP = {"start": 2.0, "end": 10.0, "generations": 8, "after": 4}


@pytest.mark.parametrize("generation, value", [(0, 2.0), (4, 2.0), (5, 3.0), (8, 6.0), (11, 9.0), (12, 10.0),
                                               (500, 10.0)])
def test_a_schedule_holds_ramps_linearly_then_holds(generation, value):
    """start until `after`, then (end - start) / generations more per generation, then end: 2 + (g - 4) N."""
    assert Schedule.of(RAMP).at(generation) == pytest.approx(value, abs=1e-12)
    assert Schedule.of(7.5).at(generation) == 7.5
    fr = Schedule.of({"start": [1.0, 1.0], "end": [0.6, 1.4], "generations": 4}).at(generation)
    assert fr == pytest.approx((1.0 - 0.1 * min(generation, 4), 1.0 + 0.1 * min(generation, 4)))


def test_scheduled_strengths_reach_each_generations_trials():
    """The pushes of generation g have the ramp's force; the quantile and the aggregate switch as declared;
    the draws still depend on (seed, generation) alone."""
    cfg = PerturbationOptions.from_dict(dict(presentations=3, pushes=2, push_force=RAMP,
                                             slope={"start": 0.0, "end": 0.05, "generations": 10},
                                             quantile={"start": 0.5, "end": 0.1, "generations": 4}, aggregate="mean",
                                             aggregate_later="quantile", aggregate_from=3))
    for g in (0, 5, 8, 20):
        t = cfg.draw((3, g), seconds=20.0, n_actuators=6)
        assert np.allclose(np.linalg.norm(t.push_force, axis=2), 2.0 + min(max(g - 4, 0), 8))
        assert 0 <= t.slope <= 0.005 * min(g, 10) and (t.slope > 0) == (g > 0)
        assert t.aggregate == ("quantile" if g >= 3
                               else "mean") and t.quantile == pytest.approx(max(0.5 - 0.1 * g, 0.1))
        again = cfg.draw((3, g), seconds=20.0, n_actuators=6)
        assert np.array_equal(t.push_start, again.push_start) and (t.slope,
                                                                   t.slope_direction) == (
                                                                       again.slope, again.slope_direction)
    f = np.array([[0.0, 1.0, 2.0, 3.0, 4.0]])
    assert Trials.nominal(5, 6, aggregate="quantile", quantile=0.1).combine(f)[0] == pytest.approx(0.4)


def test_constant_options_draw_as_before_schedules_existed():
    """A run without schedules, slopes or gene noise draws exactly what the code before them drew (its history is
    unchanged): the same generator, the same draws in the same order."""
    cfg = PerturbationOptions(**PERTURBED)
    t = cfg.draw((5, 2), seconds=20.0, n_actuators=6)
    rng = np.random.default_rng([5, 2, 0x7E57])
    angle, start = rng.uniform(0.0, 2 * np.pi, (3, 2)), rng.uniform(2.0, 19.9, (3, 2))
    offset, seed = rng.normal(0.0, 0.02, (3, 6)), int(rng.integers(2**63))
    pose, friction = rng.normal(0.0, 0.02, (3, 6)), float(rng.uniform(0.8, 1.2))
    assert np.array_equal(t.push_force[..., 0], 10.0 * np.cos(angle)) and np.array_equal(t.push_start, start)
    assert np.array_equal(t.target_offset,
                          offset) and t.noise_seed == seed and np.array_equal(t.pose_offset,
                                                                              pose) and t.friction == friction
    assert t.slope == 0.0 and t.gene_noise is None


def test_gene_noise_is_the_jittered_genome_run_nominally_and_shared_by_the_generation():
    """Presentation r of any genome runs that genome + noise_r x (high - low), clipped: its fitness is that of the
    jittered genome alone, nominal; every genome of the generation meets the same noise rows."""
    g, cfg, _ = load_genome(WALKER)
    ep = dataclasses.replace(cfg, perturbations={"presentations": 2, "gene_noise": 0.05}).build()
    trials = ep.trials_for((0, 1))
    lay = ep.controller.layout
    assert trials.gene_noise.shape == (2, lay.size)
    other = lay.sample(np.random.default_rng(4))
    r = ep.run(np.vstack([other, g]), seconds=3.0, trials=trials)
    nominal = cfg.build()
    for i in range(2):
        jittered = np.clip(g + trials.gene_noise[i] * (lay.high - lay.low), lay.low, lay.high)
        assert r.rows.fitness[2 + i] == nominal.run(jittered, seconds=3.0).fitness[0]
        assert r.rows.fitness[i] == nominal.run(lay.jitter(other[None], trials.gene_noise[i:i + 1])[0],
                                                seconds=3.0).fitness[0]
    assert not np.array_equal(r.rows.fitness[2:], np.repeat(nominal.run(g, seconds=3.0).fitness, 2))


@pytest.mark.parametrize("direction, unit", [(0.0, (1, 0)), (np.pi, (-1, 0)), (np.pi / 2, (0, 1)),
                                             (-np.pi / 2, (0, -1))])
def test_a_slope_rises_towards_its_direction(direction, unit):
    """Gravity, seen in the floor's frame, pulls down the slope: against the direction the floor rises, by g sin(atan
    s)."""
    g, cfg, _ = load_genome(WALKER)
    ep = cfg.build()
    gx, gy, gz = ep.sims(1, slope=0.05, slope_direction=direction).model.opt.gravity
    a = np.arctan(0.05)
    assert (gx, gy) == pytest.approx((-9.81 * np.sin(a) * unit[0], -9.81 * np.sin(a) * unit[1]), abs=1e-12)
    assert gz == pytest.approx(-9.81 * np.cos(a))


@pytest.mark.parametrize("bad, words", [
    ({"nope": 1}, "nope: unknown option"),
    ({"push_force": -1.0}, "push_force: must be >= 0"),
    ({"presentations": 0}, "presentations: must be"),
    ({"friction": [2.0, 1.0]}, "friction: must be"),
    ({"aggregate": "median"}, "aggregate: must be one of"),
    ({"target_noise": float("nan")}, "target_noise: must be finite"),
    ({"push_force": {"start": 2.0, "end": 10.0, "generations": -5}}, "push_force.generations: the ramp's end "
                                                                     "(generation -5) precedes its start"),
    ({"slope": {"start": 0.0, "end": 0.03, "generations": 5, "after": -1}},
     "slope.after: the ramp cannot begin before generation 0"),
    ({"target_offset": {"start": 0.0, "end": -0.02, "generations": 5}}, "target_offset.end: must be >= 0 rad"),
    ({"friction": {"start": [1.0, 1.0], "end": [0.0, 1.5], "generations": 5}}, "friction.end: must be"),
    ({"gene_noise": {"start": -0.01, "end": 0.01, "generations": 5}}, "gene_noise.start: must be >= 0"),
    ({"gene_noise": 1.0}, "gene_noise: must be < 1"),
    ({"quantile": 1.0}, "quantile: must be < 1"),
    ({"quantile": 0}, "quantile: must be > 0"),
    ({"quantile": {"start": 0.5, "end": 1.5, "generations": 3}}, "quantile.end: must be < 1"),
    ({"pose_noise": {"start": 0.01, "end": 0.02}}, "pose_noise: a schedule needs start, end and generations"),
    ({"pose_noise": {"start": 0.01, "end": 0.02, "generations": 3, "until": 9}},
     "pose_noise: a schedule takes start, end, generations, after"),
    ({"aggregate_later": "best"}, "aggregate_later: must be one of"),
])
def test_bad_perturbations(bad, words):
    with pytest.raises(ConfigError) as info:
        EpisodeConfig(perturbations=bad)
    assert str(info.value).startswith(f"episode.perturbations.{words}"), str(info.value)


@pytest.mark.parametrize("line", ["push_force = -3", "push_force = {start = 5.0, end = 1.0, generations = -2}",
                                  "quantile = 1.5", "gene_noise = 1.0",
                                  "slope = {start = 0.0, end = 0.03, generations = 4, after = -2}"])
def test_bad_perturbation_config_file_one_line_nothing_written(tmp_path, capsys, line):
    cfg = tmp_path / "p.toml"
    cfg.write_text(f"[episode.perturbations]\n{line}\n")
    assert main(["evolve", "--config", str(cfg), "--out", str(tmp_path / "run"), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and line.split()[0] in err[0] and "Traceback" not in err[0]
    assert not (tmp_path / "run").exists()


def test_a_scheduled_run_resumes_and_parallelises_identically(tmp_path):
    """Schedules are functions of the generation: a run cut after two generations and resumed on two worker processes
    writes the history of an uninterrupted serial run, and its best is the best since the schedules ended."""
    from evobiped.optimizers import GAOptions
    from evobiped.run import RunConfig

    from .test_evolve import fitness_history, whole_and_resumed

    ramp = {"presentations": 2, "pushes": 1, "push_after": 0.2,
            "push_force": {"start": 0.0, "end": 20.0, "generations": 3},
            "gene_noise": {"start": 0.0, "end": 0.05, "generations": 2, "after": 1},
            "slope": {"start": 0.0, "end": 0.1, "generations": 3},
            "aggregate": "mean", "aggregate_later": "worst", "aggregate_from": 2}
    config = RunConfig(episode=EpisodeConfig(seconds=1.5, perturbations=ramp),
                       optimizer_options={"ga": GAOptions(population=8)}, generations=5, seed=7, backend="serial")
    whole, cut = whole_and_resumed(tmp_path, config)
    assert fitness_history(cut) == fitness_history(whole.dir)
    assert (cut / "best.json").read_text() == (whole.dir / "best.json").read_text()
    assert config.episode.perturbations.comparable_from == 3 and whole.record.best["generation"] >= 3
    history = fitness_history(whole.dir)
    assert whole.record.best["fitness"] == max(float(r[1]) for r in history[3:])
