"""The ES update's details: ties, bounds, weight decay per gene block and ARS's stand-in for unstable rollouts; each
fixed by default and the first-shipped update kept by explicit options (the presets pin it)."""

import tomllib

import numpy as np
import pytest

from evobiped.episode import EpisodeConfig
from evobiped.run import RunConfig
from evobiped.files import presets
from evobiped.optimizers.es import ESOptions, EvolutionStrategy, centred_ranks
from evobiped.interface.genome import GeneBlock, GenomeLayout

FIRST_SHIPPED = dict(weight_decay_to="zero", credit="drawn", ties="order")


def block(name="x", size=4, low=-1.0, high=1.0, **kw):
    return GeneBlock(name=name, size=size, low=low, high=high, init_mean=0.5 * (low + high), init_sigma=0.1,
                     mutation_sigma=0.1, **kw)


def generations(es: EvolutionStrategy, fitness, n: int) -> None:
    for _ in range(n):
        pop, unknown = es.ask()
        es.tell(fitness(pop[unknown]))
        es.next_generation()


def test_tied_values_share_their_rank_so_a_tied_pair_gives_no_step():
    """Every fitness equal (a generation in which every walker fell at once): no step at all, where ranks in order of
    appearance put each + row below its - row... above, and the pairs pushed theta along the eps they drew."""
    assert centred_ranks(np.array([1.0, 1.0])).tolist() == [0.0, 0.0]
    assert centred_ranks(np.array([2.0, 1.0, 2.0, 0.0])).tolist() == pytest.approx([1 / 3, -1 / 6, 1 / 3, -0.5])
    layout = GenomeLayout((block(size=6),))
    es = EvolutionStrategy(layout, ESOptions(pairs=8, sigma=0.1, learning_rate=0.1, weight_decay=0.0), seed=4)
    start = es.theta.copy()
    generations(es, lambda pop: np.zeros(len(pop)), 5)
    assert np.array_equal(es.theta, start)
    old = EvolutionStrategy(layout, ESOptions(pairs=8, sigma=0.1, learning_rate=0.1, weight_decay=0.0, ties="order"),
                            seed=4)
    generations(old, lambda pop: np.zeros(len(pop)), 5)
    assert np.abs(old.theta - start).max() > 0.1  # the first-shipped ranks: five steps of about the learning rate


def test_weight_decay_pulls_each_block_to_its_centre_and_leaves_the_time_constants():
    """A fitness that says nothing (all tied): weight decay alone moves theta.  The CTRNN's ln tau genes stay where they
    are (the first-shipped pull to 0 drags tau to 1 s), a block on [1, 3] goes to 2, not 0."""
    ctrnn = EpisodeConfig(body="reil", controller="ctrnn", task="walk", controller_options={
        "time_constants": [0.02, 2.0], "tau_scale": "log"}).layout()
    offset = block("offset", size=3, low=1.0, high=3.0)
    layout = GenomeLayout(ctrnn.blocks + (offset,))
    tau, weights, off = (layout.slices()[b] for b in ("time_constants", "weights", "offset"))
    start = layout.init_mean.copy()
    start[tau] = np.log(0.2)
    start[weights] = 4.0
    start[off] = 2.9
    es = EvolutionStrategy(layout, ESOptions(pairs=4, sigma=0.01, weight_decay=0.5), seed=0, initial=start)
    generations(es, lambda pop: np.zeros(len(pop)), 60)
    assert np.array_equal(es.theta[tau], start[tau])
    assert np.abs(es.theta[weights]).max() < 3.0 and np.abs(es.theta[off] - 2.0).max() < 0.8
    old = EvolutionStrategy(layout, ESOptions(pairs=4, sigma=0.01, weight_decay=0.5, **FIRST_SHIPPED), seed=0,
                            initial=start)
    generations(old, lambda pop: np.zeros(len(pop)), 60)
    assert np.exp(old.theta[tau]).min() > 0.25  # the first-shipped decay: tau pulled towards 1 s


def test_a_bound_builds_no_momentum_and_a_clipped_sample_is_credited_with_the_move_it_made():
    """theta on its upper bound, the fitness rising beyond it for 20 generations, then falling: theta leaves the bound
    at the first step after the turn (no momentum was kept pushing into it).  A gene of zero range (every sample clipped
    back onto theta) gets no gradient and no moments."""
    layout = GenomeLayout((block("x", size=2), block("fixed", size=1, low=0.5, high=0.5)))
    start = np.array([1.0, 0.0, 0.5])
    rising = lambda pop: pop[:, 0] + 0.1 * pop[:, 1]  # noqa: E731
    for first_shipped, leaves in (({}, True), (FIRST_SHIPPED, False)):
        es = EvolutionStrategy(layout, ESOptions(pairs=8, sigma=0.05, weight_decay=0.0, **first_shipped), seed=2,
                               initial=start)
        generations(es, rising, 20)
        assert es.theta[0] == 1.0
        assert bool(es.m[0] == 0.0) is leaves and bool(es.m[2] == 0.0 and es.v[2] == 0.0) is leaves
        generations(es, lambda pop: -pop[:, 0], 1)
        assert bool(es.theta[0] < 1.0) is leaves


def test_an_unstable_ars_rollout_does_not_erase_the_other_pairs():
    """ARS on a linear fitness with one unstable + row: the step still follows the fitness's gradient (the stand-in is
    the generation's worst finite value), where a stand-in 10^6 below it made sigma_f measure only that row and the step
    point along that pair's -eps."""
    layout = GenomeLayout((block(size=8, low=-10.0, high=10.0),))
    slope = np.linspace(-1.0, 1.0, 8)
    es = EvolutionStrategy(layout, ESOptions(method="ars", pairs=16, sigma=0.1, learning_rate=0.1), seed=5)
    start = es.theta.copy()
    pop, unknown = es.ask()
    f = pop[unknown] @ slope
    f[0] = -np.inf
    es.tell(f)
    es.next_generation()
    step = es.theta - start
    cos = step @ slope / (np.linalg.norm(step) * np.linalg.norm(slope))
    assert cos > 0.8 and np.linalg.norm(step) > 0.05, (cos, np.linalg.norm(step))


def test_the_update_as_first_shipped_is_kept_bit_for_bit_where_the_presets_pin_it():
    """With the three first-shipped settings (what the ES presets pin) the update is the one they were evolved with,
    written out here in the first-shipped form; the defaults are the fixed update."""
    layout = GenomeLayout((block(size=5, low=-0.3, high=0.3),))
    options = ESOptions(pairs=6, sigma=0.2, weight_decay=0.01, **FIRST_SHIPPED)
    es = EvolutionStrategy(layout, options, seed=9)
    theta, m, v = es.theta.copy(), np.zeros(5), np.zeros(5)
    for t in range(1, 6):
        pop, unknown = es.ask()
        f = np.round(pop[unknown] @ np.arange(5.0), 1)  # rounded: ties happen
        es.tell(f)
        eps = np.random.default_rng([9, t - 1, 0x6A]).standard_normal((6, 5))
        ff = f[:12]
        r = np.empty(12)
        r[np.argsort(ff, kind="stable")] = np.arange(12)
        r = r / 11 - 0.5
        g = (r[:6] - r[6:]) @ eps / 12 - 0.01 * theta
        m = 0.9 * m + (1 - 0.9) * g
        v = 0.999 * v + (1 - 0.999) * g * g
        theta = np.clip(theta + 0.02 * np.sqrt(1 - 0.999**t) / (1 - 0.9**t) * m / (np.sqrt(v) + 1e-8), -0.3, 0.3)
        es.next_generation()
        assert np.array_equal(es.theta, theta) and np.array_equal(es.m, m)
    for name in ("walker-es-linear", "walker-ctrnn-es", "walker-es-robust", "steer-es"):
        es_table = tomllib.loads(presets.path(name).read_text())["es"]
        assert {k: es_table[k] for k in FIRST_SHIPPED} == FIRST_SHIPPED, name
    assert (ESOptions().weight_decay_to, ESOptions().credit, ESOptions().ties) == ("centre", "evaluated", "average")


@pytest.mark.parametrize("setting", ["credit = 'clip'", "ties = 'random'", "weight_decay_to = 1.0"])
def test_bad_es_update_settings_are_one_line(tmp_path, capsys, setting):
    from .conftest import cli

    (tmp_path / "c.toml").write_text(f"[es]\n{setting}\n")
    code = cli("evolve", "--preset", "walker-es-linear", "--config", tmp_path / "c.toml", "--out", tmp_path / "r",
               "--generations", 1)
    err = capsys.readouterr().err
    assert code == 2 and len(err.strip().splitlines()) == 1 and f"es.{setting.split()[0]}: must be one of" in err, err
    assert not (tmp_path / "r").exists()


def test_a_run_config_reads_and_writes_the_update_settings():
    config = RunConfig.from_dict({"optimizer": "es", "es": {"credit": "drawn"}, "episode": {"controller": "linear"}})
    assert config.to_dict()["es"]["credit"] == "drawn" and config.to_dict()["es"]["ties"] == "average"
