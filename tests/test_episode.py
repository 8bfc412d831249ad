"""One honest episode: standing, collapsing, eq. 4, determinism, bad genomes."""

import dataclasses
import json

import mujoco
import numpy as np
import pytest

from evobiped.cli import main
from evobiped.bodies import ReilBiped
from evobiped.controllers.base import Controller
from evobiped.episode import Episode, EpisodeConfig, build_episode
from evobiped.core.errors import GenomeError
from evobiped.interface.genome import GeneBlock, GenomeLayout
from evobiped.tasks import WalkTask

from .conftest import WALKERS

from .conftest import random_genomes


def constant_genome(fractions):
    """A CTRNN with zero weights: motor outputs stay sigma(-alpha) = the given fractions."""
    f = np.clip(np.asarray(fractions, float), 0.0182, 0.9818)
    g = np.zeros(120)
    g[100:110] = 1.0
    alpha = np.zeros(10)
    alpha[:6] = -np.log(f / (1 - f))
    g[110:] = alpha
    return g


class Constant(Controller):
    """Test double: constant outputs in [0, 1], the genome is the outputs."""

    name = "constant"
    output_kind = "unit"
    dt = 0.02

    def __init__(self, n_outputs=6):
        self.n_outputs = n_outputs
        self._layout = GenomeLayout((GeneBlock(name="o", size=n_outputs, low=0, high=1, init_mean=0.5, init_sigma=0,
                                               mutation_sigma=0),))

    layout = property(lambda self: self._layout)
    initial_state = lambda self, p: None  # noqa: E731
    step = lambda self, p, s, i: (s, p["o"])  # noqa: E731
    neuron_outputs = lambda self, p, s: p["o"]  # noqa: E731


# output fractions that map onto targets of exactly 0 rad in Table II's ranges
# (1.3 / 2.9 gives 2e-16 rad; the next float below gives exactly 0)
HIP0 = 0.44827586206896547
NEUTRAL = [HIP0, 0.5, 1.0, HIP0, 0.5, 1.0]
COLLAPSE = [1.3 / 2.9, 0.5, 0.0, 1.3 / 2.9, 0.5, 0.0]  # knees fully bent


@pytest.fixture(scope="module")
def constant_episode():
    return Episode(ReilBiped(), Constant(), WalkTask(), seconds=50.0)


def test_neutral_targets_stand_50s(constant_episode):
    """Upright, legs straight, all targets 0: the symmetric stance holds for 50 s, no drift."""
    state = constant_episode.advance(constant_episode.start(np.array(NEUTRAL)), 50.0)
    r = constant_episode.result(state)
    assert np.all(state.sims.ctrl == 0.0)
    assert not r.fell[0] and not r.unstable[0]
    assert r.end_time[0] == pytest.approx(50.0)
    assert r.fitness[0] < 1e-9  # standing still
    com = constant_episode.body.com(state.sims)[0]
    # COM of the upright pose: (1 * 1.08 + 1.2 * 0.83 + 0.9 * 0.33 + 0.3 * 0.08) / 3.4, less contact penetration
    assert com[2] == pytest.approx((1.08 + 1.2 * 0.83 + 0.9 * 0.33 + 0.3 * 0.08) / 3.4, abs=2e-3)


def test_point_feet_cannot_hold_a_lean(constant_episode):
    """Sphere feet are point contacts: leaning the legs 0.05 rad forward topples the walker."""
    o = np.array(NEUTRAL)
    o[[0, 3]] += 0.05 / 2.9
    r = constant_episode.run(o)
    assert r.fell[0] and 1.0 < r.end_time[0] < 10.0


def test_ctrnn_near_neutral_topples_forward():
    """A CTRNN cannot output exactly 1: knees at -0.025 rad tip the point-footed walker over."""
    ep = build_episode(seconds=50.0)
    r = ep.run(constant_genome(NEUTRAL))
    assert r.fell[0] and r.end_time[0] < 10.0
    assert r.end_position[0, 0] > 0.3  # it fell forwards (+x), as the bent knees put the COM ahead


def test_collapsing_legs_end_early(constant_episode):
    r = constant_episode.run(np.array(COLLAPSE))
    assert r.fell[0] and not r.unstable[0]
    assert r.end_time[0] < 2.0


def test_fitness_is_eq4_from_an_independent_loop():
    """Re-simulate with plain MjData + mj_step and a hand-written CTRNN; compare eq. 4."""
    ep = build_episode(seconds=3.0)
    g = random_genomes(ep.controller.layout, 12, seed=7)
    res = ep.run(g)
    model = ep.body.build_model()
    lo, hi = ep.low, ep.high
    pelvis = model.body("pelvis").id
    for k in range(12):
        W = g[k, :100].reshape(10, 10)
        tau, alpha = g[k, 100:110], g[k, 110:120]
        d = mujoco.MjData(model)
        mujoco.mj_forward(model, d)
        start = d.xpos[pelvis, :2].copy()
        A = np.zeros(10)
        t_end = 3.0
        for tick in range(150):
            O = 1 / (1 + np.exp(alpha - A))
            A = A + 0.02 / tau * (-A + O @ W)
            d.ctrl[:] = lo + O[:6] * (hi - lo)
            mujoco.mj_step(model, d, nstep=4)
            mujoco.mj_forward(model, d)
            if d.subtree_com[pelvis, 2] < 0.5 or d.xmat[pelvis, 8] < 0:  # fallen: COM low, or pelvis past 90 degrees
                t_end = (tick + 1) * 0.02
                break
        W4 = np.hypot(*(d.xpos[pelvis, :2] - start))
        assert res.end_time[k] == pytest.approx(t_end)
        assert res.fitness[k] == pytest.approx(W4, rel=1e-6, abs=1e-9)


def test_an_episode_continued_in_pieces_is_the_whole_episode_and_can_change_course():
    """start + advance(1.3 s) + advance(rest) under perturbed presentations (pushes, noise) gives the
    whole run bit for bit; an experiment's change between pieces acts from then on only."""
    from evobiped.files.genome_file import load_genome

    g, cfg, _ = load_genome(WALKERS / "simbicon_seed1.json")
    ep = dataclasses.replace(cfg, perturbations=dict(presentations=2, pushes=2, push_force=10.0,
                                                     target_noise=0.01)).build()
    trials = ep.trials_for((0, 1))
    whole = ep.run(g, seconds=3.0, trials=trials)
    state = ep.start(g, seconds=3.0, trials=trials)
    ep.advance(state, 1.3)
    assert state.ticks == 65 and state.time == pytest.approx(1.3)
    ep.advance(state, ticks=state.n_ticks - state.ticks)
    pieces = ep.result(state)
    assert np.array_equal(pieces.rows.fitness, whole.rows.fitness) and np.array_equal(pieces.end_time, whole.end_time)
    # a push of 2000 N along +y on every trunk between the pieces moves every walker sideways (to +y)
    state = ep.start(g, seconds=3.0, trials=trials)
    ep.advance(state, 1.0)
    mid = ep.body.planar_position(state.sims).copy()
    state.sims.xfrc_applied[:, ep._trunk, 1] = 2000.0
    ep.advance(state, 0.1)
    assert (ep.body.planar_position(state.sims)[:, 1] - mid[:, 1] > 0.05).all()


@pytest.mark.parametrize("cyclic_weight", [0.0, 1.0])
def test_walk_terms_beside_the_fitness(cyclic_weight):
    """distance is eq. 4 from the positions, forward the displacement along the initial facing (+x for the
    Reil body), cyclicity c in [0, 1] with the cyclic criterion (fitness = distance (1 + c)), NaN without."""
    ep = build_episode(seconds=2.0, task_options={"cyclic_weight": cyclic_weight})
    r = ep.run(random_genomes(ep.controller.layout, 6, seed=4))
    d = r.end_position - r.start_position
    assert ep.task.term_names == tuple(r.terms) == ("distance", "forward", "cyclicity")
    np.testing.assert_array_equal(r.terms["distance"], np.linalg.norm(d, axis=1))
    np.testing.assert_allclose(r.terms["forward"], d[:, 0], rtol=1e-12, atol=1e-12)
    c = r.terms["cyclicity"]
    if cyclic_weight:
        assert ((0 <= c) & (c <= 1)).all() and c.max() > 0
        np.testing.assert_array_equal(r.fitness, r.terms["distance"] * (1.0 + c))
    else:
        assert np.isnan(c).all()
        np.testing.assert_array_equal(r.fitness, r.terms["distance"])


@pytest.mark.parametrize("controller", ["ctrnn", "simbicon"])
def test_same_genome_same_fitness_any_batch(controller):
    """Bit for bit, whatever else is in the batch (so a run never depends on how genomes are split over workers)."""
    ep = build_episode(controller=controller, seconds=6.0)
    g = random_genomes(ep.controller.layout, 8, seed=3)
    a = ep.run(g)
    b = ep.run(g)
    alone = [ep.run(g[i]).fitness[0] for i in range(8)]
    shuffled = ep.run(np.concatenate([g[::-1], g[:3]]))
    assert np.array_equal(a.fitness, b.fitness)
    assert np.array_equal(a.fitness, np.array(alone))
    assert np.array_equal(a.fitness, shuffled.fitness[:8][::-1])
    assert np.array_equal(a.end_time, ep.run(g).end_time)


@pytest.mark.parametrize(
    "genes, words",
    [([0.0] * 119, "119 genes"), ([float("nan")] + [0.0] * 119, "not finite"), ([99.0] + [0.0] * 119, "outside"),
     ([[[0.0] * 120]], r"shape \(1, 1, 120\): give one genome \(120,\) or a population \(P, 120\)")],
)
def test_malformed_genome_clear_error(genes, words):
    with pytest.raises(GenomeError, match=words):
        build_episode(seconds=1.0).run(np.array(genes))


def test_cli_bad_genome_file(tmp_path, capsys):
    f = tmp_path / "g.json"
    f.write_text(json.dumps({"genome": [0.0] * 7, "episode": {"body": "reil", "controller": "ctrnn"}}))
    assert main(["episode", "--genome", str(f)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "7 genes" in err[0]
    f.write_text("not json")
    assert main(["episode", "--genome", str(f)]) == 2
    assert "not valid JSON" in capsys.readouterr().err


def test_cli_episode_prints_fitness(capsys):
    assert main(["episode", "--seed", "1", "--seconds", "2", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    ep = EpisodeConfig(seconds=2.0).build()
    lay = ep.controller.layout
    g = lay.sample(np.random.default_rng(1))
    assert out["fitness"] == ep.run(g).fitness[0]


class Launched(ReilBiped):
    """Test double: walker 0 starts with its pelvis thrown forward at 300 m/s (finite, but no walker's speed)."""

    def reset(self, sims):
        super().reset(sims)
        sims.qvel[0, 0] = 300.0
        sims.forward()


def test_a_runaway_simulation_is_unstable_and_keeps_its_last_plausible_distance():
    """MuJoCo warns only at 1e10: a state running away at 300 m/s would carry the walker 6 m
    in one control tick.  It is flagged unstable, ends as a fall, and scores where it was before."""
    ep = Episode(Launched(), Constant(), WalkTask(), seconds=1.0)
    state = ep.advance(ep.start(np.array([NEUTRAL, NEUTRAL])), 1.0)
    r = ep.result(state)
    assert state.sims.qpos[0, 0] > 5.0  # the physics really did carry it off, and MuJoCo said nothing
    assert not state.sims.batch.warning[0, :, 0].any()
    assert r.unstable.tolist() == [True, False] and r.fell.tolist() == [True, False]
    assert r.end_time[0] == pytest.approx(0.02)
    assert r.fitness[0] == 0.0 and r.fitness[1] < 1e-9
