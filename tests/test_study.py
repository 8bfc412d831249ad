"""Studies: the statistics on known numbers, and a tiny study end to end (resume, growth, bad input)."""

import csv
import json
import math

import numpy as np
import pytest

from evobiped.experiments.reil.stats import histogram_edges, mean_std, wilson_interval
from evobiped.experiments.reil.study_results import summarize

from .conftest import cli


@pytest.mark.parametrize(
    "k, n, low, high",
    # textbook values of the 95 % Wilson score interval (e.g. Newcombe 1998, Table I; Agresti & Coull 1998)
    [(0, 10, 0.0, 0.2775), (1, 10, 0.0179, 0.4042), (8, 10, 0.4902, 0.9433), (5, 10, 0.2366, 0.7634),
     (10, 100, 0.0552, 0.1744), (80, 100, 0.7112, 0.8666)],
)
def test_wilson_interval_known_values(k, n, low, high):
    lo, hi = wilson_interval(k, n)
    assert lo == pytest.approx(low, abs=5e-5) and hi == pytest.approx(high, abs=5e-5)


def test_wilson_interval_edges():
    assert all(math.isnan(x) for x in wilson_interval(0, 0))
    with pytest.raises(ValueError):
        wilson_interval(3, 2)


def test_mean_std_is_the_sample_deviation():
    m, s = mean_std([20.0, 21.0, 22.0, 19.0])
    assert m == 20.5 and s == pytest.approx(math.sqrt(((0.5**2) * 2 + 1.5**2 * 2) / 3))
    assert math.isnan(mean_std([3.0])[1]) and all(math.isnan(x) for x in mean_std([]))


def test_histogram_edges_cover_every_value_in_metre_bins():
    v = [0.5, 2.0, 7.9, 20.577]
    e = histogram_edges(v)
    assert e[0] == 0 and e[-1] == 21 and np.all(np.diff(e) == 1.0)
    counts, _ = np.histogram(v, bins=e)
    assert counts.sum() == 4 and counts[2] == 1 and counts[20] == 1  # 2.0 falls in [2, 3)
    assert list(histogram_edges([], 1.0)) == [0.0, 1.0]


def test_summarize_synthetic_outcomes():
    """10 plain runs, 1 stable (the paper's 10 %); 5 cyclic runs, 4 stable."""
    outs = [{"condition": "plain", "distance": 7.0 + i, "fell": True, "walks_indefinitely": None, "wall_seconds": 10.0}
            for i in range(9)]
    outs.append({"condition": "plain", "distance": 20.5, "fell": False, "walks_indefinitely": True,
                 "wall_seconds": 100.0})
    outs += [{"condition": "cyclic", "distance": f, "fell": False, "walks_indefinitely": f > 20, "wall_seconds": 50.0}
             for f in (19.0, 20.0, 21.0, 22.0)]
    outs.append({"condition": "cyclic", "distance": 3.0, "fell": True, "walks_indefinitely": None, "wall_seconds": 5.0})
    plain, cyclic = summarize(outs, ("plain", "cyclic"))
    assert (plain["runs"], plain["stable"], plain["success_rate"]) == (10, 1, 0.1)
    assert (plain["ci95_low"], plain["ci95_high"]) == pytest.approx((0.0179, 0.4042), abs=5e-5)
    assert plain["stable_mean_m"] == 20.5 and math.isnan(plain["stable_std_m"])
    assert plain["unstable_mean_m"] == 11.0 and plain["unstable_std_m"] == pytest.approx(np.std(np.arange(
        7.0, 16.0), ddof=1))
    assert plain["wall_seconds"] == 190.0 and plain["walks_indefinitely"] == 1
    assert (cyclic["stable"], cyclic["success_rate"], cyclic["stable_mean_m"],
            cyclic["walks_indefinitely"]) == (4, 0.8, 20.5, 2)



TINY = ["--population", 4, "--generations", 2, "--episode-seconds", 1, "--recheck-seconds", 3, "--workers", 2,
        "--quiet"]


def test_tiny_study_end_to_end(tmp_path, capsys):
    out = tmp_path / "study"
    assert cli("study", "--runs", 2, *TINY, "--out", out) == 0
    table = capsys.readouterr().out
    assert "| plain | 2 |" in table and "| cyclic | 2 |" in table
    runs = list(csv.DictReader(open(out / "runs.csv")))
    assert [(r["condition"], r["seed"]) for r in runs] == [("plain", "0"), ("plain", "1"), ("cyclic", "0"),
                                                           ("cyclic", "1")]
    for r in runs:  # each row is its run directory's best walker
        d = out / r["condition"] / f"seed_{int(r['seed']):03d}"
        best = json.loads((d / "best.json").read_text())
        assert float(r["fitness"]) == best["fitness"] and (r["fell"] == "True") == best["fell"]
        if r["condition"] == "plain":  # eq. 4: fitness is the distance
            assert float(r["distance"]) == best["fitness"]
        assert len((d / "history.csv").read_text().splitlines()) == 3
        assert json.loads((d / "config.json").read_text())["episode"]["task_options"]["cyclic_weight"] == (1.0 if r[
            "condition"] == "cyclic" else 0.0)
    t = {row["condition"]: row for row in json.loads((out / "table.json").read_text())["conditions"]}
    for c in ("plain", "cyclic"):
        stable = sum(1 for r in runs if r["condition"] == c and r["fell"] == "False")
        assert t[c]["runs"] == 2 and t[c]["stable"] == stable
    for png in ("distances.png", "fitness_graphs.png"):
        assert (out / png).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"

    # the same command again: nothing re-run; with --runs 3 only the new seeds run
    mtimes = {p: p.stat().st_mtime_ns for p in out.rglob("checkpoint.json")}
    assert cli("study", "--runs", 3, *TINY, "--out", out) == 0
    assert all(p.stat().st_mtime_ns == t for p, t in mtimes.items())
    assert len(list(csv.DictReader(open(out / "runs.csv")))) == 6


def test_interrupted_study_resumes_unfinished_runs(tmp_path):
    """A run stopped after generation 1 of 3 is resumed from its checkpoint and ends as an uninterrupted one."""
    from evobiped.episode import EpisodeConfig
    from evobiped.optimizers import GAOptions
    from evobiped.run import Run, RunConfig
    from evobiped.evaluation import make_evaluator
    from evobiped.experiments.reil.study import StudyConfig, open_study, run_dir, run_study

    cfg = StudyConfig(run=RunConfig(episode=EpisodeConfig(seconds=1.0),
                                    optimizer_options={"ga": GAOptions(population=4)}, generations=3),
                      runs=1, conditions=("plain",), recheck_seconds=3.0)
    ref = run_study(tmp_path / "whole", cfg, backend="serial")

    out = open_study(tmp_path / "cut", cfg)
    d = run_dir(out, "plain", 0, cfg)
    run = Run.create(d, cfg.run_config("plain", 0))

    class Stop(Exception):
        pass

    def stop(stats):
        raise Stop

    with make_evaluator(run.config.episode, "serial") as ev, pytest.raises(Stop):
        run.evolve(ev, stop)
    first = (d / "generations" / "gen_0000.json").stat().st_mtime_ns
    (resumed,) = run_study(out, cfg, backend="serial")
    assert (d / "generations" / "gen_0000.json").stat().st_mtime_ns == first  # generation 0 was not redone
    assert {k: v for k, v in resumed.items() if k != "wall_seconds"} == {k: v for k, v in ref[0].items()
                                                                         if k != "wall_seconds"}
    from evobiped.files.rundir import read_history

    whole = read_history(run_dir(tmp_path / "whole", "plain", 0, cfg) / "history.csv")
    cut = read_history(d / "history.csv")
    assert cut.keys() == whole.keys()
    for name in whole:
        if name != "wall_seconds":  # wall seconds differ
            np.testing.assert_array_equal(cut[name], whole[name])


@pytest.mark.parametrize(
    "args, words",
    [
        (["--runs", "0"], "--runs: must be > 0"),
        (["--conditions", "plain,fancy"], "study conditions must be distinct names"),
        (["--conditions", ","], "study conditions must be distinct names"),
        (["--backend", "mpi"], "unknown study backend"),
        (["--backend", "ray", "--address", "127.0.0.1:1"], "cannot reach a Ray cluster"),
    ],
)
def test_bad_input(tmp_path, capsys, args, words):
    out = tmp_path / "s"
    assert cli("study", *args, *TINY, "--out", out) == 2
    err = capsys.readouterr().err
    assert words in err and err.count("\n") == 1
    assert not out.exists()


def test_a_study_needs_a_task_with_criteria_and_the_distance_term(tmp_path, capsys):
    cfg = tmp_path / "steer.toml"
    cfg.write_text('[episode]\ntask = "steer"\n')
    out = tmp_path / "s"
    assert cli("study", "--config", cfg, *TINY, "--out", out) == 2
    err = capsys.readouterr().err
    assert "a study compares fitness criteria by the terms distance; the run's task 'steer' declares criteria []" in err
    assert err.count("\n") == 1 and not out.exists()


def test_a_different_study_in_the_directory_is_refused(tmp_path, capsys):
    out = tmp_path / "s"
    assert cli("study", "--runs", 1, "--conditions", "plain", *TINY, "--out", out) == 0
    before = (out / "study.json").read_text()
    assert cli("study", "--runs", 1, "--conditions", "plain", *TINY, "--first-seed", 5, "--out", out) == 2
    assert "holds a different study" in capsys.readouterr().err
    assert (out / "study.json").read_text() == before


def test_controller_and_optimizer_axes(tmp_path, capsys):
    """One command compares controllers and optimizers: one run directory per cell, each with its settings."""
    out = tmp_path / "axes"
    assert cli("study", "--runs", 1, "--controllers", "ctrnn,simbicon", "--optimizers", "ga,cma", "--conditions",
               "forward", *TINY, "--out", out) == 0
    table = capsys.readouterr().out
    cells = ["ctrnn-ga-forward", "ctrnn-cma-forward", "simbicon-ga-forward", "simbicon-cma-forward"]
    for c in cells:
        assert f"| {c} | 1 |" in table
        cfg = json.loads((out / c / "seed_000" / "config.json").read_text())
        controller, optimizer, _ = c.split("-")
        assert (cfg["episode"]["controller"], cfg["optimizer"],
                cfg["episode"]["task_options"]["fitness"]) == (controller, optimizer, "forward")
    runs = list(csv.DictReader(open(out / "runs.csv")))
    assert [r["condition"] for r in runs] == cells
    for r in runs:  # heading of the displacement, in degrees from the initial facing
        assert -180 <= float(r["heading_deg"]) <= 180 and r["forward_walker"] in ("True", "False")
    assert cli("study", "--runs", 1, "--optimizers", "ga,nope", *TINY, "--out", tmp_path / "bad") == 2
    assert not (tmp_path / "bad").exists()
