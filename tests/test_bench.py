"""``evobiped bench``: the three measurements integrate the same physics; the CLI prints ratios.

Speed itself is not asserted (timings belong to the benchmark, not the tests).
"""

import json

import pytest

from evobiped.bench import bench
from evobiped.cli import main
from evobiped.episode import EpisodeConfig


def test_raw_replay_reproduces_the_closed_loop_episodes_exactly():
    """(a) replays (b)'s controls open-loop with mujoco.rollout: same end positions to the bit."""
    r = bench(EpisodeConfig(seconds=2.0), population=4, workers=2, repeats=2)
    assert r["replay_end_position_gap_m"] == 0.0
    assert {k: len(v) for k, v in r["wall_seconds"].items()} == {"raw": 2, "eval": 2, "1": 2, "2": 2}
    reported = {"raw": r["raw_sim_s_per_s"], "eval": r["eval_sim_s_per_s"], **r["pool_sim_s_per_s"]}
    for k, v in r["wall_seconds"].items():  # the reported rate is the fastest repeat's
        assert reported[k] == pytest.approx(8.0 / min(v)) and r["slowest_repeat_sim_s_per_s"][k] == pytest.approx(8.0 / max(v))
    assert r["simulated_seconds"] == pytest.approx(8.0)
    assert set(r["pool_sim_s_per_s"]) == {"1", "2"}
    for v in (r["raw_sim_s_per_s"], r["eval_sim_s_per_s"], *r["pool_sim_s_per_s"].values()):
        assert v > 0
    assert r["ratio_eval_over_raw"] == pytest.approx(r["eval_sim_s_per_s"] / r["raw_sim_s_per_s"])


def test_cli_json(capsys):
    assert main(["bench", "--population", "1", "--seconds", "0.5", "--workers", "1", "--repeats", "1", "--json"]) == 0
    r = json.loads(capsys.readouterr().out)
    assert r["speedup_all_over_1"] == 1.0 and r["population"] == 1 and r["repeats"] == 1


@pytest.mark.parametrize("args, words", [(["--population", "0"], "must be > 0"), (["--repeats", "0"], "must be > 0"), (["--body", "tripod"], "unknown body 'tripod'")])
def test_cli_bad_arguments(capsys, args, words):
    try:
        rc = main(["bench", *args])
    except SystemExit as exc:
        rc = exc.code
    assert rc == 2 and words in capsys.readouterr().err
