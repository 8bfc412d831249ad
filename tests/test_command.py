"""Commanded walkers: the command task's senses and their mirror, its schedules (drawn per generation, piecewise),
its tracking terms, ``evobiped gait`` on a commanded genome, the steering rule, and the bad inputs."""

from __future__ import annotations

import json
import math
import subprocess
import sys

import numpy as np
import pytest

from evobiped.cli import main
from evobiped.core.errors import ConfigError
from evobiped.episode import EpisodeConfig
from evobiped.tasks.command_schedule import clip_command
from evobiped.tasks.steer_command import steering_command

#: a controller that stands still (the linear controller with every gene zero) reading the commands
STANDS = dict(body="reil", controller="linear", task="command",
              controller_options={"inputs": ["command_speed", "command_turning", "joint_angles"]})


def standing(seconds=1.0, **task_options):
    return EpisodeConfig(seconds=seconds, task_options=task_options, **STANDS).build()


def commanded_genome(path, **episode):
    """A genome file of the walker-command preset's layout (every gene at its range's centre: it need not walk)."""
    from evobiped.core.fileio import read_toml
    from evobiped.run.run_config import RunConfig
    from evobiped.files.genome_file import save_genome
    from evobiped.files.presets import path as preset_path, split_declarations

    settings, _ = split_declarations("walker-command", read_toml(preset_path("walker-command")))
    config = RunConfig.from_dict(settings, where="preset").episode
    save_genome(path, config.layout().centre, config)
    return config


def test_the_stance_frame_mirror_keeps_the_speed_and_negates_the_turning():
    cfg = EpisodeConfig(body="reil", controller="ctrnn", task="command", seconds=1.0,
                        controller_options={"frame": "stance",
                                            "inputs": ["command_speed", "command_turning", "joint_angles"]})
    ep = cfg.build()
    frame = ep.controller.frame
    x = np.tile(np.r_[0.5, 0.2, np.arange(6.0)], (2, 1))
    seen = frame.inputs(x, np.array([False, True]))
    assert seen[0, :2].tolist() == [0.5, 0.2]
    assert seen[1, :2].tolist() == [0.5, -0.2]  # the mirrored walker is told to turn right
    assert np.array_equal(frame.inputs(seen, np.array([False, True])), x)


def test_drawn_commands_are_the_generations_for_every_genome_and_change_mid_episode():
    ep = standing(seconds=12.0, schedule="drawn", stretch=2.0, p_stop=0.3)
    draw = ep.task.draw_sources((7, 3))
    again = ep.task.draw_sources((7, 3)).steps(12.0)
    s = draw.steps(12.0)
    assert np.array_equal(s.speed, again.speed) and np.array_equal(s.turning, again.turning)
    # changes mid-episode
    assert len(s.times) == 6 and len(set(s.speed.tolist())) > 1 and len(set(s.turning.tolist())) > 1
    other = ep.task.draw_sources((7, 4)).steps(12.0)
    assert not np.array_equal(other.speed, s.speed)  # another generation, other commands
    assert ((s.speed == 0) | ((s.speed >= 0.2) & (s.speed <= 0.8))).all() and (np.abs(s.turning) <= 0.35).all()
    state = ep.start(np.zeros((5, ep.controller.layout.size)), trials=ep.trials_for((7, 3)))
    for k in range(3):  # every genome of the generation is told the same: the draw's stretch of the time
        senses = ep.task.sensors(ep.body, state.sims, state.task)
        i = int(np.floor(2.5 * k / 2.0 + 1e-9))
        assert (senses["command_speed"][:,
                                        0] == s.speed[i]).all() and (senses["command_turning"][:, 0] == s.turning[
                                            i]).all()
        ep.advance(state, 2.5)
    assert ep.task.draw_sources(None) is None  # a nominal episode: the documented tour
    assert ep.task.nominal.speed.tolist() == [0.5, 0.8, 0.5, 0.5, 0.2, 0.0]


def test_the_same_key_draws_bit_identical_commands_in_another_process():
    code = ("from evobiped.episode import EpisodeConfig\n"
            "t = EpisodeConfig(body='reil', controller='linear', task='command', seconds=1.0, "
            "task_options={'schedule': 'drawn'}, controller_options={'inputs': ['command_speed', "
            "'command_turning']}).parts()[2]\ns = t.draw_sources((11, 5)).steps(40.0)\n"
            "print(s.speed.tobytes().hex(), s.turning.tobytes().hex())")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split()
    s = standing(schedule="drawn").task.draw_sources((11, 5)).steps(40.0)
    assert out == [s.speed.tobytes().hex(), s.turning.tobytes().hex()]


def test_a_piecewise_schedule_switches_on_the_first_tick_at_or_after_each_time():
    ep = standing(schedule="piecewise", times=[0.0, 0.06, 0.25], speed=[0.1, 0.2, 0.3], turning=[0.0, -0.1, 0.1])
    state = ep.start(np.zeros((1, ep.controller.layout.size)))
    seen = []
    for _ in range(16):  # 0.02 s ticks
        senses = ep.task.sensors(ep.body, state.sims, state.task)
        seen.append((float(senses["command_speed"][0, 0]), float(senses["command_turning"][0, 0])))
        ep.advance(state, ticks=1)
    assert seen[:3] == [(0.1, 0.0)] * 3  # ticks beginning at 0 .. 0.04 s
    assert seen[3:13] == [(0.2, -0.1)] * 10  # 0.06 (the clock reads 0.0599...) .. 0.24 s
    assert seen[13:] == [(0.3, 0.1)] * 3  # from 0.26 s, the first tick at or after 0.25 s


def test_tracking_terms_of_a_walker_that_stands_match_a_hand_calculation():
    ep = standing(schedule="constant", speed=0.0, turning=0.0)
    r = ep.run(np.zeros((1, ep.controller.layout.size)))
    assert not r.fell[0]
    assert r.terms["stand"][0] > 0.99 and r.terms["track_speed"][0] > 0.99 and r.terms["track_turning"][0] > 0.99
    ep = standing(schedule="constant", speed=0.5, turning=0.2, sigma_speed=0.4)
    r = ep.run(np.zeros((1, ep.controller.layout.size)))
    assert r.terms["track_speed"][0] == pytest.approx(math.exp(-0.5 ** 2 / 0.4 ** 2), abs=1e-3)
    assert r.terms["track_turning"][0] == pytest.approx(math.exp(-0.2 ** 2 / 0.35 ** 2), abs=1e-3)
    assert r.terms["stand"][0] == 0.0  # no zero command: standing earns nothing
    w = standing().task.weights
    assert r.fitness[0] == pytest.approx(sum(w[k] * r.terms[k][0] for k in w))


def test_the_walk_tasks_gait_terms_stay_available():
    ep = standing(weights={"track_speed": 1.0, "airborne": -1.0, "sliding": -1.0, "positive_work": -1.0,
                           "duty_left": 1.0})
    assert {"airborne", "sliding", "positive_work", "duty_left", "track_speed", "track_turning",
            "stand"} <= set(ep.task.term_names)
    r = ep.run(np.zeros((1, ep.controller.layout.size)))
    assert np.isfinite(r.fitness).all()


def test_evobiped_gait_follows_a_commanded_genome(tmp_path, capsys):
    commanded_genome(tmp_path / "tiny.json")
    out = tmp_path / "out"
    code = main(["gait", str(tmp_path / "tiny.json"), "--speed", "0.5,0,1.5", "--turning", "10,0,0", "--stretch", "2",
                 "--out", str(out), "--json"])
    assert code == 0
    report = json.loads(capsys.readouterr().out)
    assert [s["commanded_speed"] for s in report["stretches"]] == [0.5, 0.0, 0.8]  # 1.5 m/s clipped to the trained 0.8
    assert len(report["notes"]) == 1 and "clipped to 0.8 m/s" in report["notes"][0]
    assert report["stretches"][0]["commanded_turning"] == pytest.approx(math.radians(10))
    for s in report["stretches"]:
        assert {"walked_speed", "walked_turning", "speed_error_pct", "fell"} <= set(s)
    assert json.loads((out / "tiny_command.json").read_text())["stretches"] == report["stretches"]
    assert (out / "tiny_command.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # its nominal schedule
    assert main(["gait", str(tmp_path / "tiny.json"), "--stretch", "0.5", "--out", str(out)]) == 0
    assert "nominal schedule" in capsys.readouterr().out


def test_clipping_to_the_trained_range():
    o = standing(schedule="drawn").task.options
    assert clip_command(o, 0.5, 0.1) == (0.5, 0.1)
    assert clip_command(o, 0.05, -1.0) == (0.0, -0.35)  # nearer a stop than the slowest speed
    assert clip_command(o, 0.15, 0.0) == (0.2, 0.0)


@pytest.mark.parametrize("options, words", [
    ({"schedule": "piecewise", "times": [-1.0, 2.0], "speed": [0.3, 0.4], "turning": [0.0, 0.0]}, "must be >= 0"),
    ({"schedule": "piecewise", "times": [0.0, 2.0, 1.0], "speed": [0.3, 0.4, 0.5], "turning": [0, 0, 0]},
     "strictly increasing"),
    ({"schedule": "piecewise", "times": [0.0, 2.0], "speed": [0.3, 0.4, 0.5], "turning": [0.0, 0.0]},
     "one speed and one turning"),
    ({"schedule": "piecewise", "times": [0.0, 2.0], "speed": [0.3, float("nan")], "turning": [0.0, 0.0]}, "finite"),
    ({"schedule": "constant", "speed": float("inf")}, "finite"),
    ({"schedule": "drawn", "speed_low": 0.9, "speed_high": 0.5}, "must not exceed"),
])
def test_a_bad_schedule_is_one_line(options, words):
    with pytest.raises(ConfigError, match=words) as e:
        EpisodeConfig(seconds=1.0, task_options=options, **STANDS).parts()
    assert "\n" not in str(e.value)


def test_bad_input_to_gait_is_one_line_and_writes_nothing(tmp_path, capsys):
    from pathlib import Path

    commanded_genome(tmp_path / "tiny.json")
    out = tmp_path / "out"
    walker = Path(__file__).resolve().parent.parent / "docs" / "walkers" / "ctrnn_es_seed5.json"
    for argv, words in ((["--speed", "0.5,0.4", "--turning", "1,2,3"], "3 turning rates for 2 speeds"),
                        (["--speed", "0.5,nan"], "finite"), (["--turning", "inf", "--speed", "0.4"], "finite")):
        assert main(["gait", str(tmp_path / "tiny.json"), *argv, "--out", str(out)]) == 2
        err = capsys.readouterr().err.strip()
        assert words in err and "\n" not in err
    assert main(["gait", str(walker), "--speed", "0.5", "--out", str(out)]) == 2  # a walker without the command senses
    err = capsys.readouterr().err.strip()
    assert "is not a commanded walker" in err and "\n" not in err
    assert not out.exists()
    # the command senses on a task without them
    with pytest.raises(ConfigError, match="not sensors of the body or task"):
        EpisodeConfig(body="reil", controller="linear", task="walk", seconds=1.0,
                      controller_options={"inputs": ["command_speed"]}).parts()


def test_the_steering_rule_reads_bearing_and_distance_from_the_ears():
    from evobiped.tasks.sound import ear_signal, intensity

    e = 0.25
    left, right = np.array([[0.0, e]] * 4), np.array([[0.0, -e]] * 4)  # ears of a walker at the origin facing +x
    D, theta = np.array([8.0, 3.0, 1.0, 0.5]), np.radians([20.0, -50.0, 80.0, 5.0])
    q = np.stack([D * np.cos(theta), D * np.sin(theta)], axis=1)
    a, b = intensity(left, q), intensity(right, q)
    speed, turning, heard = steering_command(ear_signal(left, right, q), (a + b) / 2, ear=e, gain=1.0, turning_max=10.0)
    c = 2 * D * e * np.sin(theta)  # the law of cosines from each ear: |e - q|^2 = D^2 + e^2 -+ c
    assert heard == pytest.approx(1 / np.sqrt((1 / (D ** 2 + e ** 2 - c) + 1 / (D ** 2 + e ** 2 + c)) / 2), rel=1e-9)
    # the bearing, within the distance estimate's error
    assert turning[[0, 1, 3]] == pytest.approx(theta[[0, 1, 3]], abs=0.01)
    assert 1.0 < turning[2] < theta[2]  # 1 m away at 80 deg it reads 66 deg: the loudness overstates the nearness
    assert speed[0] == pytest.approx(0.6) and speed[1] == pytest.approx(0.6)  # farther than slow_from (2 m): full speed
    assert speed[2] == pytest.approx(0.2 + 0.4 * (heard[2] - 0.3) / 1.7)  # slower as it gets near
    behind = np.array([[-5.0, 1.0]])  # a source behind on the left is heard as its mirror in front, on the left
    s, w, _ = steering_command(ear_signal(left[:1], right[:1], behind),
                               (intensity(left[:1], behind) + intensity(right[:1], behind)) / 2, ear=e)
    assert w[0] > 0
    with pytest.raises(ConfigError):
        steering_command(0.0, 0.5, ear=e, reach=4.0)


def test_standing_needs_both_feet_down(monkeypatch):
    ep = standing(schedule="constant", speed=0.0)
    monkeypatch.setattr(type(ep.body), "contacts", lambda self, sims: np.tile([True, False], (sims.n, 1)))
    r = ep.run(np.zeros((1, ep.controller.layout.size)))
    assert r.terms["track_speed"][0] > 0.99 and r.terms["stand"][0] == 0.0  # still, but on one foot: not standing


class _Stop(Exception):
    pass


def test_a_run_on_drawn_commands_resumed_on_two_workers_is_bit_identical(tmp_path):
    """The commands are drawn from (run seed, generation) alone: a run stopped after generation 1 and resumed on two
    worker processes has the uninterrupted run's history (the tracking terms included) and θ."""
    import csv

    from evobiped.run import Run, RunConfig
    from evobiped.evaluation import make_evaluator

    config = RunConfig.from_dict({
        "optimizer": "es", "generations": 3, "seed": 4, "backend": "serial", "es": {"pairs": 2},
        "episode": {**STANDS, "seconds": 0.6, "controller_options": {**STANDS["controller_options"], "frame": "stance"},
                    "task_options": {"schedule": "drawn", "stretch": 0.2, "p_stop": 0.3},
                    "perturbations": {"pose_noise": 0.01}}})
    whole = Run.create(tmp_path / "whole", config)
    with make_evaluator(config.episode, "serial") as ev:
        whole.evolve(ev)
    cut = Run.create(tmp_path / "cut", config)

    def stop(stats):
        if stats.generation == 1:
            raise _Stop

    with make_evaluator(config.episode, "serial") as ev, pytest.raises(_Stop):
        cut.evolve(ev, stop)
    with make_evaluator(config.episode, "process", 2) as ev:
        Run.resume(cut.dir).evolve(ev)

    def history(d):
        rows = list(csv.reader(open(d / "history.csv")))
        wall = rows[0].index("wall_seconds")
        return [r[:wall] + r[wall + 1:] for r in rows]

    assert history(whole.dir) == history(cut.dir) and "best_track_speed" in history(whole.dir)[0]
    a, b = (json.loads((d / "checkpoint.json").read_text()) for d in (whole.dir, cut.dir))
    assert a["optimizer"] == b["optimizer"]


def test_a_replay_of_a_commanded_walker_says_which_commands_it_follows(tmp_path, capsys):
    commanded_genome(tmp_path / "tiny.json")
    assert main(["replay", str(tmp_path / "tiny.json"), "--seconds", "0.2", "--out", str(tmp_path / "r.rrd"),
                 "--quiet"]) == 0
    lines = [x for x in capsys.readouterr().out.splitlines() if x.startswith("commands:")]
    assert len(lines) == 1 and "the fixed tour of its drawn range (0.5 m/s +0 deg/s from 0 s, 0.8 m/s" in lines[0]
