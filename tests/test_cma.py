"""CMA-ES behind the GA's seam: it optimises, resumes exactly, keeps to the bounds, refuses bad input."""

import json

import numpy as np
import pytest

from evobiped.cli import main
from evobiped.episode import EpisodeConfig
from evobiped.core.errors import ConfigError, UserError
from evobiped.run import Run, RunConfig
from evobiped.evaluation import make_evaluator
from evobiped.optimizers.cma import CMAES, CMAOptions
from evobiped.run.individuals import Individuals
from evobiped.interface.genome import GeneBlock, GenomeLayout

from .test_evolve import fitness_history

LAYOUT = GenomeLayout((GeneBlock(name="x", size=10, low=-5.0, high=5.0, init_mean=3.0, init_sigma=1.0,
                                 mutation_sigma=1.0),))


def optimise(opt, f, generations):
    for _ in range(generations):
        pop, unknown = opt.ask()
        opt.tell(f(pop[unknown]))
        opt.next_generation()
    return opt


def test_nothing_is_carried():
    """CMA-ES samples a fresh population each generation: every new row is a new individual, so a run's outcomes
    are unknown after it (NaN here, null in the checkpoint, never zeros)."""
    opt = CMAES(LAYOUT, CMAOptions(population=4), seed=2)
    opt.tell(np.array([1.0, 4.0, 2.0, 3.0]))
    ind = Individuals(outcome={"end_time": np.array([0.5, 2.0, 1.0, 1.5])})
    rows = opt.next_generation()
    assert rows.tolist() == [-1] * 4
    ind.carry(rows)
    assert np.isnan(ind.outcome["end_time"]).all() and not ind.known.any()
    assert ind.to_dict()["end_time"] == [None] * 4 and ind.to_dict()["previous"] == [None] * 4


def test_minimises_a_sphere_inside_the_bounds():
    """-|x - c|^2 with c inside the box: the mean reaches c; every sample stays within the bounds."""
    c = np.linspace(-4, 4, 10)
    seen = []

    def f(pop):
        seen.append(pop.copy())
        return -((pop - c) ** 2).sum(axis=1)

    opt = optimise(CMAES(LAYOUT, CMAOptions(sigma0=0.3), seed=1), f, 150)
    best = opt.population[opt.ranking()[0]] if not np.isnan(opt.fitness).all() else None
    assert best is None  # a fresh, not yet evaluated generation
    pop, _ = opt.ask()
    assert np.abs(pop.mean(axis=0) - c).max() < 1e-3
    allpop = np.concatenate(seen)
    assert allpop.min() >= -5 and allpop.max() <= 5
    assert len(seen[0]) == 4 + int(3 * np.log(10))  # pycma's default population


def test_state_round_trip_asks_the_same():
    """A checkpointed strategy replays its told fitness and asks the identical next population."""
    f = lambda pop: -np.abs(pop).sum(axis=1)  # noqa: E731
    a = optimise(CMAES(LAYOUT, CMAOptions(population=6, restarts=1), seed=3), f, 12)
    state = json.loads(json.dumps(a.state().to_dict()))
    b = CMAES(LAYOUT, CMAOptions(population=6, restarts=1), seed=3)
    b.restore(b.state_from(state))
    assert b.generation == 12 and np.array_equal(a.ask()[0], b.ask()[0])
    optimise(a, f, 3)
    optimise(b, f, 3)
    assert np.array_equal(a.ask()[0], b.ask()[0])


def test_ipop_restart_doubles_the_population():
    """A flat fitness stops pycma (tolflatfitness); the restart doubles lambda."""
    opt = optimise(CMAES(LAYOUT, CMAOptions(population=4, restarts=1), seed=0), lambda pop: np.zeros(len(pop)), 40)
    assert opt.restart == 1 and len(opt.ask()[0]) == 8


@pytest.mark.parametrize("bad", [dict(population=1), dict(sigma0=0.0), dict(sigma0=float("nan")), dict(sigma0=2.0),
                                 dict(restarts=-1), dict(population=True)])
def test_bad_settings(bad):
    with pytest.raises(ConfigError):
        CMAOptions(**bad)


def test_tampered_state_is_refused():
    opt = CMAES(LAYOUT, CMAOptions(population=4), seed=0)
    good = json.loads(json.dumps(optimise(CMAES(LAYOUT, CMAOptions(population=4), seed=0),
                                          lambda p: -np.abs(p).sum(axis=1), 2).state().to_dict()))
    strategy = good["strategy"]
    foreign = json.loads(json.dumps(strategy).replace('"cma.sampler:', '"os:', 1))  # a class outside pycma named
    assert foreign != strategy
    old = {"name": "cma", "generation": 2, "fitness": [None] * 4}
    for bad in ({**good, "strategy": "x"}, {**good, "strategy": foreign},
                {**good, "strategy": {**strategy, "asked": strategy["es"]}},
                {**good, "generation": "5"}, {"name": "ga"}, {**good, "fitness": [1.0]}, {**good, "restart": 3},
                {**good, "restart": True},
                {**old, "told": [[1.0] * 3, [1.0] * 4]}, {**old, "told": "x"}, {**old, "told": [[1.0] * 4, ["x"] * 4]},
                {**old, "generation": 5, "told": [[1.0] * 4] * 2}):
        with pytest.raises(UserError):
            opt.restore(opt.state_from(bad))


def test_a_cma_state_of_an_older_checkpoint_is_read():
    """Older checkpoints kept the fitness told at every generation (``told``; before that the state's name was
    ``optimizer``): such a table is replayed into the same strategy."""
    told = []

    def f(p):
        told.append((-np.abs(p).sum(axis=1)).tolist())
        return np.array(told[-1])

    a = optimise(CMAES(LAYOUT, CMAOptions(population=4), seed=1), f, 3)
    old = {"optimizer": "cma", "generation": 3, "told": told, "fitness": [None] * 4}
    b = CMAES(LAYOUT, CMAOptions(population=4), seed=1)
    b.restore(b.state_from(old))
    assert b.generation == 3 and np.array_equal(a.ask()[0], b.ask()[0])
    assert not b.state().fitness.flags.writeable


def test_a_resume_costs_the_same_at_any_generation():
    """The stored strategy is written into a fresh one: restoring generation 200 takes no longer than generation 2."""
    import time

    f = lambda p: -np.abs(p).sum(axis=1)  # noqa: E731
    costs = []
    for n in (2, 200):
        state = json.loads(json.dumps(optimise(CMAES(LAYOUT, CMAOptions(population=4), seed=1), f,
                                               n).state().to_dict()))
        t = time.perf_counter()
        b = CMAES(LAYOUT, CMAOptions(population=4), seed=1)
        b.restore(b.state_from(state))
        costs.append(time.perf_counter() - t)
        assert b.generation == n
    assert costs[1] < 5 * costs[0] + 0.05, costs


SMALL = RunConfig(episode=EpisodeConfig(controller="simbicon", seconds=1.0, task_options={"fitness": "forward"}),
                  optimizer="cma", optimizer_options={"cma": CMAOptions(population=6)}, generations=4, seed=2,
                  backend="serial")


def test_cma_run_resumes_bit_identically(tmp_path):
    """An interrupted CMA-ES run resumed (on 2 workers) gives the uninterrupted history and best genome."""
    from .test_evolve import whole_and_resumed

    whole, cut = whole_and_resumed(tmp_path, SMALL, stop_after=0)
    assert fitness_history(cut) == fitness_history(whole.dir)
    a, b = (json.loads((d / "best.json").read_text()) for d in (whole.dir, cut))
    assert a["genome"] == b["genome"] and a["fitness"] == b["fitness"]
    # CMA-ES improves on its first generation in this small run (the forward fitness is positive)
    hist = fitness_history(whole.dir)
    assert float(hist[-1][1]) > 0


def test_resume_with_another_optimizer_is_refused(tmp_path, capsys):
    run = Run.create(tmp_path / "r", SMALL)
    with make_evaluator(SMALL.episode, "serial") as ev:
        run.step(ev)
        run.checkpoint()
    cfg = json.loads((tmp_path / "r" / "config.json").read_text())
    cfg["optimizer"] = "ga"
    (tmp_path / "r" / "config.json").write_text(json.dumps(cfg))
    assert main(["evolve", "--resume", str(tmp_path / "r"), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and 'optimizer "cma" → "ga"' in err[0]
    # a checkpoint of before the settings were recorded
    ck = json.loads((tmp_path / "r" / "checkpoint.json").read_text())
    older = {k: v for k, v in ck.items() if k not in ("settings", "start", "format")}
    (tmp_path / "r" / "checkpoint.json").write_text(json.dumps(older))
    assert main(["evolve", "--resume", str(tmp_path / "r"), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "'cma' optimizer" in err[0]


def test_cli_optimizer_flag_and_population(tmp_path, capsys):
    out = tmp_path / "c"
    assert main(["evolve", "--optimizer", "cma", "--controller", "simbicon", "--population", "5", "--generations", "2",
                 "--episode-seconds", "0.5", "--backend", "serial", "--out", str(out), "--quiet"]) == 0
    cfg = json.loads((out / "config.json").read_text())
    assert cfg["optimizer"] == "cma" and cfg["cma"]["population"] == 5
    assert int(fitness_history(out)[0][5]) == 5  # five evaluations in generation 0
    with pytest.raises(SystemExit) as exc:
        main(["evolve", "--optimizer", "nope", "--out", str(tmp_path / "x")])
    assert exc.value.code == 2
    assert not (tmp_path / "x").exists()
