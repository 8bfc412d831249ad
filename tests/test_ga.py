"""The GA of Reil & Husbands (Table III, Sect. II-C1): operator statistics and search."""

import json

import numpy as np
import pytest

from evobiped.controllers import CTRNN
from evobiped.core.errors import ConfigError
from evobiped.episode.result import EpisodeResult
from evobiped.optimizers.ga import GA, GAOptions
from evobiped.run.individuals import Individuals
from evobiped.interface.genome import GeneBlock, GenomeLayout

LAYOUT = CTRNN(n_outputs=6).layout


def test_initial_population_table_III():
    ga = GA(LAYOUT, GAOptions(population=4000), seed=1)
    pop = ga.population
    w, tau, b = pop[:, :100], pop[:, 100:110], pop[:, 110:]
    assert pop.min() >= -16 and pop.max() <= 16
    assert tau.min() >= 0.5 and tau.max() <= 5 and b.min() >= -4 and b.max() <= 4
    # clipped Gaussians: the fraction at the clip bounds equals the Gaussian tail mass
    assert np.mean(np.abs(w) == 16) == pytest.approx(0.0455, abs=0.004)  # |N(0, 8)| > 2 sigma
    assert np.median(w) == pytest.approx(0, abs=0.1)
    assert np.median(tau) == pytest.approx(2.75, abs=0.05)  # clipping keeps the median
    assert np.mean(tau == 0.5) == pytest.approx(0.0668, abs=0.006)  # P(N(2.75, 1.5) < 0.5) = P(z < -1.5)
    assert np.mean(np.abs(b) == 4) == pytest.approx(0.1824, abs=0.008)  # P(|N(0, 3)| > 4/3 sigma)


def test_one_mutation_per_chromosome_on_average():
    ga = GA(LAYOUT, GAOptions(), seed=2)
    assert ga.mutation_rate == pytest.approx(1 / 120)
    parents = np.zeros((20000, 120)) + LAYOUT.init_mean
    children = ga.mutate(parents, np.random.default_rng(0))
    changed = (children != parents).sum(axis=1)
    assert changed.mean() == pytest.approx(1.0, abs=0.03)
    assert np.mean(changed == 0) == pytest.approx((1 - 1 / 120) ** 120, abs=0.01)  # binomial P(0) ~ e^-1
    # per-type mutation sigma (Table III): 8, 1.5, 3 (tau at 2.75 and biases at 0 rarely clip)
    d = children - parents
    tau_d = d[:, 100:110][d[:, 100:110] != 0]
    bias_d = d[:, 110:][d[:, 110:] != 0]
    assert np.std(tau_d) == pytest.approx(1.5 * 0.93, rel=0.08)  # clipping at 0.5 / 5 trims the tails
    assert np.std(bias_d) == pytest.approx(3 * 0.88, rel=0.08)
    assert children.min() >= LAYOUT.low.min() and np.all(children <= LAYOUT.high) and np.all(children >= LAYOUT.low)


def test_mutation_clips_to_range():
    lay = GenomeLayout((GeneBlock(name="x", size=1, low=-1, high=1, init_mean=0, init_sigma=0, mutation_sigma=100),))
    ga = GA(lay, GAOptions(population=2), seed=0)
    out = ga.mutate(np.zeros((10000, 1)), np.random.default_rng(1))
    assert out.min() == -1.0 and out.max() == 1.0
    # rate 1 for a one-gene genome; P(|N(0, 100)| > 1) = 0.992, half of it clipped to each bound
    assert np.mean(out == 1) == pytest.approx(0.496, abs=0.015)
    assert np.mean(out == -1) == pytest.approx(0.496, abs=0.015)


def test_truncation_keeps_top_half_unchanged():
    ga = GA(LAYOUT, GAOptions(population=10), seed=3)
    pop0 = ga.population.copy()
    fit = np.array([5, 1, 9, 3, 7, 0, 8, 2, 6, 4], float)
    ga.tell(fit)
    ga.next_generation()
    top = [2, 6, 4, 8, 0]  # best first
    assert np.array_equal(ga.population[:5], pop0[top])
    assert np.array_equal(ga.fitness[:5], fit[top]) and np.isnan(ga.fitness[5:]).all()
    # each child is a copy of parent i (mutated in about one gene)
    diff = (ga.population[5:] != pop0[top]).sum(axis=1)
    assert diff.max() <= 5
    pop, unknown = ga.ask()
    assert unknown.tolist() == [False] * 5 + [True] * 5


def _result(fitness, fell, unstable, end_time):
    """An EpisodeResult of walkers that went ``fitness`` m along +x, with the term ``distance`` beside it."""
    n = len(fitness)
    end = np.stack([fitness, np.zeros(n)], 1)
    return EpisodeResult(fitness=fitness, fell=fell, unstable=unstable, end_time=end_time,
                         start_position=np.zeros((n, 2)),
                         end_position=end, start_facing=np.tile([1.0, 0.0], (n, 1)), terms={"distance": fitness.copy()})


def test_survivors_keep_their_outcome():
    """The rows the GA keeps (next_generation's answer) carry each survivor's fell / unstable / end_time, terms and
    walk along (best first); the children's are unknown (NaN; null in the checkpoint, never zeros) until told, with
    the survivor each was bred from; a second tell fills only their rows."""
    ga = GA(LAYOUT, GAOptions(population=6), seed=5)
    ind = Individuals()
    fit = np.array([3.0, 1.0, 5.0, 0.0, 4.0, 2.0])
    _, unknown = ga.ask()
    r = _result(fit, fit < 2.5, fit == 0.0, 10 * fit)
    ga.tell(r)
    ind.record_results(unknown, r)
    assert ind.outcome["end_time"].tolist() == [30.0, 10.0, 50.0, 0.0, 40.0, 20.0]
    ind.carry(ga.next_generation(), ga.parent_rows())  # survivors 2, 4, 0 (fitness 5, 4, 3)
    assert ind.outcome["end_time"][:3].tolist() == [50.0, 40.0, 30.0] and np.isnan(ind.outcome["end_time"][3:]).all()
    carried = ind.to_dict()
    assert carried["end_time"] == [50.0, 40.0, 30.0, None, None, None] and carried["fell"] == [False] * 3 + [None] * 3
    assert carried["previous"] == [2, 4, 0, None, None, None] and carried["parents"] == [None, None, None, 2, 4, 0]
    assert ind.terms_of(1) == {"distance": 4.0} and ind.walk_of(0) == {"distance": 5.0, "heading_deg": 0.0,
                                                                       "displacement": [5.0, 0.0]}
    _, unknown = ga.ask()
    r = _result(np.array([6.0, 1.0, 2.0]), np.array([False, True, True]), np.array([False, False, True]),
                np.array([60.0, 1.5, 2.5]))
    ga.tell(r)
    ind.record_results(unknown, r)
    assert ind.outcome["end_time"].tolist() == [50.0, 40.0, 30.0, 60.0, 1.5, 2.5]
    assert ind.outcome["unstable"].tolist() == [False] * 5 + [True]
    back = Individuals.from_dict(json.loads(json.dumps(ind.to_dict())), 6)
    assert back.to_dict() == ind.to_dict() and back.to_dict()["fell"] == [False, False, False, False, True, True]
    ind.carry(ga.next_generation())  # survivors: rows 3 (6.0), 0 (5.0), 1 (4.0)
    assert ind.to_dict()["end_time"] == [60.0, 50.0, 40.0, None, None, None]
    assert ind.to_dict()["terms"]["distance"] == [6.0, 5.0, 4.0, None, None, None]


def test_frozen_genes_never_change():
    mutable = np.zeros(120, bool)
    mutable[110:] = True
    ga = GA(LAYOUT, GAOptions(population=6), seed=4, initial=LAYOUT.init_mean, mutable=mutable)
    assert ga.mutation_rate == pytest.approx(1 / 10)
    for g in range(30):
        _, unknown = ga.ask()
        ga.tell(np.random.default_rng(g).random(int(unknown.sum())))
        ga.next_generation()
    assert np.all(ga.population[:, :110] == LAYOUT.init_mean[:110])
    assert np.any(ga.population[:, 110:] != LAYOUT.init_mean[110:])


def test_ga_improves_a_known_function():
    """Maximise -||x - x*||^2 on a 12-gene layout: the GA gets close to x*."""
    lay = GenomeLayout((GeneBlock(name="x", size=12, low=-5, high=5, init_mean=0, init_sigma=2, mutation_sigma=0.3),))
    target = np.linspace(-3, 3, 12)
    ga = GA(lay, GAOptions(population=50), seed=5)
    first = None
    for g in range(400):
        pop, unknown = ga.ask()
        ga.tell(-((pop[unknown] - target) ** 2).sum(axis=1))
        if first is None:
            first = ga.fitness.max()
        if g < 399:
            ga.next_generation()
    assert first < -30
    assert ga.fitness.max() > -0.5
    # survivors keep their fitness: the best never gets worse
    assert np.isfinite(ga.fitness).all()


def test_same_seed_same_population_and_bad_configs():
    a, b = GA(LAYOUT, GAOptions(), seed=9), GA(LAYOUT, GAOptions(), seed=9)
    assert np.array_equal(a.population, b.population)
    assert not np.array_equal(a.population, GA(LAYOUT, GAOptions(), seed=10).population)
    for bad in (dict(population=1), dict(fittest_fraction=1.0), dict(mutations_per_genome=0), dict(population=2.5)):
        with pytest.raises(ConfigError):
            GAOptions(**bad)


def test_table_iii_numbers_are_config_values(tmp_path):
    """`genes` controller options replace a block's initialisation and mutation (here: fixed weights, frozen taus)."""
    from evobiped.episode import EpisodeConfig
    from evobiped.run import Run, RunConfig
    from evobiped.evaluation import make_evaluator

    genes = {"weights": {"init_mean": 2.0, "init_sigma": 0.0},
             "time_constants": {"mutation_sigma": 0.0, "low": 1.0, "high": 3.0}}
    cfg = RunConfig(episode=EpisodeConfig(seconds=0.2, controller_options={"genes": genes}),
                    optimizer_options={"ga": GAOptions(population=10)}, generations=3, backend="serial")
    run = Run.create(tmp_path / "r", cfg)
    layout = cfg.episode.build().controller.layout
    s = layout.slices()
    first = run.optimizer.ask()[0].copy()
    assert np.all(first[:, s["weights"]] == 2.0)
    assert first[:, s["time_constants"]].min() >= 1.0 and first[:, s["time_constants"]].max() <= 3.0
    with make_evaluator(cfg.episode, "serial") as ev:
        run.evolve(ev)
    taus = run.optimizer.population[:, s["time_constants"]]
    assert {tuple(t) for t in taus} <= {tuple(t) for t in first[:, s["time_constants"]]}  # never mutated


@pytest.mark.parametrize(
    "genes, words",
    [({"wieghts": {"init_sigma": 1}}, "no gene block 'wieghts'"), ({"weights": {"sigma": 1}}, "expected a table of"),
     ({"biases": {"low": 5, "high": 1}}, "bad size or bounds")],
)
def test_bad_gene_overrides(genes, words):
    from evobiped.episode import EpisodeConfig
    from evobiped.core.errors import ConfigError

    with pytest.raises(ConfigError, match=f"^episode.controller_options.genes.*{words}"):
        EpisodeConfig(controller_options={"genes": genes}).layout()


def test_children_carry_about_one_mutation_each_at_the_block_sigma():
    """Mutation at the per-locus rate 1 / G: over 2,000 children the number of changed genes is Binomial(G, 1/G) (mean
    1, about (1 - 1/G)^G = 37 % unchanged), and a changed gene moves by the Gaussian of its block's sigma (Table
    III)."""
    ga = GA(LAYOUT, GAOptions(population=4000), seed=11)
    parents = ga.population.copy()
    fitness = np.arange(4000, dtype=float)
    ga.tell(fitness)
    ga.next_generation()
    best = np.argsort(-fitness, kind="stable")[:2000]  # the survivors, best first; child i is a copy of survivor i
    assert np.array_equal(ga.population[:2000], parents[best])
    children, sources = ga.population[2000:], parents[best]
    changed = children != sources
    G = LAYOUT.size
    assert abs(changed.sum(axis=1).mean() - 1.0) < 0.1
    assert abs((changed.sum(axis=1) == 0).mean() - (1 - 1 / G) ** G) < 0.05
    w = LAYOUT.slices()["weights"]
    inside = changed[:, w] & (np.abs(sources[:, w]) < 8)  # far from the clipping bounds (+-16)
    step = (children[:, w] - sources[:, w])[inside]
    assert len(step) > 300 and abs(step.std() - LAYOUT.blocks[0].mutation_sigma) < 0.1 * LAYOUT.blocks[0].mutation_sigma
