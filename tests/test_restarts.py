"""The lost-run rule ([restart]): a phase that takes its patience is lost; the run says so and starts over (the
optimizer from its start point, the curriculum from its first phase), stops, or goes on; every restart's episodes
count in the budget; a resumed run restarts where the uninterrupted one did, bit for bit; bad rules are one line."""

import json

import numpy as np
import pytest

from evobiped.core.errors import ConfigError
from evobiped.evaluation import make_evaluator
from evobiped.run import Run, RunConfig
from evobiped.run.stopping import Attempts, RestartOptions

from .conftest import cli
from .test_evolve import fitness_history
from .test_stopping import _evolve


def _config(optimizer="ga", generations=10, **restart) -> RunConfig:
    tables = {"ga": {"population": 8}, "es": {"pairs": 3, "sigma": 0.05}}
    return RunConfig.from_dict({"episode": {"seconds": 1.0}, optimizer: tables[optimizer], "optimizer": optimizer,
                                "generations": generations, "seed": 4, "backend": "serial", "restart": restart})


def test_a_phase_is_lost_when_it_takes_its_patience_and_a_restart_begins_its_count_again():
    rule, a = RestartOptions(patience=[2, 3], max_restarts=1), Attempts()
    assert a.check(rule, 0, 0, moved_on=False) is None
    assert a.check(rule, 1, 0, moved_on=True) is None and a.phase_since == 2  # phase 0 took 2, but moved on
    assert a.check(rule, 2, 1, False) is None and a.check(rule, 3, 1, False) is None
    assert a.check(rule, 4, 1, False) == "restart" and (a.attempt, a.phase_since) == (1, 5)
    assert a.check(rule, 5, 0, False) is None
    assert a.check(rule, 6, 0, False) == "stop" and a.stopped  # the one restart spent
    assert a.lost == [{"generation": 4, "phase": 1, "action": "restart", "why": "patience"},
                      {"generation": 6, "phase": 0, "action": "stop", "why": "patience"}]
    assert Attempts.from_dict(a.to_dict()) == a
    falls, b = RestartOptions(patience=[50], fallen_for=[3]), Attempts()
    assert [b.check(falls, g, 0, False, fell) for g, fell in enumerate([True, True, False, True, True, True])] == [
        None, None, None, None, None, "restart"]  # three generations running, not three in all
    assert b.lost == [{"generation": 5, "phase": 0, "action": "restart", "why": "fallen"}] and b.fallen == 0


def test_a_lost_ga_run_starts_over_every_patience_generations_and_resumes_bit_for_bit(tmp_path):
    config = _config(patience=[3])
    whole = _evolve(tmp_path / "whole", config)
    summary = json.loads((whole.dir / "summary.json").read_text())
    assert summary["generations"] == 10 and [e["generation"] for e in summary["lost"]] == [2, 5, 8]
    assert {e["action"] for e in summary["lost"]} == {"restart"} and whole.context.attempts.attempt == 3
    # after generation 8 the GA began again: generation 9 is a first population drawn from generation 9's stream
    fresh = whole.config.episode.layout().sample(whole.optimizer.rng(9), 8)
    best9 = json.loads((whole.dir / "generations" / "gen_0009.json").read_text())["genome"]
    assert np.isclose(fresh, best9, rtol=0, atol=1e-12).all(axis=1).any()
    ck = json.loads((whole.dir / "checkpoint.json").read_text())
    assert {k: v for k, v in ck["restarts"].items() if k != "fallen"} == {"attempt": 3, "phase_since": 9,
                                                                          "lost": summary["lost"]}
    cut = _evolve(tmp_path / "cut", config, stop_at=6)  # after the second restart
    resumed = Run.resume(cut.dir)
    with make_evaluator(config.episode, "serial") as ev:
        resumed.evolve(ev)
    assert fitness_history(cut.dir) == fitness_history(whole.dir)
    again = json.loads((cut.dir / "checkpoint.json").read_text())
    assert again["optimizer"] == ck["optimizer"] and again["restarts"] == ck["restarts"] and again["best"] == ck["best"]
    plain = _evolve(tmp_path / "plain", _config())
    ours = [row[: len(fitness_history(plain.dir)[0])] for row in fitness_history(whole.dir)]  # less the rule's columns
    # the same until lost
    assert fitness_history(plain.dir)[:3] == ours[:3] and fitness_history(plain.dir)[3] != ours[3]


def test_es_starts_over_at_its_start_point_with_adams_moments_and_sigma_from_nothing(tmp_path):
    config = _config("es", generations=5, patience=[2])
    run = _evolve(tmp_path / "es", config)
    opt = run.optimizer
    assert [e["generation"] for e in run.context.attempts.lost] == [1, 3] and opt.started == 4
    # one generation after its last restart theta has taken one step from the start point, as at generation 1
    first = _evolve(tmp_path / "es1", _config("es", generations=1))
    assert np.linalg.norm(opt.theta - opt.start_point()) == pytest.approx(
        np.linalg.norm(first.optimizer.theta - first.optimizer.start_point()), rel=0.5)
    table = json.loads((run.dir / "checkpoint.json").read_text())["optimizer"]
    assert table["started"] == 4


def test_a_lost_run_can_stop_or_warn_and_says_so(tmp_path, capsys):
    stopped = _evolve(tmp_path / "stop", _config(patience=[4], action="stop"))
    summary = json.loads((stopped.dir / "summary.json").read_text())
    assert summary["generations"] == 4 and summary["lost"] == [{"generation": 3, "phase": 0, "action": "stop",
                                                                "why": "patience"}]
    warned = _evolve(tmp_path / "warn", _config(patience=[4], action="warn"))
    said = json.loads((warned.dir / "summary.json").read_text())
    assert said["generations"] == 10 and [e["generation"] for e in said["lost"]] == [3]  # said once, then on
    plain = _evolve(tmp_path / "plain", _config())
    # warning changes nothing of the evolution: every fitness column as without the rule
    assert [row[: len(fitness_history(plain.dir)[0])] for row in fitness_history(warned.dir)] == fitness_history(
        plain.dir)
    cfg = tmp_path / "lost.toml"
    cfg.write_text('optimizer = "ga"\ngenerations = 5\nseed = 4\n[ga]\npopulation = 8\n[episode]\nseconds = 1.0\n'
                   '[restart]\npatience = [2]\nmax_restarts = 1\n')
    capsys.readouterr()
    assert cli("evolve", "--config", cfg, "--out", tmp_path / "cli", "--backend", "serial") == 0
    out = capsys.readouterr()
    lost = [line for line in out.err.splitlines() if line.startswith("evolve: lost")]
    assert lost == ["evolve: lost: phase 1 of 1 did not end within its 2 generations (restart.patience); starting over "
                    "at generation 2 (restart 1 of at most 1)",
                    "evolve: lost: phase 1 of 1 did not end within its 2 generations (restart.patience); stopping "
                    "(all 1 restarts spent)"]
    assert "stopped after generation 3: lost" in out.out


@pytest.mark.parametrize("table, words", [
    ({"restart": {"patience": [0]}}, "restart.patience: must be a list of whole numbers"),
    ({"restart": {"patience": [5, 5]}}, "restart.patience: one entry per curriculum phase (1), got 2"),
    ({"restart": {"patience": [5], "action": "pray"}}, "restart.action"),
    ({"restart": {"patience": [5]}, "optimizer": "cma"}, "cannot start over"),
    ({"budget": 7}, "budget: 7 episodes is less than one generation's 8"),
    ({"restart": {"patience": [5], "fallen_for": [3, 3]}}, "restart.fallen_for: one entry per entry of "
                                                           "restart.patience (1), got 2"),
])
def test_bad_restart_rules_and_budgets_are_one_line_and_write_nothing(tmp_path, capsys, table, words):
    with pytest.raises(ConfigError, match=words.replace("(", r"\(").replace(")", r"\)")):
        RunConfig.from_dict({"ga": {"population": 8}, **table})
    lines = [f"{k} = {json.dumps(v)}" for k, v in table.items() if not isinstance(v, dict)]
    lines += ["[ga]", "population = 8"]
    for k, v in table.items():
        if isinstance(v, dict):
            lines += [f"[{k}]"] + [f"{a} = {json.dumps(b)}" for a, b in v.items()]
    bad = tmp_path / "bad.toml"
    bad.write_text("\n".join(lines) + "\n")
    assert cli("evolve", "--config", bad, "--out", tmp_path / "r", "--quiet") == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and words.split(":")[0] in err[0] and not (tmp_path / "r").exists()
