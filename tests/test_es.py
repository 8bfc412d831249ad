"""The route from scratch: the mirrored stance frame, the linear controller, the running normaliser, the ES and the
curriculum.  Physics checked against the simulation itself (a mirrored body reads mirrored senses), numbers against
independent calculations (numpy's mean and variance, a quadratic's optimum)."""

import csv
import json
from pathlib import Path

import numpy as np
import pytest

from evobiped.episode import EpisodeConfig
from evobiped.core.errors import ConfigError
from evobiped.run import Run, RunConfig
from evobiped.evaluation import make_evaluator
from evobiped.optimizers.es import ESOptions, EvolutionStrategy, centred_ranks
from evobiped.interface.genome import GeneBlock, GenomeLayout
from evobiped.interface.normaliser import Normaliser, SenseSums
from evobiped.physics.sim import Sims

from .conftest import cli

STANCE_LINEAR = dict(body="reil", controller="linear", task="walk", seconds=1.0,
                     controller_options={"frame": "stance"},
                     task_options={"fitness": "weighted", "heading_sense": True})


def mirror_reil_state(model, sims: Sims, i: int) -> None:
    """Row ``i`` becomes its left/right mirror image about the walker's x-z plane (the Reil model's roll axes are
    mirrored, so the legs' joint angles swap without a sign)."""
    q, v = sims.qpos[i].copy(), sims.qvel[i].copy()
    q[1], v[1] = -q[1], -v[1]  # y
    w, x, y, z = q[3:7]
    q[3:7] = (w, -x, y, -z)  # a reflection y -> -y turns rotations about x and z the other way
    v[3], v[5] = -v[3], -v[5]
    for a, b in (("left_hip_pitch", "right_hip_pitch"), ("left_hip_roll", "right_hip_roll"),
                 ("left_knee", "right_knee")):
        qa, qb = model.joint(a).qposadr[0], model.joint(b).qposadr[0]
        da, db = model.joint(a).dofadr[0], model.joint(b).dofadr[0]
        q[qa], q[qb] = q[qb], q[qa]
        v[da], v[db] = v[db], v[da]
    sims.qpos[i], sims.qvel[i] = q, v


def test_the_reil_body_declares_its_mirror_truly():
    """A mirrored body reads the mirror of every sense it declares (a walked, asymmetric state, not the symmetric
    reset)."""
    ep = EpisodeConfig(body="reil", controller="simbicon", seconds=2.0).build()
    state = ep.start(np.zeros(ep.controller.layout.size) + ep.controller.layout.init_mean)
    rng = np.random.default_rng(3)
    state.sims.qpos[:, 7:] += rng.normal(0, 0.2, state.sims.qpos[:, 7:].shape)
    state.sims.qvel[:] = rng.normal(0, 0.5, state.sims.qvel.shape)
    state.sims.qpos[0, 2] -= 0.1  # the left foot on the ground, the right in the air
    quat = np.array([1.0, 0.08, -0.05, 0.3])  # the pelvis rolled, pitched and turned
    state.sims.qpos[0, 3:7] = quat / np.linalg.norm(quat)
    pair = Sims(ep.model, 2)
    pair.qpos[:], pair.qvel[:] = state.sims.qpos[0], state.sims.qvel[0]
    mirror_reil_state(ep.model, pair, 1)
    pair.forward()
    body = ep.body
    got = body.sensors(pair)
    for name, (perm, sign) in body.mirror.items():
        if name in ("stance_leg", "since_touchdown"):
            continue  # the gait senses' tracker mirrors by its own declaration (checked below)
        expect = got[name][0][list(perm)] * np.array(sign)
        assert np.allclose(got[name][1], expect, atol=1e-9), name
    assert body.mirror["stance_leg"] == ((0,), (-1,))


def test_a_mirrored_pose_gives_mirrored_targets():
    """The stance frame: the same policy on a pose standing on its left leg and on that pose's mirror (standing on its
    right) gives targets that are each other's mirror, so one set of weights serves both legs."""
    ep = EpisodeConfig(**{**STANCE_LINEAR, "task_options": {"fitness": "weighted"}}).build()
    ctrl = ep.controller
    genome = np.random.default_rng(0).normal(0, 0.3, ctrl.layout.size)
    state = ep.start(np.tile(genome, (2, 1)))
    sims = state.sims
    sims.qpos[:, 2] -= 0.05
    sims.qpos[:, 7:] += np.random.default_rng(1).normal(0, 0.15, sims.qpos[:, 7:].shape)
    sims.qpos[1] = sims.qpos[0]
    mirror_reil_state(ep.model, sims, 1)
    sims.forward()
    sims.extra.pop("gait", None)
    sims.extra["gait"] = {"stance": np.array([0, 1]), "touchdown": np.zeros(2), "lifted": np.full((2, 2), np.inf)}
    inputs, flip = ep._inputs(state, 2)
    assert flip.tolist() == [False, True]
    assert np.allclose(inputs[0], inputs[1], atol=1e-9)  # both read "stance side, then swing side"
    _, out = ctrl.step(state.params, state.controller, inputs)
    action = ctrl.frame.actions(np.clip(out, ep.low, ep.high), flip)
    perm = list(ep.body.actuator_mirror[0])
    assert np.allclose(action[1], action[0][perm], atol=1e-9)
    assert not np.allclose(action[0], action[0][perm])  # a real test: the targets are not symmetric themselves


@pytest.mark.parametrize("setting, msg", [
    ("[es]\nsigma = 0", "es.sigma: must be > 0"),
    ("[es]\nlearning_rate = -1.0", "es.learning_rate: must be > 0"),
    ("[curriculum]\nadvance = 'speed'", "curriculum.advance: 'speed' is neither 'up' nor a term"),
    ("[curriculum]\nphases = [{speed = 1.0}, {forward = 1.0}]", "names no term of the walk task: speed"),
])
def test_es_and_curriculum_settings_refused_with_one_line(tmp_path, capsys, setting, msg):
    (tmp_path / "c.toml").write_text(setting + "\n")
    code = cli("evolve", "--preset", "walker-es-linear", "--config", tmp_path / "c.toml", "--out", tmp_path / "r",
               "--generations", 1)
    err = capsys.readouterr().err
    assert code == 2 and len(err.strip().splitlines()) == 1 and msg in err, err
    assert not (tmp_path / "r").exists()


def test_a_stance_frame_on_a_body_without_a_mirror_is_refused():
    from evobiped.bodies import BODIES
    from evobiped.bodies.reil import ReilBiped

    class Lopsided(ReilBiped):
        name = "lopsided"
        actuator_mirror = None

    BODIES["lopsided"] = Lopsided
    try:
        with pytest.raises(ConfigError, match="frame: 'stance' needs a bilateral body with foot contacts; body "
                                              "'lopsided' declares no"):
            EpisodeConfig(body="lopsided", controller="linear", controller_options={"frame": "stance"}).parts()
    finally:
        del BODIES["lopsided"]


def test_the_running_normaliser_merges_exactly():
    """Batches merged one by one give numpy's mean and (population) variance of all the rows together."""
    x = np.random.default_rng(2).normal([1.0, -3.0, 0.0], [0.1, 2.0, 5.0], (900, 3))
    n = Normaliser.empty(3)
    for part in np.array_split(x, [10, 11, 400]):
        n = n.add(SenseSums(len(part), part.sum(0), (part * part).sum(0)))
    assert n.count == 900
    assert np.allclose(n.mean, x.mean(0), rtol=1e-12) and np.allclose(n.m2 / n.count, x.var(0), rtol=1e-9)
    centre, scale = n.centre_scale((np.zeros(3), np.ones(3)), np.array([0.5, 0.5, 0.5]))
    assert np.allclose(scale, np.maximum(x.std(0), 0.5))


def test_es_climbs_a_quadratic_and_ranks_are_centred():
    assert centred_ranks(np.array([3.0, -1.0, 10.0])).tolist() == [0.0, -0.5, 0.5]
    layout = GenomeLayout((GeneBlock(name="x", size=5, low=-10, high=10, init_mean=0, init_sigma=1, mutation_sigma=1),))
    target = np.array([1.0, -2.0, 0.5, 3.0, 0.0])
    for method in ("openai", "ars"):
        es = EvolutionStrategy(layout, ESOptions(method=method, pairs=8, sigma=0.1, learning_rate=0.1,
                                                 weight_decay=0.0), seed=1)
        start = np.linalg.norm(es.theta - target)
        for _ in range(300):
            pop, unknown = es.ask()
            es.tell(-((pop[unknown] - target) ** 2).sum(axis=1))
            es.next_generation()
        assert np.linalg.norm(es.theta - target) < 0.1 * start, method


def _history(path: Path) -> list[list[str]]:
    rows = list(csv.reader(open(path / "history.csv")))
    wall = rows[0].index("wall_seconds")
    return [r[:wall] + r[wall + 1:] for r in rows]


def test_an_es_run_resumes_bit_identically_with_its_normaliser_and_curriculum(tmp_path):
    """Stopped after generation 1 and resumed on two workers: the same history (with the phase column), checkpoint
    state and best genome; the curriculum advanced (its condition: the evaluation walker up its whole 0.4 s episode)."""
    from .test_evolve import whole_and_resumed

    config = RunConfig.from_dict({
        "optimizer": "es", "generations": 4, "seed": 3, "backend": "serial",
        "episode": {**STANCE_LINEAR, "seconds": 0.4, "perturbations": {"presentations": 2, "pose_noise": 0.01}},
        "es": {"pairs": 3}, "normalise": {"running": True},
        "curriculum": {"phases": [{"time_up": 2.0, "steps": 0.5}, {"forward": 10.0, "time_up": 5.0}],
                       "advance_for": 1}})
    whole, cut_dir = whole_and_resumed(tmp_path, config, stop_after=1)
    assert _history(whole.dir) == _history(cut_dir)
    a, b = (json.loads((d / "checkpoint.json").read_text()) for d in (whole.dir, cut_dir))
    for k in ("optimizer", "normaliser", "curriculum", "history_extra", "best_genome", "best_context"):
        assert a[k] == b[k], k
    phases = [int(r[_history(whole.dir)[0].index("phase")]) for r in _history(whole.dir)[1:]]
    assert phases[0] == 0 and phases[-1] == 1  # the short episode is survived: the run moved to walking
    assert a["normaliser"]["count"] > 0


def test_a_genome_file_freezes_its_normaliser_and_replays_its_fitness(tmp_path, capsys):
    """best.json records the normaliser and the phase weights its walker was scored with; replaying it gives that
    fitness again; a normaliser of the wrong width is refused with one line."""
    config = RunConfig.from_dict({
        "optimizer": "es", "generations": 3, "seed": 1, "backend": "serial",
        "episode": {**STANCE_LINEAR, "seconds": 0.6, "perturbations": {"pose_noise": 0.01}},
        "es": {"pairs": 2}, "normalise": {"running": True},
        "curriculum": {"phases": [{"time_up": 2.0, "steps": 0.5}, {"forward": 10.0}], "advance_for": 1}})
    run = Run.create(tmp_path / "run", config)
    with make_evaluator(config.episode, "serial") as ev:
        run.evolve(ev)
    best = json.loads((run.dir / "best.json").read_text())
    norm = best["episode"]["controller_options"]["input_norm"]
    assert len(norm["mean"]) == config.episode.parts()[1].n_inputs and norm["count"] > 0
    assert best["episode"]["task_options"]["weights"] in config.curriculum.phases
    from evobiped.files.genome_file import load_genome
    genome, cfg, meta = load_genome(run.dir / "best.json")
    trials = cfg.perturbations.draw((1, best["generation"]), seconds=0.6, n_actuators=6)
    fit = cfg.build().run(genome, trials=trials).fitness[0]
    assert fit == pytest.approx(best["fitness"], abs=1e-9)
    best["episode"]["controller_options"]["input_norm"]["mean"].pop()
    best["episode"]["controller_options"]["input_norm"]["std"].pop()
    (tmp_path / "bad.json").write_text(json.dumps(best))
    code = cli("replay", tmp_path / "bad.json", "--out", tmp_path / "x.rrd")
    err = capsys.readouterr().err
    assert code == 2 and len(err.strip().splitlines()) == 1 and "input_norm: normalises 26 inputs" in err, err


@pytest.mark.parametrize("optimizer", ["ga", "cma"])
def test_the_ga_and_cma_es_run_in_the_stance_frame_with_a_running_normaliser(tmp_path, optimizer):
    """The route's pieces are the search's choice, not a fork: the GA and CMA-ES evolve the linear policy in the stance
    frame under the running normaliser and the curriculum; without evaluation rows of their own, the normaliser learns
    from every walker they evaluated (one tick of senses per control tick each was up: the sum of their end times)."""
    from evobiped.run.run_config import make_optimizer

    config = RunConfig.from_dict({
        "optimizer": optimizer, "generations": 1, "seed": 2, "backend": "serial",
        "episode": {**STANCE_LINEAR, "seconds": 0.5, "controller_options": {"frame": "stance", "init_sigma": 0.3}},
        "ga": {"population": 4}, "cma": {"population": 4}, "normalise": {"running": True},
        "curriculum": {"phases": [{"time_up": 2.0, "steps": 0.5}, {"forward": 10.0}], "advance_for": 1}})
    run = Run.create(tmp_path / "run", config)
    with make_evaluator(config.episode, "serial") as ev:
        run.evolve(ev)
    ck = json.loads((run.dir / "checkpoint.json").read_text())
    population = make_optimizer(config).ask()[0]
    from evobiped.episode import Context

    again = config.episode.build().run(population, context=Context(weights={"time_up": 2.0, "steps": 0.5}))
    assert ck["normaliser"]["count"] == pytest.approx(np.round(again.end_time / 0.02).sum()) and ck["normaliser"][
        "count"] > 0
    fittest_up = not again.fell[np.argmax(again.fitness)]  # the curriculum's walker: the fittest; up: on to phase 1
    assert ck["history_extra"][0]["phase"] == 0 and ck["curriculum"]["phase"] == int(fittest_up)


def test_a_ctrnn_with_a_direct_path_contains_the_linear_policy():
    """With its network at rest (zero weights, centre-crossing biases: every O = 1/2) a CTRNN's direct path gives the
    linear policy's targets: direct genes = linear genes / (2 g max|range|) per joint, under motor = "full"."""
    from evobiped.interface.mapping import to_action

    common = dict(body="reil", task="walk", seconds=1.0, task_options={"heading_sense": True})
    lin = EpisodeConfig(controller="linear", **common).build()
    net = EpisodeConfig(controller="ctrnn", controller_options={
        "n_neurons": 8, "motor": "full", "normalise_inputs": True, "centre_crossing": True, "tau_scale": "log",
        "time_constants": [0.02, 2.0], "outputs": "after", "direct": True, "direct_scale": 0.3,
        "input_weights": [-5.0, 5.0], "inputs": list(lin.controller.input_names)}, **common).build()
    rng = np.random.default_rng(5)
    b = rng.normal(0, 0.2, 6)
    W = rng.normal(0, 0.1, (lin.controller.n_inputs, 6))
    span = 2 * 0.3 * np.maximum(np.abs(lin.low), np.abs(lin.high))
    layout = net.controller.layout
    genes = layout.init_mean.copy()
    sl = layout.slices()
    genes[sl["weights"]] = 0.0
    genes[sl["biases"]] = 0.0
    genes[sl["input_weights"]] = 0.0
    genes[sl["direct_biases"]] = b / span
    genes[sl["direct_weights"]] = (W / span).ravel()
    x = rng.normal(0, 1, (3, lin.controller.n_inputs))
    p_lin = lin.controller.decode(np.concatenate([b, W.ravel()])[None].repeat(3, 0))
    p_net = net.controller.decode(genes[None].repeat(3, 0))
    _, y_lin = lin.controller.step(p_lin, None, x)
    _, o_net = net.controller.step(p_net, net.controller.initial_state(p_net), x)
    a_lin = to_action("angle", lin.low, lin.high, "position", y_lin)
    a_net = to_action(net.controller.output_kind, net.low, net.high, "position", o_net)
    assert np.allclose(a_lin, a_net, atol=1e-12)
    assert not np.allclose(a_lin, 0)


def test_the_taga_body_declares_its_mirror_truly():
    """Taga's sagittal walker: swapping its legs' joint coordinates swaps its link senses as declared, and the
    actions' mirror swaps each right-leg actuator with its left-leg namesake."""
    ep = EpisodeConfig(body="taga", controller="matsuoka", seconds=0.5).build()
    body = ep.body
    sims = Sims(ep.model, 2)
    body.reset(sims)
    rng = np.random.default_rng(4)
    q = body._qadr
    sims.qpos[0, q[2:]] += rng.normal(0, 0.2, len(q) - 2)
    sims.qvel[0, body._dadr[2:]] = rng.normal(0, 1.0, len(q) - 2)
    sims.qpos[1], sims.qvel[1] = sims.qpos[0], sims.qvel[0]
    for a, b in ((2, 4), (3, 5)):  # right thigh/knee <-> left thigh/knee
        sims.qpos[1, [q[a], q[b]]] = sims.qpos[0, [q[b], q[a]]]
        sims.qvel[1, [body._dadr[a], body._dadr[b]]] = sims.qvel[0, [body._dadr[b], body._dadr[a]]]
    sims.forward()
    got = {k: v for k, v in body.sensors(sims).items() if k in ("link_angles", "link_velocities")}
    for name, x in got.items():
        perm, sign = body.mirror[name]
        assert np.allclose(x[1], x[0][list(perm)] * np.array(sign)), name
        assert not np.allclose(x[0], x[1]), name
    names = [a.name for a in body.actuators]
    perm, _ = body.actuator_mirror
    assert [names[i] for i in perm] == [n.replace("right", "L").replace("left", "right").replace("L", "left")
                                        for n in names]


def test_evolve_runs_the_es_preset_from_the_command_line(tmp_path, capsys):
    """`evobiped evolve --preset walker-es-linear` end to end (two short generations): the checkpoint holds the ES
    state of the preset's genome, the normaliser has learnt from the evaluation walker's senses at every tick of both
    generations (it stayed up), and the curriculum, its walker up two generations running (``advance_for = 2``),
    moved to its second phase after scoring both generations in the first (history.csv's phase column)."""
    from evobiped.flags import run_config

    (tmp_path / "short.toml").write_text("[es]\npairs = 2\n[curriculum]\nseconds = [0.4, 0.4]\n")
    code = cli("evolve", "--preset", "walker-es-linear", "--config", tmp_path / "short.toml", "--generations", 2,
               "--backend", "serial", "--out", tmp_path / "run", "--quiet")
    assert code == 0, capsys.readouterr().err
    ck = json.loads((tmp_path / "run" / "checkpoint.json").read_text())
    episode = run_config(preset="walker-es-linear", config=str(tmp_path / "short.toml")).episode.build()
    assert ck["optimizer"]["name"] == "es" and ck["optimizer"]["generation"] == 2
    assert len(ck["optimizer"]["theta"]) == episode.controller.layout.size and len(ck["optimizer"][
        "fitness"]) == 2 * 2 + 1
    with open(tmp_path / "run" / "history.csv") as f:
        rows = list(csv.DictReader(f))
    assert [(r["phase"], float(r["evaluation_up"])) for r in rows] == [("0", 1.0), ("0", 1.0)]
    assert ck["curriculum"] == {"phase": 1, "streak": 0}
    assert ck["normaliser"]["count"] == 2 * round(0.4 / episode.control_dt)  # one evaluation walker, 2 generations


def test_a_stance_frame_network_s_motor_neurons_are_labelled_by_leg_role():
    """In the stance frame motor neuron i drives the stance (first half) or swing leg's joint, not actuator i: the
    motor figure names it so."""
    from types import SimpleNamespace

    from evobiped.record.png.motor_labels import _motor_label

    names = ("left_hip_pitch", "left_hip_roll", "left_knee", "right_hip_pitch", "right_hip_roll", "right_knee")
    framed, plain = (SimpleNamespace(actuator_names=names, stance_frame=f) for f in (True, False))
    assert [_motor_label(framed, i) for i in (0, 2, 3, 5)] == ["stance hip_pitch", "stance knee", "swing hip_pitch",
                                                               "swing knee"]
    assert _motor_label(plain, 3) == "right_hip_pitch" and _motor_label(framed, 7) == "output 8"


@pytest.mark.parametrize("value, nulls, rows, words", [
    (["x"], False, None, "es.theta must be a list of finite numbers"),
    ([True], False, None, "es.theta must be a list of finite numbers"),
    ([float("inf")], False, None, "es.theta must be a list of finite numbers"),
    ([None], False, None, "es.theta must be a list of finite numbers"),
    ("1, 2", True, None, "es.theta must be a list of finite numbers or nulls"),
    ([[1.0, 2.0], [3.0]], False, 2, "es.theta must be a list of rows of 2 finite numbers"),
])
def test_a_checkpoint_list_that_is_not_numbers_is_one_line(value, nulls, rows, words):
    """OptimizerState.numbers_of (every optimizer's state reads its lists of numbers with it: the next test): strings,
    booleans, infinities, nulls where none may be, and ragged rows are refused naming the optimizer and field; nulls,
    where allowed, read NaN."""
    from evobiped.core.errors import UserError
    from evobiped.optimizers.es import ESState

    with pytest.raises(UserError) as err:
        ESState.numbers_of({"theta": value}, "theta", null=np.nan if nulls else None, rows=rows)
    assert str(err.value) == f"checkpoint: {words}"
    got = ESState.numbers_of({"fitness": [1, None, 2.5]}, "fitness", null=np.nan)
    assert np.isnan(got[1]) and got[[0, 2]].tolist() == [1.0, 2.5]
    assert ESState.numbers_of({"g": [[1, 2], [3, 4]]}, "g", rows=2).shape == (2, 2)
    assert ESState.numbers_of({"g": []}, "g", rows=3).shape == (0, 3)


@pytest.mark.parametrize("name", ["ga", "cma", "es", "map-elites"])
def test_every_optimizer_reads_its_checkpoint_lists_with_numbers_of(name, monkeypatch):
    """Each registered optimizer's state, written and read back, goes through OptimizerState.numbers_of (so each refuses
    a malformed list as the previous test shows), and reads back equal to what it wrote."""
    from evobiped.optimizers import OPTIMIZERS
    from evobiped.optimizers.base import OptimizerState

    if name == "map-elites":
        pytest.importorskip("ribs")
    assert set(OPTIMIZERS) == {"ga", "cma", "es", "map-elites"}
    cls = OPTIMIZERS[name]
    layout = EpisodeConfig(controller="simbicon").layout()
    opt = cls(layout, cls.Options(), seed=3)
    from types import SimpleNamespace

    n = len(opt.ask()[1])
    f = np.arange(n, dtype=float)
    opt.tell(SimpleNamespace(fitness=f, fell=np.zeros(n), end_time=np.full(n, 2.0),
                             terms={"speed": f / n, "turning": 10.0 * f - 20.0}))  # the map-elites cells' measures
    opt.next_generation()
    table = json.loads(json.dumps(opt.state().to_dict()))
    read, numbers_of = [], OptimizerState.numbers_of.__func__

    def counted(klass, table, key, **kw):
        read.append(key)
        return numbers_of(klass, table, key, **kw)

    monkeypatch.setattr(OptimizerState, "numbers_of", classmethod(counted))
    assert json.loads(json.dumps(opt.state_from(table).to_dict())) == table
    assert "fitness" in read, read
