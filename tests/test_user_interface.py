"""What a user sees: flags that do not apply are refused, -h names the choices, long work shows progress."""

import os
import re

import numpy as np
import pytest

from evobiped.core import progress
from evobiped.cli import build_parser, main
from evobiped.episode import EpisodeConfig
from evobiped.files.genome_file import save_genome


@pytest.fixture
def genome_file(tmp_path):
    cfg = EpisodeConfig(seconds=0.5)
    lay = cfg.build().controller.layout
    g = lay.sample(np.random.default_rng(2))
    save_genome(tmp_path / "w.json", g, cfg)
    return tmp_path / "w.json"


REFUSED = [
    (["episode", "--genome", "GENOME", "--body", "taga"], "--body/--controller"),
    (["episode", "--genome", "GENOME", "--controller", "g3"], "--body/--controller"),
    (["evolve", "--address", "127.0.0.1:6379", "--generations", "1"], "--address: only a Ray backend"),
    (["evolve", "--backend", "serial", "--workers", "2", "--generations", "1"], "--workers: the serial backend"),
    (["study", "--address", "127.0.0.1:6379"], "--address: only a Ray backend"),
    (["taga", "--window", "10", "--seconds", "2"], "--window: the metrics window (10 s) cannot be longer"),
    (["taga", "--push", "leg", "--seconds", "5"], "--seconds/--window"),
    (["taga", "--push-force", "100"], "--push-force/--push-delay"),
    (["g3", "fig4", "--switch-at", "5"], "--switch-at"),
    (["g3", "fig4", "--channels", "LF"], "--channels"),
    (["g3", "fig4", "--reproduce", "out"], "PRESET: --reproduce runs the paper's own presets"),
    (["g3", "--reproduce", "out", "--go", "0.1", "--continue"], "--go/--continue: --reproduce"),
    (["g3", "fig4", "--step", "0.1"], "--step: it spaces the sweeps of --reproduce"),
    (["g3"], "g3: give a PRESET"),
    (["taga", "--reproduce", "out", "--u0", "6", "--json"],
     "--u0/--json: --reproduce runs the paper's own experiments"),
    (["taga", "--quick"], "--quick: it coarsens the grids of --reproduce"),
    (["replay", "GENOME", "--spawn"], "cannot spawn a Rerun viewer: no display here"),
    (["taga", "--seconds", "1", "--window", "1", "--save-genome", "no/such/dir/t.json"],
     "--save-genome: the folder no/such/dir does not exist"),
]


@pytest.mark.parametrize("argv, words", REFUSED, ids=[" ".join(a) for a, _ in REFUSED])
def test_a_flag_that_does_not_apply_is_refused_with_one_line(argv, words, genome_file, tmp_path, capsys, monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    monkeypatch.chdir(tmp_path)
    argv = [str(genome_file) if a == "GENOME" else a for a in argv]
    before = sorted(os.listdir(tmp_path))
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert words in err and err.count("\n") == 1 and "Traceback" not in err
    assert sorted(os.listdir(tmp_path)) == before  # nothing written


def test_more_workers_than_cores_is_one_warning_line(tmp_path, capsys):
    n = (os.cpu_count() or 1) + 3
    out = tmp_path / "run"
    assert main(["evolve", "--backend", "thread", "--workers", str(n), "--population", "4", "--generations", "1",
                 "--episode-seconds", "0.2", "--out", str(out), "--quiet"]) == 0
    warnings = [l for l in capsys.readouterr().err.splitlines() if "warning" in l]
    assert len(warnings) == 1 and f"--workers {n} on {os.cpu_count()} cores" in warnings[0]


def test_unknown_body_option_names_the_valid_ones(tmp_path, capsys):
    cfg = tmp_path / "c.toml"
    cfg.write_text("[episode.body_options]\nkpp = 3\n")
    assert main(["evolve", "--config", str(cfg), "--out", str(tmp_path / "r")]) == 2
    err = capsys.readouterr().err
    assert "episode.body_options.kpp: unknown option (choose from timestep, kp," in err
    assert "__init__" not in err and err.count("\n") == 1


def _help(command: str) -> str:
    sub = next(a for a in build_parser()._actions if a.dest == "command")
    return "".join(sub.choices[command].format_help().split())  # argparse wraps lines, also at hyphens


@pytest.mark.parametrize("command, listed", [
    ("evolve", ["reil, taga", "ctrnn, g3, linear, matsuoka, open-loop, simbicon", "walk, steer",
                "serial, process, thread, ray", "paper, paper-cyclic"]),
    ("episode", ["reil, taga", "ctrnn, g3, linear, matsuoka, open-loop, simbicon"]),
    ("bench", ["reil, taga", "ctrnn, g3, linear, matsuoka, open-loop, simbicon"]),
    ("study", ["serial, process, thread, ray", "paper, paper-cyclic"]),
    ("g3", ["fig4, fig5a"]),
    ("taga", ["rhythm-generator parameters: taga"]),
])
def test_help_lists_the_valid_names(command, listed):
    text = _help(command)
    for names in listed:
        assert "".join(names.split()) in text, (command, names)


def test_progress_line_format(capsys):
    p = progress.Progress("job", 20, "s simulated")
    p.done = 5
    p._line(p.t0 + 10.0, "")
    err = capsys.readouterr().err
    assert err == "job:  25% (5 of 20 s simulated)  elapsed 0:00:10  left ~0:00:30\n"
    quiet = progress.Progress("job", 20, quiet=True)
    quiet._line(quiet.t0 + 1, "")
    assert capsys.readouterr().err == ""


def test_time_left_counts_the_simulated_seconds_still_to_go():
    """Generations whose episodes lengthen: the time left follows the simulated seconds, not the generation count.
    The numbers are the quick start's first five generations (walker-simbicon, seed 5): wall s, longest episode s."""
    wall, clock = [1.34, 0.39, 0.36, 0.90, 0.44], [3.12, 2.18, 2.16, 14.3, 6.48]
    rate = (0.36 + 0.90 + 0.44) / (2.16 + 14.3 + 6.48)  # wall s per simulated s, the last 3 generations
    # 145 generations to go, each waiting for one 50 s episode: 537 s (the run took 642 s more)
    assert progress.time_left(wall, clock, 145, ahead=50.0) == pytest.approx(rate * 50 * 145)
    assert 0.7 * 642 < progress.time_left(wall, clock, 145, ahead=50.0) < 1.3 * 642
    # episodes as short as now: at least the latest generation's and the window's mean (7.65 s)
    assert progress.time_left(wall, clock, 145) == pytest.approx(rate * (2.16 + 14.3 + 6.48) / 3 * 145)
    assert progress.time_left([1.0, 1.0, 4.0], [10.0, 10.0, 40.0], 2) == pytest.approx(2 * 40 * 6 / 60)
    assert progress.time_left([2.0, 4.0], [0.0, 0.0], 3) == pytest.approx(9.0)  # nothing simulated: wall per step
    assert np.isnan(progress.time_left([], [], 5))


def test_every_long_command_reports_in_one_line_shape(capsys):
    p = progress.Progress("evolve", 150, "generations")
    p.t0 -= 62.0
    p.report(6, "best 21.000 (up), this generation's 6.060 (fell)", left=760.0)
    err = capsys.readouterr().err
    assert err == ("evolve:   4% (6 of 150 generations; best 21.000 (up), this generation's 6.060 (fell))  "
                   "elapsed 0:01:02  left ~0:12:40\n")
    got = []
    progress.Progress("study", 4, "runs", emit=got.append).report(1, "last: plain seed 0")
    assert len(got) == 1 and re.fullmatch(r"study:  25% \(1 of 4 runs; last: plain seed 0\)  elapsed 0:00:00  left "
                                          r"~0:00:00", got[0])


def test_the_robustness_table_has_one_header_per_column_and_names_its_statistics():
    from evobiped.analysis.robustness import table

    rows = [{"family": "push 5 N", "trials": 32, "survived": 30, "survival": 30 / 32, "forward_m": 12.345,
             "median_fall_s": 14.5},
            {"family": "slope", "trials": 2, "survived": 2, "survival": 1.0, "forward_m": -1.0, "median_fall_s": None}]
    head, *lines = table(rows).splitlines()
    cols = re.split(r" {2,}", head.strip())
    assert cols == ["family", "survived", "of", "survival", "mean forward (m)", "median fall time of the fallen (s)"]
    for line in lines:
        assert len(re.split(r" {2,}", line.strip())) == len(cols)  # one value under each header
    assert re.split(r" {2,}", lines[0].strip()) == ["push 5 N", "30", "32", "94%", "12.35", "14.50"]
    assert lines[1].split()[-1] == "-"
    # each value ends where its header ends (right-aligned columns)
    ends = [m.end() for m in re.finditer(r"\S+(?: \S+)*", head)]
    assert [m.end() for m in re.finditer(r"\S+(?: \S+)*", lines[0])][1:] == ends[1:]


def test_taga_shows_progress_unless_quiet(capsys, monkeypatch):
    monkeypatch.setattr(progress, "INTERVAL", 0.0)
    assert main(["taga", "--seconds", "1.5", "--window", "1"]) == 0
    lines = [l for l in capsys.readouterr().err.splitlines() if l.startswith("taga: ")]
    assert len(lines) >= 3 and "left ~" in lines[0] and lines[-1].startswith("taga: 100% (1.5 of 1.5 s simulated)")
    assert main(["taga", "--seconds", "1.5", "--window", "1", "--quiet"]) == 0
    assert capsys.readouterr().err == ""


def test_replay_shows_progress_unless_quiet(genome_file, capsys, monkeypatch):
    monkeypatch.setattr(progress, "INTERVAL", 0.0)
    assert main(["replay", str(genome_file)]) == 0
    lines = [l for l in capsys.readouterr().err.splitlines() if l.startswith("replay: ")]
    assert lines and "s simulated" in lines[-1]
    assert main(["replay", str(genome_file), "--quiet"]) == 0
    assert "replay: " not in capsys.readouterr().err


def test_robustness_shows_progress_unless_quiet(tmp_path, capsys, monkeypatch):
    cfg = EpisodeConfig(seconds=2.0, controller="simbicon")
    lay = cfg.build().controller.layout
    save_genome(tmp_path / "s.json", (lay.low + lay.high) / 2, cfg)
    monkeypatch.setattr(progress, "INTERVAL", 0.0)
    assert main(["robustness", str(tmp_path / "s.json"), "--seconds", "1.0", "--push-after", "0.5"]) == 0
    lines = [l for l in capsys.readouterr().err.splitlines() if l.startswith("robustness: ")]
    # what it really simulates: 164 trials of 1 s, each counted for its own simulated time
    assert lines and lines[-1].startswith("robustness: 100% (164 of 164 trial-s of 164 trials of 1 s)")
    assert main(["robustness", str(tmp_path / "s.json"), "--seconds", "1.0", "--push-after", "0.5", "--quiet"]) == 0
    assert "robustness: " not in capsys.readouterr().err


def test_a_closed_output_pipe_ends_quietly():
    """`evobiped presets | head -1`: the reader leaves early; no traceback, exit 141 like cat."""
    import subprocess
    import sys

    proc = subprocess.Popen([sys.executable, "-m", "evobiped", "presets"], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, env=dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path)))
    proc.stdout.close()  # before the child has imported anything, so its first write meets a closed pipe
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 141 and err == b""


def test_a_stop_signal_python_cannot_raise_is_no_traceback_other_errors_still_are(capsys, monkeypatch):
    """A second Ctrl-C while the pool is torn down strikes inside a weakref callback: Python would print
    'Exception ignored ... KeyboardInterrupt' after the command's last line; the command's hook drops only that."""
    import sys

    from evobiped.cli import quiet_interrupts

    class Raises:  # Python cannot raise from __del__: it hands the exception to sys.unraisablehook
        def __init__(self, exc):
            self.exc = exc

        def __del__(self):
            raise self.exc

    monkeypatch.setattr(sys, "unraisablehook", quiet_interrupts)
    Raises(KeyboardInterrupt())
    assert capsys.readouterr().err == ""
    Raises(ValueError("a real fault"))
    assert "a real fault" in capsys.readouterr().err
