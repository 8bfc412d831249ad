"""Damaged generation files: a committed ``generations/gen_NNNN.json`` cut, deleted, swapped for another or edited is
rewritten from the checkpoint where it holds that genome (the run's best generation), and otherwise refused by
``evolve --resume``, ``replay`` and ``select`` with one line naming it; never kept or replayed silently."""

import json
import shutil
from pathlib import Path

import pytest

from .conftest import cli
from .test_faults import one_line_error

RUN = ["--population", "4", "--generations", "4", "--seconds", "0.5", "--backend", "serial", "--seed", "3", "--quiet"]


@pytest.fixture(scope="module")
def finished(tmp_path_factory) -> Path:
    d = tmp_path_factory.mktemp("gens") / "run"
    assert cli("evolve", *RUN, "--out", d) == 0
    return d


@pytest.fixture
def run(finished, tmp_path) -> Path:
    d = tmp_path / "run"
    shutil.copytree(finished, d)
    return d


def best_generation(d: Path) -> int:
    return json.loads((d / "checkpoint.json").read_text())["best"]["generation"]


def other_generation(d: Path) -> int:
    return next(g for g in range(4) if g != best_generation(d))


def gen(d: Path, g: int) -> Path:
    return d / "generations" / f"gen_{g:04d}.json"


def _truncate(d, g):
    p = gen(d, g)
    p.write_bytes(p.read_bytes()[:100])


def _delete(d, g):
    gen(d, g).unlink()


def _swap(d, g):
    other = next(h for h in range(4) if h != g)
    shutil.copyfile(gen(d, other), gen(d, g))


def _edit_gene(d, g):  # the same generation and fitness, another genome
    obj = json.loads(gen(d, g).read_text())
    obj["genome"][0] = obj["genome"][0] / 2 + 0.125
    gen(d, g).write_text(json.dumps(obj, indent=1))


def _edit_fitness(d, g):
    obj = json.loads(gen(d, g).read_text())
    obj["fitness"] += 1.0
    gen(d, g).write_text(json.dumps(obj, indent=1))


DAMAGE = [_truncate, _delete, _swap, _edit_gene, _edit_fitness]


@pytest.mark.parametrize("damage", DAMAGE, ids=lambda f: f.__name__[1:])
@pytest.mark.parametrize("command", ["resume", "replay", "select"])
def test_a_damaged_generation_file_the_checkpoint_cannot_rebuild_is_refused_by_name(run, capsys, damage, command):
    g = other_generation(run)
    damage(run, g)
    before = {p: p.read_bytes() for p in run.rglob("*") if p.is_file() and p.name != ".lock"}
    args = {"resume": ["evolve", "--resume", run], "replay": ["replay", run, "--generation", g],
            "select": ["select", run, "--seconds", "1", "--top", "4"]}[command]
    assert cli(*args) == 2
    one_line_error(capsys.readouterr().err, f"gen_{g:04d}.json")
    assert before == {p: p.read_bytes() for p in run.rglob("*") if p.is_file() and p.name != ".lock"}


@pytest.mark.parametrize("damage", DAMAGE, ids=lambda f: f.__name__[1:])
def test_the_best_generations_file_is_rewritten_from_the_checkpoint(finished, run, capsys, damage):
    g = best_generation(run)
    damage(run, g)
    assert cli("evolve", "--resume", run) == 0
    assert f"repaired: generations/gen_{g:04d}.json rewritten from the checkpoint" in capsys.readouterr().err
    assert gen(run, g).read_bytes() == gen(finished, g).read_bytes()


@pytest.mark.parametrize("command", ["replay", "select"])
def test_replay_and_select_rewrite_the_best_generations_file_and_go_on(finished, run, capsys, command):
    g = best_generation(run)
    _swap(run, g)
    args = {"replay": ["replay", run, "--generation", g],
            "select": ["select", run, "--seconds", "1", "--top", "2"]}[command]
    assert cli(*args) == 0, capsys.readouterr().err
    assert gen(run, g).read_bytes() == gen(finished, g).read_bytes()
