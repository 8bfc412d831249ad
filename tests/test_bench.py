"""``evobiped bench``: the measurements integrate the same physics; medians and ratios as documented.

Speed itself is not asserted (timings belong to the benchmark, not the tests).
"""

import json
from pathlib import Path

import numpy as np
import pytest

from evobiped.analysis.bench import bench
from evobiped.cli import main
from evobiped.episode import EpisodeConfig

STEERER = str(Path(__file__).parents[1] / "docs" / "walkers" / "steer_ctrnn_es_seed0.json")


def test_raw_replay_on_threads_reproduces_the_closed_loop_episodes_exactly():
    """(a) replays (b)'s controls open-loop with mujoco.rollout on 2 threads: same end positions to the bit."""
    r = bench(EpisodeConfig(seconds=2.0), population=3, workers=2, repeats=3)
    assert r["replay_end_position_gap_m"] == 0.0
    names = {"raw 1", "raw 2", "eval", "pool 1", "pool 2", "threads 2"}
    assert {k: len(v) for k, v in r["wall_seconds"].items()} == dict.fromkeys(names, 3)
    m = r["median_sim_s_per_s"]
    for k, v in r["wall_seconds"].items():  # the reported rate is the median repeat's
        assert m[k] == pytest.approx(6.0 / np.median(v)) and sorted(v)[1] == pytest.approx(6.0 / m[k])
    assert r["simulated_seconds"] == pytest.approx(6.0)
    assert r["efficiency_one_core"] == pytest.approx(m["eval"] / m["raw 1"])
    assert r["efficiency_pool"] == pytest.approx(m["pool 2"] / m["raw 2"])
    assert r["efficiency_threads"] == pytest.approx(m["threads 2"] / m["raw 2"])
    assert r["scaling_raw"] == pytest.approx(m["raw 2"] / m["raw 1"]) and r["scaling_pool"] == pytest.approx(m[
        "pool 2"] / m["pool 1"])


def test_cli_json(capsys):
    assert main(["bench", "--population", "1", "--seconds", "0.5", "--workers", "1", "--repeats", "1", "--json"]) == 0
    r = json.loads(capsys.readouterr().out)
    assert r["population"] == 1 and r["repeats"] == 1 and r["simulated_seconds"] == pytest.approx(0.5)
    # one repeat ran
    assert {k: len(v) for k, v in r["wall_seconds"].items()} == dict.fromkeys(r["median_sim_s_per_s"], 1)
    m = r["median_sim_s_per_s"]
    assert set(m) == {"raw 1", "eval", "pool 1", "threads 1"} and all(np.isfinite(v) and v > 0 for v in m.values())
    # one worker: the efficiencies are each evaluator's rate over the one raw rate
    assert r["efficiency_one_core"] == pytest.approx(m["eval"] / m["raw 1"]) and r["efficiency_pool"] == pytest.approx(
        m["pool 1"] / m["raw 1"])


def test_cli_quick_sizes_and_overrides(capsys):
    """--quick: 16 walkers, 5 repeats, --seconds overriding its 4 s; each measurement ran 5 times (not only
    reported)."""
    assert main(["bench", "--quick", "--seconds", "0.2", "--workers", "1", "--json"]) == 0
    r = json.loads(capsys.readouterr().out)
    assert (r["population"], r["episode_seconds"], r["repeats"]) == (16, 0.2, 5)
    assert r["simulated_seconds"] == pytest.approx(16 * 0.2)
    assert {k: len(v) for k, v in r["wall_seconds"].items()} == dict.fromkeys(r["median_sim_s_per_s"], 5)
    m = r["median_sim_s_per_s"]
    assert all(m[k] == pytest.approx(16 * 0.2 / np.median(v)) for k, v in r["wall_seconds"].items())


@pytest.mark.parametrize("args, words", [(["--population", "0"], "must be > 0"), (["--repeats", "0"], "must be > 0"),
                                         (["--body", "tripod"], "unknown body 'tripod'")])
def test_cli_bad_arguments(capsys, args, words):
    try:
        rc = main(["bench", *args])
    except SystemExit as exc:
        rc = exc.code
    assert rc == 2 and words in capsys.readouterr().err


def test_presentations_measurement_counts_every_presentation(capsys):
    """(e) simulates R presentations of each walker: R times the simulated seconds of (b)."""
    assert main(["bench", "--population", "2", "--seconds", "0.5", "--workers", "1", "--repeats", "1",
                 "--presentations", "3", "--json"]) == 0
    r = json.loads(capsys.readouterr().out)
    assert r["simulated_seconds_each"]["eval x3"] == pytest.approx(3 * r["simulated_seconds_each"][
        "eval"]) == pytest.approx(3.0)
    m = r["median_sim_s_per_s"]
    assert r["presentation_cost"] == pytest.approx(m["eval"] / m["eval x3"])
    assert m["eval x3"] == pytest.approx(3.0 / r["wall_seconds"]["eval x3"][0])
    # (a e) replays every perturbed row open-loop (its start, controls and push forces): the same physics to the bit
    assert r["replay_presentations_gap_m"] == 0.0
    assert r["efficiency_presentations"] == pytest.approx(m["eval x3"] / m["raw x3"])


def test_a_preset_that_tunes_a_genome_is_timed_from_it_every_presentation_replayed(capsys):
    """steer-walk presents each walker its 4 sources: 4 rows a walker, each replayed open-loop to the bit."""
    args = ["bench", "--preset", "steer-walk", "--from", STEERER, "--population",
            "2", "--seconds", "0.5", "--workers", "1", "--repeats", "1", "--json"]
    assert main(args) == 0
    r = json.loads(capsys.readouterr().out)
    assert r["rows"] == 8 and r["simulated_seconds"] == pytest.approx(8 * 0.5)
    assert r["replay_end_position_gap_m"] == 0.0 and r["replay_blow_ups"] == 0


@pytest.mark.parametrize("args, words", [(["--preset", "steer-walk", "--from", "no/such.json"], "no such run"),
                                         (["--from", STEERER], "--from names")])
def test_a_bad_genome_to_time_from_is_one_line(capsys, args, words):
    assert main(["bench", *args, "--quick"]) == 2
    err = capsys.readouterr().err
    assert words in err and len(err.strip().splitlines()) == 1
