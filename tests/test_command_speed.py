"""The speed command through the velocity sense's frame (``evobiped genome command-start --speed-gain``), and the
speed battery of ``evobiped gait --battery``: a commanded speed changes the walk, the battery's numbers are the
walk's, and bad input is one line."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from evobiped.analysis.commanded import follow_commands
from evobiped.analysis.gait_report import gait_report
from evobiped.analysis.speed_battery import (_windows, calibrate_speed, gait_at_speeds, random_schedules, speed_battery,
                                             stop_and_go)
from evobiped.core.errors import UserError
from evobiped.core.options import given
from evobiped.episode.remap import input_widths
from evobiped.files.genome_edit import command_genome
from evobiped.files.genome_file import load_genome, save_genome

from .conftest import WALKERS, cli

ROBUST = WALKERS / "ctrnn_walk_robust_seed0.json"


@pytest.fixture(scope="module")
def framed(tmp_path_factory):
    """The robust walking network with the speed command moving its velocity sense's frame (k 0.77, at 0.59 m/s)."""
    path = tmp_path_factory.mktemp("framed") / "framed.json"
    genome, cfg = command_genome(ROBUST, 0.77, 0.59)
    save_genome(path, genome, cfg)
    return path


SHIPPED = WALKERS / "ctrnn_command_robust_seed0.json"


@pytest.fixture(scope="module")
def stopping():
    """The shipped commanded walker: ``framed`` with a stop (at a zero command the frame of a 0.09 m/s command)."""
    return SHIPPED


def test_the_shipped_commanded_walker_is_the_documented_construction():
    built, cfg = command_genome(ROBUST, 0.77, 0.59, 0.09)
    shipped, shipped_cfg, meta = load_genome(SHIPPED)
    assert np.array_equal(built, shipped) and meta["source"].endswith("ctrnn_walk_robust_seed0.json")
    assert given(cfg.controller_options)["input_norm"] == given(shipped_cfg.controller_options)["input_norm"]


def test_at_the_reference_speed_the_framed_walker_is_the_walker(framed):
    g, cfg, _ = load_genome(framed)
    old_g, old, _ = load_genome(ROBUST)
    at_ref = dataclasses.replace(cfg, task_options={**given(cfg.task_options), "schedule": "constant", "speed": 0.59,
                                                    "turning": 0.0})
    new, was = gait_report(at_ref, g, seconds=8.0), gait_report(old, old_g, seconds=8.0)
    assert new["forward"] == pytest.approx(was["forward"], abs=1e-9)
    assert new["displacement"] == pytest.approx(was["displacement"], abs=1e-9)


def test_command_speed_rows_are_minus_the_forward_velocity_rows(framed):
    g, cfg, _ = load_genome(framed)
    c = cfg.build().controller
    at, where = 0, {}
    for n, w in zip(c.input_names, input_widths(cfg)):
        where[n], at = at, at + w
    s = c.layout.slices()
    for block in ("input_weights", "direct_weights"):
        rows = g[s[block]].reshape(c.n_inputs, -1)
        assert np.array_equal(rows[where["command_speed"]], -rows[where["com_velocity"]])
        assert not rows[where["command_turning"]].any()


def test_a_faster_command_walks_faster(framed):
    g, cfg, _ = load_genome(framed)
    r = follow_commands(cfg, g, [0.0, 10.0], [0.3, 0.7], [0.0, 0.0], 20.0)
    slow, fast = (s["walked_speed"] for s in r["stretches"])
    assert not r["fell"]
    assert slow == pytest.approx(0.3, rel=0.15) and fast == pytest.approx(0.7, rel=0.15)


def test_the_speed_battery_scores_the_walk_it_follows(framed):
    g, cfg, _ = load_genome(framed)
    b = speed_battery(cfg, g, n=2, stretches=2, stretch=6.0, low=0.3, high=0.7, seed=4)
    speeds = random_schedules(2, 2, 0.3, 0.7, 4)
    assert np.array_equal(speeds, random_schedules(2, 2, 0.3, 0.7, 4)) and ((speeds >= 0.3) & (speeds <= 0.7)).all()
    for row, schedule in zip(b["schedules"], speeds):
        again = follow_commands(cfg, g, [0.0, 6.0], list(schedule), [0.0, 0.0], 12.0)
        for s, t in zip(row["stretches"], again["stretches"]):
            assert s["walked"] == t["walked_speed"]
            assert s["error_pct"] == pytest.approx(100 * abs(t["walked_speed"] - s["commanded"]) / s["commanded"])
            assert len(s["windows_pct"]) == 3  # measured from 3 s into the 6 s stretch: three whole 1 s windows
            assert s["within"] == (s["error_pct"] <= 10.0)
    m = b["summary"]
    assert m["schedules"] == 2 and m["stretches"] == 4 and m["within"] == sum(s["within"] for r in b["schedules"]
                                                                              for s in r["stretches"])


def test_window_errors_match_a_hand_calculation():
    trace = {"time": [0.0, 0.5, 1.0, 1.5, 2.0, 2.5], "walked_speed": [1.0, 1.0, 0.5, 1.5, 2.0, 2.0]}
    assert _windows(trace, 0.0, 3.0, 1.0, 1.0) == pytest.approx([0.0, 0.0, 100.0])
    assert _windows(trace, 0.0, 3.0, 1.0, 2.0) == pytest.approx([0.0])


def test_bad_speed_gains_are_refused():
    with pytest.raises(UserError, match="--speed-gain"):
        command_genome(ROBUST, -1.0, 0.5)
    with pytest.raises(UserError, match="--reference-speed"):
        command_genome(ROBUST, 0.7, None)


@pytest.mark.parametrize("flags, words", [
    (["--battery", "0"], "from 1 to 10,000"),
    (["--battery", "2", "--range", "0.5"], "LOW,HIGH"),
    (["--battery", "2", "--range", "0.6,0.3"], "LOW,HIGH"),
    (["--battery", "2", "--speed", "0.4"], "without --speed"),
    (["--battery", "2", "--hold", "2"], "longer than the settling time"),
])
def test_bad_battery_input_is_one_line_and_writes_nothing(framed, tmp_path, capsys, flags, words):
    out = tmp_path / "out"
    assert cli("gait", framed, "--out", out, *flags) == 2
    err = capsys.readouterr().err.strip()
    assert words in err and len(err.splitlines()) == 1
    assert not out.exists()


def test_the_battery_command_writes_its_json(framed, tmp_path, capsys):
    out = tmp_path / "out"
    assert cli("gait", framed, "--battery", "1", "--stretches", "2", "--hold", "5", "--range", "0.4,0.6", "--json",
               "--out", out) == 0
    printed = json.loads(capsys.readouterr().out)
    stored = json.loads((out / "framed_speed_battery.json").read_text())
    assert printed["summary"] == stored["summary"] and stored["summary"]["schedules"] == 1
    assert [g["commanded"] for g in stored["gait"]] == [0.4, 0.5, 0.6]


def test_a_stop_marks_time_and_it_walks_off_again(stopping):
    g, cfg, _ = load_genome(stopping)
    (r,) = stop_and_go(cfg, g, [0.5], walk=8.0, stop=12.0)
    assert not r["fell"] and r["time_to_stop"] is not None and r["time_to_stop"] <= 6.0
    assert abs(r["stop_speed"]) <= 0.05 and r["double_support"] < 0.5  # on the spot, stepping: it does not stand
    assert r["walk_off"] == pytest.approx(0.5, rel=0.10)


def test_a_commanded_walker_walks_to_sources_through_its_ears(stopping, capsys):
    assert cli("episode", "--genome", stopping, "--source", "4", "1.5", "--source", "-3.5", "0.05", "--seconds", "40",
               "--json") == 0
    out = json.loads(capsys.readouterr().out)
    for s in out["sources"]:  # one ahead, one straight behind (heard as if in front until its fading tells)
        assert not s["fell"] and s["final_distance"] <= 0.5 and s["arrival_time"] is not None and s["stood"]
    assert out["sources"][1]["arrival_time"] <= 22.0  # 17 s; turning round only where noise bends its path: 28 s


def test_calibration_makes_a_walker_told_half_as_hard_walk_as_told(stopping, tmp_path):
    g, cfg, _ = load_genome(stopping)
    norm = dict(given(cfg.controller_options)["input_norm"])
    at = dict(zip(cfg.parts()[1].input_names, np.cumsum([0] + list(input_widths(cfg)))[:-1]))
    i, j = at["command_speed"], at["command_stop"]
    std = list(norm["std"])
    std[i] *= 2  # every command now moves its frame half as far: it walks nearer its reference speed
    weak = dataclasses.replace(cfg, controller_options={**given(cfg.controller_options),
                                                        "input_norm": {**norm, "std": std}})
    off = follow_commands(weak, g, [0.0], [0.3], [0.0], 15.0)["stretches"][0]["walked_speed"]
    assert off > 0.4  # told 0.3 m/s, it walks well above
    fixed, fit = calibrate_speed(weak, g, [0.3, 0.45, 0.6, 0.75])
    assert 0.3 < fit["slope"] < 0.7
    on = follow_commands(fixed, g, [0.0, 15.0], [0.4, 0.7], [0.0, 0.0], 30.0)["stretches"]
    assert [s["walked_speed"] for s in on] == pytest.approx([0.4, 0.7], rel=0.10)  # within the speeds it was fitted on
    m0, s0 = weak.controller_options.input_norm["mean"], weak.controller_options.input_norm["std"]
    m1, s1 = fixed.controller_options.input_norm["mean"], fixed.controller_options.input_norm["std"]
    assert -m0[i] / s0[i] + 1 / s0[j] == pytest.approx(-m1[i] / s1[i] + 1 / s1[j])  # the stop's frame kept


def test_calibrating_a_walker_without_commands_is_one_line(tmp_path, capsys):
    out = tmp_path / "x.json"
    assert cli("genome", "command-calibrate", ROBUST, out) == 2
    err = capsys.readouterr().err.strip()
    assert "not a commanded walker" in err and "\n" not in err and not out.exists()
    assert cli("genome", "command-calibrate", ROBUST, out, "--speeds", "0.4") == 2


def test_sources_for_a_walker_that_takes_no_commands_are_one_line(tmp_path, capsys):
    assert cli("episode", "--genome", WALKERS / "simbicon_cma_seed5.json", "--source", "3", "1") == 2
    err = capsys.readouterr().err.strip()
    assert "--source applies to the steer task" in err and "commanded walker" in err and "\n" not in err


def test_a_steering_rule_out_of_order_is_one_line(stopping, tmp_path):
    import subprocess
    import sys

    cfg = tmp_path / "bad.toml"
    cfg.write_text('[episode]\ntask = "steer-command"\n[episode.task_options]\nreach = 3.0\nslow_from = 2.0\n')
    r = subprocess.run([sys.executable, "-m", "evobiped", "evolve", "--config", cfg, "--generations", "1", "--out",
                        tmp_path / "run"], capture_output=True, text=True, cwd=tmp_path)
    assert r.returncode == 2 and "reach < slow_from" in r.stderr and len(r.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "run").exists()


def test_the_calibrated_quick_start_walker_walks_as_told_by_every_criterion():
    g, cfg, meta = load_genome(WALKERS / "ctrnn_command_seed1.json")
    assert meta["source"].endswith("ctrnn_walk_preset_seed1.json") and len(meta["calibrations"]) == 2
    r = follow_commands(cfg, g, [0.0, 12.0], [0.4, 0.7], [0.0, 0.0], 24.0)
    assert not r["fell"] and [s["walked_speed"] for s in r["stretches"]] == pytest.approx([0.4, 0.7], rel=0.10)
    (gait,) = gait_at_speeds(cfg, g, [0.5], seconds=20.0)
    assert gait["walks"], gait["failed"]  # duty >= 0.5 each foot, no flight, slip <= 5 %, as the docs' table says


def test_the_replay_recording_logs_commanded_against_walked(tmp_path):
    """The recording's commands/speed holds the commands the walker was told and the speed it walked (1 s mean): on
    its tour, 0.5 m/s then 0.8 m/s from 5 s, the walked mean late in each stretch is near its command."""
    import rerun as rr

    out = tmp_path / "c.rrd"
    assert cli("replay", SHIPPED, "--seconds", "10", "--out", out) == 0
    series = {}
    for c in rr.chunk.RrdReader(out).stream():
        if c.entity_path in ("/commands/speed", "/commands/turning") and not c.is_static:
            rb = c.to_record_batch()
            t = np.array([x.total_seconds() if hasattr(x, "total_seconds") else x
                          for x in rb.column("sim_time").to_pylist()])
            series[c.entity_path] = (t, np.array(rb.column("Scalars:scalars").to_pylist(), float))
    t, v = series["/commands/speed"]
    told, walked = v[:, 0], v[:, 1]  # a row at t holds the command from t on (the last, at 10 s, the next stretch's)
    assert (told[(t > 5.01) & (t < 9.99)] == 0.8).all() and (told[t < 4.99] == 0.5).all()
    assert np.mean(walked[(t > 3.5) & (t < 5)]) == pytest.approx(0.5, rel=0.15)
    assert np.mean(walked[(t > 9) & (t < 10)]) == pytest.approx(0.8, rel=0.15)
    _, w = series["/commands/turning"]
    assert (w[t < 9.99, 0] == 0).all() and w[-1, 0] == pytest.approx(0.35 * 180 / np.pi)  # the turn from 10 s
