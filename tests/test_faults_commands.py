"""The newer commands under faults: a stop signal, a genome path that is no file, an output folder that is missing,
each one line (with the resume command where the work is resumable), nothing half-written."""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

from .conftest import ROOT, WALKERS, cli
from .test_faults import one_line_error

TINY = '[ga]\npopulation = 4\n[episode]\nseconds = 1.0\n'


def _start(*args) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "evobiped", *map(str, args)], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
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
