"""Walking direction: the heading of the displacement relative to the initial facing."""

import json

import numpy as np
import pytest

from evobiped.cli import main
from evobiped.episode import EpisodeConfig
from evobiped.tasks.walk import direction_words, displacement_heading


def test_heading_against_facing_in_every_quadrant():
    start = np.zeros((5, 2))
    end = np.array([[1, 0], [0, 1], [-1, 0], [0, -1], [1, 1]], float)
    facing = np.tile([1.0, 0.0], (5, 1))
    np.testing.assert_allclose(displacement_heading(start, end, facing), [0, 90, 180, -90, 45])
    # the same displacements seen by a walker that faced +y: straight ahead is +y, its left is -x
    facing_y = np.tile([0.0, 1.0], (5, 1))
    np.testing.assert_allclose(displacement_heading(start, end, facing_y), [-90, 0, 90, 180, -45])


def test_heading_of_a_walker_that_did_not_move_is_nan():
    h = displacement_heading(np.ones((1, 2)), np.ones((1, 2)), np.array([[1.0, 0.0]]))
    assert np.isnan(h[0]) and direction_words(h[0]) == "did not move"
    assert direction_words(-172.0).endswith("backwards") and direction_words(3.0).endswith("forwards")


def test_episode_records_start_facing_and_reports_direction():
    ep = EpisodeConfig(seconds=0.4).build()
    rng = np.random.default_rng(1)
    lay = ep.controller.layout
    g = lay.sample(rng, 3)
    r = ep.run(g)
    assert r.start_facing.shape == (3, 2)
    np.testing.assert_allclose(np.linalg.norm(r.start_facing, axis=1), 1.0)
    w = r.walk(1)
    d = r.end_position[1] - r.start_position[1]
    assert w["distance"] == pytest.approx(np.linalg.norm(d))
    f = r.start_facing[1]
    assert w["heading_deg"] == pytest.approx(np.degrees(np.arctan2(f[0] * d[1] - f[1] * d[0], f @ d)), abs=0.01)


def test_episode_command_prints_the_direction(capsys):
    assert main(["episode", "--seconds", "0.5", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert {"distance", "heading_deg", "displacement"} <= set(out)
    assert main(["episode", "--seconds", "0.5"]) == 0
    assert "from the initial facing" in capsys.readouterr().out


def test_run_summary_states_distance_and_direction_of_the_best(tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["evolve", "--population", "4", "--generations", "1", "--episode-seconds", "0.5", "--backend", "serial",
                 "--out", str(out), "--quiet"]) == 0
    assert "from the initial facing" in capsys.readouterr().out
    walk = json.loads((out / "summary.json").read_text())["best_walk"]
    best = json.loads((out / "best.json").read_text())
    from evobiped.files.genome_file import load_genome

    genome, cfg, _ = load_genome(out / "best.json")
    again = cfg.build().run(genome)
    assert again.fitness[0] == best["fitness"]  # eq. 4 is the distance the summary reports
    assert walk["distance"] == best["fitness"]
