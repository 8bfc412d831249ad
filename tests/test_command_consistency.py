"""One prefix for every refusal, one flag for episode length, outputs named after their source."""

from __future__ import annotations

import numpy as np
import pytest

from evobiped.cli import build_parser
from evobiped.episode import EpisodeConfig
from evobiped.files.genome_file import save_genome

from .conftest import cli


@pytest.mark.parametrize("argv", [
    ["evolve", "--population", "0"],
    ["evolve", "--seconds", "nan"],
    ["replay", "nowhere.json", "--video-fps", "inf"],
    ["robustness", "nowhere.json", "--seconds", "-1"],
    ["evolve", "--no-such-flag"],
    ["episode", "--genome", "nowhere.json"],
])
def test_every_refusal_is_one_line_with_one_prefix(argv, capsys):
    assert cli(*argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("evobiped: error: ") and err.count("\n") == 1, err


@pytest.mark.parametrize("text, words", [("nan", "must be a finite number, got nan"),
                                         ("inf", "must be a finite number"),
                                         ("0", "must be > 0, got 0"), ("-2", "must be > 0, got -2")])
def test_a_size_that_is_not_a_number_says_so(text, words, capsys):
    assert cli("evolve", "--seconds", text) == 2
    assert words in capsys.readouterr().err


@pytest.mark.parametrize("command", [["evolve"], ["study"]])
def test_seconds_is_the_episode_length_and_the_old_name_still_works(command):
    parser = build_parser()
    assert parser.parse_args([*command, "--seconds", "7"]).episode_seconds == 7.0
    assert parser.parse_args([*command, "--episode-seconds", "7"]).episode_seconds == 7.0


def test_every_command_with_an_episode_length_takes_seconds():
    parser = build_parser()
    for argv in (["episode"], ["evolve"], ["study"], ["replay", "x"], ["robustness", "x"], ["distill", "x"],
                 ["select", "x"], ["bench"]):
        parser.parse_args([*argv, "--seconds", "3"])


def _genome(path):
    cfg = EpisodeConfig(seconds=0.2)
    g = cfg.build().controller.layout.sample(np.random.default_rng(1))
    path.parent.mkdir(parents=True, exist_ok=True)
    save_genome(path, g, cfg)
    return path


def test_two_runs_selected_genomes_replay_into_their_own_run_directories(tmp_path, monkeypatch):
    """Each run's selected.json used to replay into runs/selected/: the second overwrote the first."""
    from evobiped.usecases.replaying import default_out
    from evobiped.record.source import resolve

    monkeypatch.chdir(tmp_path)
    outs = []
    for run in ("runs/a", "runs/b", "elsewhere/c"):
        (tmp_path / run).mkdir(parents=True)
        (tmp_path / run / "config.json").write_text("{}")
        outs.append(default_out(resolve(_genome(tmp_path / run / "selected.json"))))
    assert [o.relative_to(tmp_path).as_posix() for o in outs] == ["runs/a/replay_selected.rrd",
                                                                  "runs/b/replay_selected.rrd",
                                                                   "elsewhere/c/replay_selected.rrd"]
    student = resolve(_genome(tmp_path / "runs" / "distill_x" / "student.json"))  # under runs/: beside it
    assert default_out(student).relative_to(tmp_path).as_posix() == "runs/distill_x/replay_student.rrd"
    # anywhere else: runs/<stem>, never beside it
    shipped = resolve(_genome(tmp_path / "repo" / "docs" / "walker.json"))
    assert default_out(shipped).as_posix() == "runs/walker/replay_walker.rrd"


def test_a_recording_with_the_video_and_one_without_have_different_names(tmp_path):
    from evobiped.usecases.replaying import default_out
    from evobiped.record.source import resolve

    source = resolve(_genome(tmp_path / "w.json"))
    assert default_out(source).name == "replay_w.rrd"
    assert default_out(source, video=True).name == "replay_w_video.rrd"


def test_replaying_a_run_with_and_without_video_keeps_both_recordings(tmp_path, monkeypatch, capsys):
    pytest.importorskip("imageio")
    monkeypatch.chdir(tmp_path)
    run = tmp_path / "runs" / "a"
    run.mkdir(parents=True)
    (run / "config.json").write_text("{}")
    genome = _genome(run / "selected.json")
    assert cli(*["replay", str(genome), "--video", str(tmp_path / "w.gif"), "--video-size", "64", "48",
                 "--video-fps", "5", "--quiet"]) == 0
    assert cli(*["replay", str(genome), "--figures", "--quiet"]) == 0
    import rerun as rr

    entities = lambda path: {c.entity_path for c in rr.chunk.RrdReader(path).stream()}  # noqa: E731
    assert any("video" in e for e in entities(run / "replay_selected_video.rrd"))
    assert not any("video" in e for e in entities(run / "replay_selected.rrd"))
    assert (run / "figures_selected" / "ground_trajectory.png").is_file()


def test_a_replay_that_checks_nothing_says_so(tmp_path, monkeypatch, capsys):
    """A perturbed run's genome file without an outcome: neither its fitness nor its outcome can be compared."""
    monkeypatch.chdir(tmp_path)
    cfg = EpisodeConfig(seconds=0.2, perturbations={"presentations": 2})
    assert cfg.perturbed
    g = cfg.build().controller.layout.sample(np.random.default_rng(1))
    save_genome(tmp_path / "w.json", g, cfg, fitness=1.0)
    assert cli("replay", tmp_path / "w.json", "--quiet") == 0
    assert "outcome not checked: the file records none" in capsys.readouterr().out
