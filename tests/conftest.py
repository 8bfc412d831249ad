from pathlib import Path

import numpy as np
import pytest

from evobiped.cli import main

#: the repository's root: tests name its files by absolute path, since every test runs elsewhere
ROOT = Path(__file__).resolve().parents[1]
#: the shipped walkers
WALKERS = ROOT / "docs" / "walkers"


@pytest.fixture(autouse=True)
def _outside_the_repository(tmp_path_factory, monkeypatch):
    """Every test runs in an empty directory of its own, so that a command's default outputs (``runs/...``)
    land there and never in the repository (tests/test_replay.py checks where they go)."""
    monkeypatch.chdir(tmp_path_factory.mktemp("cwd"))


@pytest.fixture
def rng():
    return np.random.default_rng(12345)


def random_genomes(layout, n, seed=0):
    """Genomes drawn from the layout's initialisation Gaussians, clipped to bounds."""
    r = np.random.default_rng(seed)
    return layout.sample(r, n)


def cli(*args) -> int:
    """Exit status of ``evobiped ARGS`` run in this process (argument errors exit via SystemExit)."""
    try:
        return main([str(a) for a in args])
    except SystemExit as exc:
        return exc.code


class ActionRecorder:
    """An episode listener keeping the action ``(n, n_act)`` every control tick took (``seen``, one array a tick;
    ``row``: only that row's ``(n_act,)``)."""

    def __init__(self, row: int | None = None):
        self.row, self.seen = row, []

    def start(self, episode, sims) -> None:
        pass

    def tick(self, t, sims, ids, neurons, action, task_state) -> None:
        self.seen.append((action if self.row is None else action[self.row]).copy())

    def end(self, result) -> None:
        pass
