"""The newer commands under faults: a stop signal, a genome path that is no file, an output folder that is missing,
each one line (with the resume command where the work is resumable), nothing half-written."""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from .conftest import ROOT, WALKERS, cli
from .test_faults import one_line_error

TINY = '[ga]\npopulation = 4\n[episode]\nseconds = 1.0\n'


def _start(*args) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "evobiped", *map(str, args)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE,
                            text=True, env={**os.environ, "PYTHONPATH": str(ROOT)}, start_new_session=True)


def _wait_for(p: subprocess.Popen, path: Path, timeout: float = 120) -> None:
    deadline = time.time() + timeout
    while not path.exists() and p.poll() is None and time.time() < deadline:
        time.sleep(0.05)
    assert path.exists(), p.communicate(timeout=30)


def test_a_comparison_stopped_by_a_signal_names_its_resume_command(tmp_path):
    (tmp_path / "a.toml").write_text(TINY)
    d = tmp_path / "cmp"
    p = _start("compare", tmp_path / "a.toml", "--seeds", "2", "--budget", "400", "--trials", "1", "--checkpoints", "1",
               "--workers", "1", "--quiet", "--out", d)
    _wait_for(p, d / "comparison.json")
    time.sleep(0.5)
    p.send_signal(signal.SIGTERM)
    out, err = p.communicate(timeout=60)
    assert p.returncode == 128 + signal.SIGTERM, err
    assert "Traceback" not in err and err.strip().splitlines()[-1].endswith(f"evobiped compare --resume {d}"), err


def test_a_replay_stopped_while_it_records_says_interrupted_and_nothing_else(tmp_path):
    for delay in (1.5, 3.0):
        p = _start("replay", WALKERS / "ctrnn_walk_seed1.json", "--seconds", "20", "--out", tmp_path / "r.rrd")
        time.sleep(delay)
        p.send_signal(signal.SIGTERM)
        out, err = p.communicate(timeout=60)
        if p.returncode == 0:  # done first on a fast machine
            continue
        assert p.returncode == 128 + signal.SIGTERM and err == "evobiped: interrupted\n", (delay, err)
        assert not list(tmp_path.iterdir())


def _odd(tmp_path: Path, kind: str) -> tuple[Path, str]:
    """A path that is no genome file, and the words that say what it is."""
    p = tmp_path / kind
    if kind == "fifo":
        os.mkfifo(p)
        return p, "is a FIFO (a named pipe), not a file"
    if kind == "loop":
        p.symlink_to(p)
        return p, "is a symbolic link in a loop"
    p.symlink_to(tmp_path / "gone.json")
    return p, "is a broken symbolic link"


@pytest.mark.parametrize("kind", ["fifo", "loop", "broken"])
@pytest.mark.parametrize("command", [["replay", "{p}", "--seconds", "0.5"], ["episode", "--genome", "{p}"],
                                     ["gait-report", "{p}"], ["robustness", "{p}"], ["gait", "{p}", "--speed", "0.5"]])
def test_a_genome_path_that_is_no_file_says_what_it_is(tmp_path, capsys, kind, command):
    p, words = _odd(tmp_path, kind)
    assert cli(*[a.format(p=p) for a in command]) == 2
    err = capsys.readouterr().err
    one_line_error(err, str(p), words)
    assert "not found" not in err


def test_a_figure_in_a_missing_folder_is_refused_before_the_episode(capsys):
    t0 = time.perf_counter()
    assert cli("gait-report", WALKERS / "ctrnn_walk_seed1.json", "--figure", "missing/f.png") == 2
    one_line_error(capsys.readouterr().err, "--figure: the folder missing does not exist")
    assert time.perf_counter() - t0 < 5 and not Path("missing").exists()


def _gait(out: Path, kill_at: int | None = None) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": str(ROOT),
           **({"EVOBIPED_FAULT_KILL_AT_REPLACE": str(kill_at)} if kill_at else {})}
    return subprocess.run([sys.executable, "-m", "evobiped", "gait", str(WALKERS / "ctrnn_command_seed1.json"),
                           "--speed", "0.5",
                           "--hold", "3", "--out", str(out)], capture_output=True, text=True, env=env, timeout=120)


def test_a_gait_killed_between_its_json_and_figure_leaves_no_old_figure_beside_a_new_json(tmp_path):
    out = tmp_path / "g"
    assert _gait(out).returncode == 0
    files = sorted(p.name for p in out.iterdir())
    assert len(files) == 2
    assert _gait(out, kill_at=2).returncode == -signal.SIGKILL  # the set's mark, then killed at the JSON's rename
    assert not all((out / f).exists() for f in files), "the previous figure beside a new JSON"
    r = _gait(out)
    assert r.returncode == 0 and "the previous gait was cut short" in r.stderr, r.stderr
    assert sorted(p.name for p in out.iterdir()) == files, "a temporary or the mark left behind"


# ---- a run another process is writing
@pytest.fixture
def live_run(tmp_path):
    """A run directory an evolve (serial, 400 generations of tiny episodes) is writing; the evolve ends with the
    test."""
    d = tmp_path / "run"
    p = _start("evolve", "--population", "4", "--generations", "400", "--seconds", "0.5", "--backend", "serial",
               "--quiet", "--out", d)
    _wait_for(p, d / "checkpoint.json")
    _wait_for(p, d / "best.json")  # derived after the commit: a moment later
    yield d, p
    p.kill()
    p.communicate(timeout=60)


@pytest.mark.parametrize("command", [["select", "{d}", "--seconds", "1", "--top", "1"],
                                     ["replay", "{d}", "--seconds", "0.5"],
                                     ["replay", "{d}/best.json", "--seconds", "0.5"],
                                     ["gait-report", "{d}", "--seconds", "1"],
                                     ["robustness", "{d}", "--seconds", "2", "--push-after", "1"]])
def test_a_run_being_written_is_refused_in_one_line(live_run, capsys, command):
    d, p = live_run
    assert cli(*[a.format(d=d) for a in command]) == 2
    one_line_error(capsys.readouterr().err, f"{d} is being written by process {p.pid}; wait or pass --allow-unfinished")
    assert not [x for x in d.iterdir() if x.name.startswith(("selected", "replay", "robustness", ".select", ".replay"))]


def test_a_selection_from_a_run_being_written_records_its_generation_and_is_not_reused_once_the_run_went_on(
    live_run, capsys):
    import json

    d, p = live_run
    assert cli("select", d, "--seconds", "1", "--top", "1", "--allow-unfinished") == 0
    assert f"is being written by process {p.pid}: chosen from its first" in capsys.readouterr().err
    chosen = json.loads((d / "selected.json").read_text())["from_checkpoint"]
    assert chosen["generations"] >= 1 and chosen["writer"] == p.pid and chosen["digest"]
    deadline = time.time() + 60
    while json.loads((d / "checkpoint.json").read_text())["history"].__len__() == chosen[
        "generations"] and time.time() < deadline:
        time.sleep(0.1)
    p.kill()
    p.communicate(timeout=60)
    assert cli("replay", d / "selected.json", "--seconds", "0.5") == 2
    one_line_error(capsys.readouterr().err, "selected.json was chosen when", f"choose again with evobiped select {d}")
