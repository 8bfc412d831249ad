"""A body, an optimizer and a fitness term added from outside the package (tests/toy_extensions.py), each by one
registration line: the CLI, the docs' generated tables, the Gymnasium registry, the task's terms, the weights'
validation and history.csv's columns all follow from the registries."""

from __future__ import annotations

import csv

import pytest

from evobiped import readme
from evobiped.bodies import BODIES
from evobiped.core.errors import ConfigError
from evobiped.optimizers import OPTIMIZERS
from evobiped.tasks import WalkTask
from evobiped.tasks.terms import WALK_TERMS

from .conftest import cli
from .toy_extensions import TOY_TERMS, RandomSearch, ToyBiped

WEIGHTS = {"forward": 10.0, "time_up": 5.0, "lateral": -1.0}


@pytest.fixture
def toys(monkeypatch):
    """The three toys registered, one line each; every registry as it was afterwards."""
    monkeypatch.setitem(BODIES, "toy", ToyBiped)
    monkeypatch.setitem(OPTIMIZERS, "random", RandomSearch)
    WALK_TERMS.append(TOY_TERMS)
    yield
    WALK_TERMS.remove(TOY_TERMS)
    gymnasium = pytest.importorskip("gymnasium")
    gymnasium.registry.pop("evobiped/ToyBiped-v0", None)
    from evobiped.envs import biped

    biped._CLASSES.pop("toy", None)


def test_the_cli_offers_them(toys, capsys):
    assert cli("evolve", "--help") == 0
    text = " ".join(capsys.readouterr().out.split())
    assert "body: reil, taga, toy" in text and "random search (a toy)" in text and "map-elites,random}" in text


def test_the_generated_docs_describe_them(toys):
    parts, tables = readme.generated(), readme.tables()
    assert "### Body `toy`" in parts["bodies"] and tables["body toy"] in parts["bodies"]
    assert "### Optimizer `random` (`[random]`)" in parts["optimizers"] and "| `population` | `6` |" in tables[
        "optimizer random"]
    assert "| `lateral` | m | weights naming lateral |" in parts["terms"]
    assert "`evobiped/ToyBiped-v0` | a toy: Reil's biped renamed | `(26,)`" in parts["environments"]
    assert "`evobiped/ToyBiped-v0`:" in parts["observations"]


def test_gymnasium_makes_its_environment(toys):
    gymnasium = pytest.importorskip("gymnasium")
    from evobiped.envs import register_environments

    assert register_environments() == ["evobiped/ToyBiped-v0"]
    env = gymnasium.make("evobiped/ToyBiped-v0", seconds=0.1)
    obs, _ = env.reset(seed=0)
    assert env.unwrapped.walkers.body.name == "toy" and obs.shape == (26,)
    assert "a toy: Reil's biped renamed" in type(env.unwrapped).__doc__
    env.close()


def test_the_task_reports_and_weighs_the_term(toys):
    task = WalkTask(fitness="weighted", weights=WEIGHTS)
    assert task.term_names[-2:] == ("lateral", "ticks_up")
    with pytest.raises(ConfigError, match=r"names no term of the walk task: sideways \(terms: .*lateral, ticks_up"):
        WalkTask(fitness="weighted", weights={"sideways": 1.0})


def test_without_it_the_term_is_no_term():
    with pytest.raises(ConfigError, match="names no term of the walk task: lateral"):
        WalkTask(fitness="weighted", weights=WEIGHTS)


def test_a_run_of_them_writes_the_term_s_columns(toys, tmp_path):
    config = tmp_path / "toy.toml"
    config.write_text('optimizer = "random"\n[episode]\nbody = "toy"\n[episode.task_options]\nfitness = "weighted"\n'
                      'weights = {forward = 10.0, time_up = 5.0, lateral = -1.0}\n')
    out = tmp_path / "run"
    assert cli("evolve", "--config", config, "--generations", 2, "--population", 4, "--episode-seconds", 0.4,
               "--backend", "serial", "--seed", 1, "--out", out, "--quiet") == 0
    with open(out / "history.csv") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 2 and all(0 < float(r["best_ticks_up"]) <= 20 for r in rows)  # 0.4 s of 0.02 s ticks
    assert all(r["best_lateral"] not in ("", "nan") for r in rows)
