"""Choosing a walker by simulating candidates for longer: the ranking, and ``evobiped select`` on a run."""

import json

import numpy as np

from evobiped.cli import main
from evobiped.analysis.selection import best_candidate

from .conftest import WALKERS


def test_the_long_run_outranks_the_episode_then_heading_then_distance():
    up_long = dict(fell=False, end_time=50.0, distance=20.0, heading_deg=40.0, up_long=True)
    fast = dict(fell=False, end_time=50.0, distance=35.0, heading_deg=0.0, up_long=False)
    assert best_candidate([fast, up_long]) == 1
    straight = dict(up_long, heading_deg=10.0, distance=15.0)
    assert best_candidate([up_long, straight]) == 1  # within 30 degrees beats farther at 40
    assert best_candidate([up_long, straight], heading_limit=45.0) == 0  # both within 45: 20 cos 40 > 15 cos 10
    fell = dict(fell=True, end_time=3.0, distance=1.0, heading_deg=None)
    assert best_candidate([fell, dict(fell, end_time=4.0)]) == 1
    assert best_candidate([up_long, dict(up_long)]) == 0  # a tie keeps the first


def _tuned(tmp_path, walker: str, *, sigma0: float, seconds: float):
    """A two-generation CMA-ES run of the balance controller --from ``walker`` (steps ``sigma0``, episodes of
    ``seconds``)."""
    cfg = tmp_path / "c.toml"
    cfg.write_text(f'optimizer = "cma"\n[cma]\npopulation = 4\nsigma0 = {sigma0}\n[episode]\ncontroller = "simbicon"\n'
                   f'seconds = {seconds}\n[episode.task_options]\nfitness = "forward"\n')
    run = tmp_path / "run"
    assert main(["evolve", "--config", str(cfg), "--from", walker, "--generations", "2", "--backend", "serial",
                 "--out", str(run), "--quiet"]) == 0
    return run


def test_select_keeps_the_start_walker_unless_a_candidate_beats_it(tmp_path, capsys):
    walker = str(WALKERS / "simbicon_seed1.json")
    run = _tuned(tmp_path, walker, sigma0=0.3, seconds=2.0)
    capsys.readouterr()
    assert main(["select", str(run), "--top", "2", "--seconds", "20"]) == 0
    out = capsys.readouterr().out
    assert "start (" in out and "generation" in out and "<- selected" in out
    chosen = json.loads((run / "selected.json").read_text())
    rows = json.loads((run / "selected_candidates.json").read_text())["candidates"]
    assert len(rows) == 3 and rows[0]["candidate"].startswith("start")
    # the selected walker is the best candidate by the ranking of evobiped.analysis.selection
    assert chosen["selected_from"] == rows[best_candidate(rows)]["candidate"]
    start = json.loads(open(walker).read())["genome"]
    if chosen["selected_from"].startswith("start"):
        assert np.array_equal(chosen["genome"], start)


def test_select_of_a_directory_that_is_not_a_run_is_one_line(tmp_path, capsys):
    assert main(["select", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "not a run directory" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "selected.json").exists()


def test_select_keeps_a_start_walker_that_no_candidate_beats(tmp_path, capsys):
    """A forward walker tuned with steps so wild that every sample falls: the 200-s choice keeps the start walker itself
    (the "unless beaten" branch), which stays up while each generation best falls."""
    walker = str(WALKERS / "simbicon_cma_seed5.json")
    run = _tuned(tmp_path, walker, sigma0=0.9, seconds=4.0)
    assert main(["select", str(run), "--top", "2", "--seconds", "10"]) == 0
    rows = json.loads((run / "selected_candidates.json").read_text())["candidates"]
    assert rows[0]["candidate"].startswith("start") and rows[0].get("up_long") is True
    assert all(r["fell"] for r in rows[1:])  # the wild samples fall within their 4 s
    chosen = json.loads((run / "selected.json").read_text())
    assert chosen["selected_from"].startswith("start")
    assert chosen["genome"] == json.loads(open(walker).read())["genome"]
