"""evobiped compare: its statistics against hand calculations, the budget stop, the fresh re-evaluation, a tiny
comparison that is the same bit for bit across runs and worker counts and after a resume, and its refusals."""

from __future__ import annotations

import dataclasses
import itertools
import json
import math
import shutil
from pathlib import Path

import numpy as np
import pytest

from evobiped.analysis.compare_stats import mann_whitney_p, median_iqr, vargha_delaney, wilson_ci
from evobiped.analysis.retest import FRESH_GENERATION, Success, fresh_noise, parse_success, retest
from evobiped.core.errors import UserError

from .conftest import cli

# ---------------------------------------------------------------- statistics


@pytest.mark.parametrize("a, b, expected", [
    ([1, 2, 3], [1, 2, 3], 0.5),  # the same samples: no effect
    ([3, 4], [1, 2], 1.0),  # every pair won
    ([1, 2], [3, 4], 0.0),
    ([2, 5, 7], [1, 5], 4.5 / 6),  # 2>1, 5>1, 5=5 (half), 7>1, 7>5: 4.5 of 6 pairs
    ([0.0], [0.0, 1.0, -1.0], 0.5),  # one win, one tie, one loss
])
def test_vargha_delaney_a_of_small_samples_by_hand(a, b, expected):
    assert vargha_delaney(a, b) == pytest.approx(expected, abs=1e-15)
    assert vargha_delaney(b, a) == pytest.approx(1 - expected, abs=1e-15)


@pytest.mark.parametrize("k, n", [(0, 5), (3, 10), (7, 7), (12, 40), (1, 2)])
def test_wilson_interval_is_the_score_formula(k, n):
    z = 1.959963984540054
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z / (1 + z * z / n) * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n))
    low, high = wilson_ci(k, n)
    assert low == pytest.approx(max(0.0, centre - half), abs=1e-9)
    assert high == pytest.approx(min(1.0, centre + half), abs=1e-9)


def _permutation_p(a, b) -> float:
    """The exact two-sided p of the rank-sum statistic over every split of the pooled sample (ties: midranks)."""
    pooled, m = np.concatenate([a, b]), len(a)
    ranks = np.array([(pooled < v).sum() + ((pooled == v).sum() + 1) / 2 for v in pooled])
    mean = m * (len(pooled) + 1) / 2
    observed = abs(ranks[:m].sum() - mean)
    splits = list(itertools.combinations(range(len(pooled)), m))
    return sum(abs(ranks[list(s)].sum() - mean) >= observed - 1e-12 for s in splits) / len(splits)


@pytest.mark.parametrize("a, b", [([1.1, 2.3, 3.7], [4.2, 5.0, 6.1, 0.5]),
                                  ([0.3, 0.9, 1.7, 2.2], [1.0, 1.5, 2.9, 3.3, 4.4]),
                                  ([5.0, 6.0], [1.0, 2.0, 3.0]), ([0.0, 0.0, 1.0], [1.0, 1.0, 1.0]),
                                  ([3.0, 3.0, 5.0, 0.0, 3.0], [3.0, 1.0, 1.0, 5.0, 2.0, 0.0]),
                                  ([1.0, 0.0, 1.0, 1.0, 0.0, 1.0, 1.0], [0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0])])
def test_mann_whitney_p_is_the_exact_permutation_p(a, b):
    assert mann_whitney_p(a, b) == pytest.approx(_permutation_p(np.array(a), np.array(b)), abs=1e-12)


def test_mann_whitney_p_with_ties_at_three_seeds_a_side_is_exact_not_the_normal_approximation():
    from scipy.stats import mannwhitneyu

    a, b = [0.0, 0.0, 1.0], [1.0, 1.0, 1.0]  # 8 of the 20 splits are as far from the mean rank sum as this one
    assert mann_whitney_p(a, b) == pytest.approx(0.4, abs=1e-12)
    assert mannwhitneyu(a, b).pvalue == pytest.approx(0.19, abs=0.01)


def test_mann_whitney_of_identical_constant_samples_is_one_and_median_iqr_interpolates():
    assert mann_whitney_p([0.0, 0.0], [0.0, 0.0, 0.0]) == 1.0
    assert median_iqr([1, 2, 3, 4]) == (2.5, 1.75, 3.25)
    assert all(math.isnan(x) for x in median_iqr([]))


# ---------------------------------------------------------------- the budget and the fresh re-evaluation


def test_a_run_stops_at_the_first_generation_boundary_where_its_episodes_reach_the_budget(tmp_path):
    from evobiped.run.run_config import RunConfig
    from evobiped.usecases.evolving import evolve

    plain = RunConfig.from_dict({"episode": {"seconds": 0.2}, "ga": {"population": 4}, "generations": 50, "budget": 9,
                                 "backend": "serial"})
    assert evolve(plain, out=tmp_path / "a")["evaluations"] == 10  # 4, then 2 new each: 4, 6, 8, 10 >= 9
    twice = RunConfig.from_dict({"episode": {"seconds": 0.2, "perturbations": {"presentations": 2}},
                                 "ga": {"population": 4}, "generations": 50, "budget": 9, "backend": "serial"})
    summary = evolve(twice, out=tmp_path / "b")  # 2 episodes a genome: 8, then 12 >= 9
    assert (summary["generations"], summary["evaluations"]) == (2, 6)
    assert cli("evolve", "--resume", tmp_path / "b", "--quiet") == 0  # an ordinary run directory, complete


def test_the_walker_and_forward_tests_without_noise_are_forward_walkers():
    """Without noise (one presentation), the two tests are ``forward_walker``'s verdicts: ``walker`` (the gait lab's
    walk) and ``forward`` (the older, gait-blind test)."""
    from evobiped.analysis.selection import forward_walker
    from evobiped.files.genome_file import load_genome

    genome, config, _ = load_genome(Path(__file__).resolve().parent.parent / "docs" / "walkers" / "ctrnn_es_seed5.json")
    config = dataclasses.replace(config, seconds=1.0)  # the measure's episode; the tests' is 200 s whatever it is
    none = fresh_noise({}, 1)
    fallen = config.layout().sample(np.random.default_rng(0))  # falls within a second
    for g, forward, walker in ((genome, True, False), (fallen, False, False)):  # this one runs (it has a flight phase)
        found = forward_walker(config, g)
        assert (found["forward"], found["walker"]) == (forward, walker)
        for test, expected in (("forward", forward), ("walker", walker)):
            assert retest(config, g, seed=0, noise=none, measure="fitness",
                          success=Success(test=test))["success"] == expected


def test_fresh_presentations_are_new_draws_the_same_for_one_seed():
    from evobiped.episode import EpisodeConfig

    config = EpisodeConfig(seconds=0.5)
    genome = config.layout().sample(np.random.default_rng(3))
    noise = fresh_noise(None, 3)
    crit = parse_success("distance>=0.1", ("distance",))
    first = retest(config, genome, seed=1, noise=noise, measure="distance", success=crit)
    assert first == retest(config, genome, seed=1, noise=noise, measure="distance", success=crit)
    assert len(set(first["measure"])) == 3  # three draws, three walks
    assert retest(config, genome, seed=2, noise=noise, measure="distance", success=crit)["measure"] != first["measure"]
    assert FRESH_GENERATION > 10**6  # beyond any run's generations: drawn by no run
    assert first["passed"] == [d >= 0.1
                               for d in first["measure"]] and first["value"] == float(np.median(first["measure"]))
    with pytest.raises(UserError, match="not fitness nor a term"):
        parse_success("speed>=1", ("distance",))


# ---------------------------------------------------------------- a tiny comparison end to end

TINY = """optimizer = "{optimizer}"
[{optimizer}]
population = 4
[episode]
seconds = {seconds}
"""
FLAGS = ["--seeds", "2", "--budget", "12", "--trials", "2", "--checkpoints", "2", "--success", "distance>=0.2",
         "--quiet"]


def _configs(where, seconds=0.5):
    where.mkdir(parents=True, exist_ok=True)
    paths = []
    for optimizer in ("ga", "cma"):
        p = where / f"{optimizer}_tiny.toml"
        p.write_text(TINY.format(optimizer=optimizer, seconds=seconds))
        paths.append(p)
    return paths


@pytest.fixture(scope="module")
def compared(tmp_path_factory):
    """One tiny comparison (two configurations, two seeds, two runs at once) and its printed table."""
    where = tmp_path_factory.mktemp("compared")
    configs = _configs(where / "configs")
    import io
    from contextlib import redirect_stdout

    out = io.StringIO()
    with redirect_stdout(out):
        assert cli("compare", *configs, *FLAGS, "--workers", "2", "--out", where / "a") == 0
    return where, configs, out.getvalue()


def _files(d):
    return {p.relative_to(d): p.read_bytes() for p in sorted(d.rglob("*")) if p.is_file()}


def test_a_tiny_comparison_reports_every_statistic(compared):
    where, _, printed = compared
    d = where / "a"
    results = json.loads((d / "results.json").read_text())
    assert [c["name"] for c in results["configurations"]] == ["ga_tiny", "cma_tiny"]
    for c in results["configurations"]:
        assert c["runs"] == 2 and len(c["values"]) == 2 and c["wilson"] == list(wilson_ci(c["successes"], 2))
        assert all(e >= 12 for e in c["episodes"]) and c["curve"][-1]["successes"] == c["successes"]
    pair = results["pairs"][0]
    a, b = (c["values"] for c in results["configurations"])
    assert pair["A"] == vargha_delaney(a, b) and pair["p"] == mann_whitney_p(a, b)
    assert (d / "results.md").read_text() in printed and "| ga_tiny vs cma_tiny |" in printed
    assert (d / "success.png").read_bytes()[:4] == b"\x89PNG"
    for seed in (0, 1):  # ordinary run directories at the budget
        run = d / "runs" / "cma_tiny" / f"seed_{seed:03d}"
        assert json.loads((run / "config.json").read_text())["budget"] == 12 and (run / "summary.json").is_file()


def test_the_same_seeds_give_the_same_results_bit_for_bit_with_one_worker(compared):
    where, configs, _ = compared
    assert cli("compare", *configs, *FLAGS, "--workers", "1", "--out", where / "b") == 0
    for name in ("results.json", "results.md"):
        assert (where / "a" / name).read_bytes() == (where / "b" / name).read_bytes()


def test_a_resumed_comparison_finishes_an_interrupted_run_and_gives_the_same_results(compared):
    from evobiped.run.run_config import RunConfig
    from evobiped.usecases.comparing import Comparison, FILE
    from evobiped.usecases.evolving import evolve

    where, configs, _ = compared
    c = where / "c"
    shutil.copytree(where / "a", c)
    for name in ("results.json", "results.md", "success.png"):
        (c / name).unlink()
    comparison = Comparison.from_dict(json.loads((c / FILE).read_text()), "comparison")
    run_dir, config, retested = comparison.jobs(c)[1][:3]  # ga_tiny, seed 1: its later generations and retest deleted
    shutil.rmtree(run_dir)
    Path(retested).unlink()

    def stop(stats):
        if stats.generation == 1:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        evolve(RunConfig.from_dict(config), out=run_dir, on_generation=stop)
    assert len(json.loads((Path(run_dir) / "checkpoint.json").read_text())["history"]) == 2
    (c / "retests" / "cma_tiny_seed_000.json").unlink()  # a retest alone: re-evaluated, the run left as it is
    assert cli("compare", "--resume", c, "--quiet") == 0
    for name in ("results.json", "results.md"):
        assert (where / "a" / name).read_bytes() == (c / name).read_bytes()
    # the same ones named again: nothing to do
    assert cli("compare", *configs, "--resume", c, "--seeds", "2", "--quiet") == 0
    assert (where / "a" / "results.json").read_bytes() == (c / "results.json").read_bytes()


def test_a_resumed_comparison_whose_configurations_changed_is_refused(compared, capsys):
    where, configs, _ = compared
    changed = _configs(where / "changed", seconds=0.4)
    before = _files(where / "a")
    capsys.readouterr()
    assert cli("compare", *changed, "--resume", where / "a") == 2
    err = capsys.readouterr().err
    assert err.startswith("evobiped: error: ") and err.count("\n") == 1 and "other configurations" in err, err
    assert cli("compare", *configs, "--resume", where / "a", "--budget", "16") == 2
    assert "other budget" in capsys.readouterr().err
    assert _files(where / "a") == before


# ---------------------------------------------------------------- refusals


@pytest.mark.parametrize("argv, words", [
    (["--seeds", "0", "--budget", "12"], "--seeds: must be > 0"),
    (["--seeds", "2", "--budget", "3"], "below one generation"),
    (["--seeds", "2", "--budget", "12", "--measure", "speed"], "not fitness nor a term"),
    (["--seeds", "2", "--budget", "12", "--success", "distance=>3"], "give walker, forward or TERM>=X"),
    (["--budget", "12"], "--seeds: required"),
    (["--seeds", "2", "--budget", "12", "--noise", "{configs}/ga_tiny.toml"], "has no [episode.perturbations] table"),
])
def test_bad_input_is_one_line_exit_2_and_writes_nothing(tmp_path, capsys, argv, words):
    configs = _configs(tmp_path / "configs")
    argv = [a.format(configs=tmp_path / "configs") for a in argv]
    assert cli("compare", *configs, *argv, "--out", tmp_path / "out") == 2
    err = capsys.readouterr().err
    assert err.startswith("evobiped: error: ") and err.count("\n") == 1 and words in err, err
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("case, words", [("tasks", "different tasks"), ("preset", "neither a preset"),
                                         ("missing", "settings file not found"), ("resume", "holds no comparison")])
def test_bad_configurations_are_one_line_exit_2_and_write_nothing(tmp_path, capsys, case, words):
    ga, _ = _configs(tmp_path / "configs")
    steer = tmp_path / "configs" / "steer.toml"
    steer.write_text('[ga]\npopulation = 4\n[episode]\ntask = "steer"\nseconds = 0.5\n')
    other = {"tasks": [steer], "preset": ["no-such-preset"], "missing": [tmp_path / "missing.toml"], "resume": []}[case]
    where = ["--resume", tmp_path / "out"] if case == "resume" else ["--out", tmp_path / "out"]
    assert cli("compare", ga, *other, "--seeds", "2", "--budget", "12", *where) == 2
    err = capsys.readouterr().err
    assert err.startswith("evobiped: error: ") and err.count("\n") == 1 and words in err, err
    assert not (tmp_path / "out").exists()
