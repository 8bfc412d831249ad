"""Adding a controller is one new file (tests/sine_controller.py) and one registration line: registered, it
evolves on every body through the command line and its run directory replays."""

import csv

import numpy as np
import pytest

from evobiped.bodies import BODIES
from evobiped.controllers import CONTROLLERS
from evobiped.files.genome_file import load_genome

from .conftest import cli
from .sine_controller import Sine


@pytest.mark.parametrize("body", sorted(BODIES))
def test_a_registered_sine_controller_evolves_on_every_body_and_replays(body, tmp_path, monkeypatch):
    monkeypatch.setitem(CONTROLLERS, Sine.name, Sine)  # the one registration line
    out = tmp_path / "run"
    assert cli("evolve", "--body", body, "--controller", "sine", "--generations", 2, "--population", 4,
               "--episode-seconds", 0.4, "--backend", "serial", "--seed", 1, "--out", out, "--quiet") == 0
    with open(out / "history.csv") as f:
        rows = list(csv.DictReader(f))
    assert [int(r["generation"]) for r in rows] == [0, 1]
    best = [float(r["best"]) for r in rows]
    assert np.isfinite(best).all() and best[1] >= best[0] > 0  # it moved the walker; the GA keeps its best
    genome, cfg, meta = load_genome(out / "best.json")
    n_act = len(BODIES[body].actuators)
    assert cfg.controller == "sine" and len(genome) == 3 * n_act == cfg.layout().size
    assert meta["fitness"] == max(best)
    assert cfg.build().run(genome).fitness[0] == meta["fitness"]  # the run directory replays to the same fitness
