"""A hostile user's input: absurd worker counts, empty names, paths that are not UTF-8, signals while the command
starts, unbounded lengths and sizes.  Each is one line on stderr and exit status 2 (or 130 for Ctrl-C), never a
traceback, and leaves nothing behind; a case that would exhaust the machine on a regression runs in a child process
under a memory limit and a timeout.
"""

import os
import resource
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from .conftest import ROOT, cli
from .test_faults import one_line_error

TINY = ["--population", "4", "--generations", "2", "--seconds", "0.5", "--seed", "3", "--quiet"]


def guarded(*args, timeout: float = 60, memory: int = 4 * 2**30, **kw) -> subprocess.CompletedProcess:
    """``python -m evobiped ARGS`` in a child process that may take at most ``memory`` bytes and ``timeout`` s."""
    def limit():
        resource.setrlimit(resource.RLIMIT_AS, (memory, memory))
        os.setsid()

    env = {**os.environ, "PYTHONPATH": str(ROOT), **kw.pop("env", {})}
    return subprocess.run([sys.executable, "-m", "evobiped", *map(str, args)], capture_output=True, encoding="utf-8",
                          errors="replace", env=env, timeout=timeout, preexec_fn=limit, **kw)


# ---- worker counts beyond the machine
@pytest.mark.parametrize("backend", ["thread", "process", "ray"])
def test_a_worker_count_beyond_the_machine_is_one_line_before_anything_starts(tmp_path, backend):
    r = guarded("evolve", *TINY, "--backend", backend, "--workers", "100000", "--out", tmp_path / "run", timeout=60)
    assert r.returncode == 2, r.stderr
    one_line_error(r.stderr, "--workers 100000", "runs at most")
    assert not (tmp_path / "run").exists()


def test_the_use_case_refuses_a_worker_count_beyond_the_machine():
    from evobiped.core.errors import ConfigError
    from evobiped.episode import EpisodeConfig
    from evobiped.evaluation import make_evaluator, worker_limit

    with pytest.raises(ConfigError, match="runs at most"):
        make_evaluator(EpisodeConfig(seconds=0.5), "process", 10**6).close()
    assert 1 <= worker_limit("thread") <= 8 * (os.cpu_count() or 1)


# ---- an empty path or name is an error, not "not given"
def _value_flags():
    import argparse

    from evobiped.cli import build_parser

    sub = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    for name, parser in sub.choices.items():
        for action in parser._actions:
            if action.nargs == 0 or isinstance(action, argparse._SubParsersAction) or action.nargs == argparse.PARSER:
                continue
            n = action.nargs if isinstance(action, int) or isinstance(action.nargs, int) else 1
            if action.option_strings:
                yield name, [action.option_strings[0], *[""] * n]
            else:
                yield name, [""]


EMPTY = list(_value_flags())


@pytest.mark.parametrize("command, args", EMPTY, ids=[f"{c} {' '.join(a) or 'POSITIONAL'}" for c, a in EMPTY])
def test_an_empty_value_is_one_line(capsys, command, args):
    assert cli(command, *args) == 2
    one_line_error(capsys.readouterr().err, "must not be empty")


def test_resume_of_an_empty_path_starts_nothing(capsys):
    assert cli("evolve", "--resume", "") == 2
    one_line_error(capsys.readouterr().err, "--resume: must not be empty")
    assert not Path("runs").exists()


# ---- paths that are not UTF-8
@pytest.fixture(scope="module")
def latin1_run(tmp_path_factory) -> Path:
    d = tmp_path_factory.mktemp("latin1") / os.fsdecode(b"run\xff")  # a byte no UTF-8 name holds
    assert cli("evolve", *TINY, "--backend", "serial", "--out", d) == 0
    return d


@pytest.mark.parametrize("locale", ["C.UTF-8", "C"])
def test_replay_of_a_path_that_is_not_utf8(latin1_run, locale):
    r = guarded("replay", latin1_run, "--seconds", "0.5", "--figures", env={"LC_ALL": locale}, timeout=300)
    assert r.returncode == 0 and "Traceback" not in r.stderr, r.stderr
    assert (latin1_run / "replay_best.rrd").is_file() and (latin1_run / "figures_best").is_dir()


def test_select_of_a_path_that_is_not_utf8(latin1_run):
    r = guarded("select", latin1_run, "--seconds", "0.5", env={"LC_ALL": "C.UTF-8"}, timeout=300)
    assert r.returncode == 0 and "Traceback" not in r.stderr, r.stderr


def test_resume_of_a_path_that_is_not_utf8_repairs_nothing(latin1_run):
    r = guarded("evolve", "--resume", latin1_run, env={"LC_ALL": "C.UTF-8"})
    assert r.returncode == 0 and "repaired" not in r.stderr and "Traceback" not in r.stderr, r.stderr


# ---- Ctrl-C at any moment from the start: one line, never a traceback
def _interrupt(args, delay: float, group: bool = False) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    p = subprocess.Popen([sys.executable, "-m", "evobiped", *map(str, args)], stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, env=env, start_new_session=True)
    time.sleep(delay)
    with pytest.raises(ProcessLookupError) if p.poll() is not None else _nothing():
        (os.killpg if group else os.kill)(p.pid, signal.SIGINT)
    out, err = p.communicate(timeout=120)
    return subprocess.CompletedProcess(args, p.returncode, out.decode(errors="replace"), err.decode(errors="replace"))


class _nothing:
    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return exc[0] is ProcessLookupError  # it ended meanwhile


@pytest.mark.parametrize("command", ["-h", "evolve", "replay", "select"])
def test_ctrl_c_while_a_command_starts_is_one_line(latin1_run, tmp_path, command):
    for delay in (0.05, 0.1, 0.15, 0.2, 0.3, 0.4, 0.5):
        # each try its own outputs: a run stopped at its start keeps its directory (to resume), which a new run refuses
        run = tmp_path / f"run_{delay}"
        args = {"-h": ["evolve", "-h"], "evolve": ["evolve", *TINY, "--backend", "serial", "--out", run],
                "replay": ["replay", latin1_run, "--seconds", "0.5", "--out", tmp_path / f"r_{delay}.rrd"],
                "select": ["select", latin1_run, "--seconds", "0.5"]}[command]
        r = _interrupt(args, delay)
        if _interpreters_own(r.stderr):
            continue
        assert "Traceback" not in r.stderr and r.stderr.count("\n") <= 1, (delay, r.stderr)
        # -SIGINT: before Python's handler
        assert r.returncode in (0, 130, -signal.SIGINT), (delay, r.returncode, r.stderr)


def _interpreters_own(err: str) -> bool:
    """A Ctrl-C in Python's own start (its site module, runpy finding evobiped), before any of evobiped's code runs
    (tens of ms; longer on a loaded machine)."""
    frames = [line for line in err.splitlines() if line.strip().startswith("File ")]
    return bool(frames) and not any("evobiped" in f or "site-packages" in f for f in frames) and \
        any("<frozen site>" in f or "<frozen runpy>" in f for f in frames)


@pytest.mark.parametrize("delay", [0.7, 0.85, 1.0, 1.15, 1.3])
def test_ctrl_c_to_the_process_group_while_workers_start_is_one_line(tmp_path, delay):
    r = _interrupt(["evolve", *TINY, "--backend", "process", "--workers", "2", "--out", tmp_path / "run"], delay,
                   group=True)
    assert "Traceback" not in r.stderr and r.stderr.count("\n") <= 1, r.stderr
    assert r.returncode in (0, 130), r.stderr


# ---- lengths and sizes beyond the machine: refused before anything is simulated or written
@pytest.fixture(scope="module")
def plain_run(tmp_path_factory) -> Path:
    d = tmp_path_factory.mktemp("plain") / "run"
    assert cli("evolve", *TINY, "--backend", "serial", "--out", d) == 0
    return d


def test_select_of_a_billion_seconds_is_one_line(plain_run):
    r = guarded("select", plain_run, "--seconds", "1e9", timeout=60)
    assert r.returncode == 2, r.stderr
    one_line_error(r.stderr, "--seconds 1e+09", "an episode needs 1 to 1e+07")
    assert not (plain_run / "selected.json").exists()


def test_a_video_of_a_billion_frames_per_second_is_one_line(plain_run, tmp_path):
    r = guarded("replay", plain_run, "--video", tmp_path / "v.mp4", "--video-fps", "1e9", timeout=120)
    assert r.returncode == 2, r.stderr
    one_line_error(r.stderr, "--video-fps 1e+09", "more than this machine can hold")
    assert sorted(p.name for p in tmp_path.iterdir()) == []


def test_a_video_window_after_the_episode_leaves_nothing(plain_run, tmp_path, capsys):
    import shutil

    shutil.copyfile(plain_run / "best.json", tmp_path / "g.json")  # a lone genome file: its outputs go to runs/g
    assert cli("replay", tmp_path / "g.json", "--video", tmp_path / "v.mp4", "--video-window", "100", "200") == 2
    one_line_error(capsys.readouterr().err, "--video-window", "the episode ends at")
    assert not Path("runs").exists() and [p.name for p in tmp_path.iterdir()] == ["g.json"]


# ---- the right words
def test_an_interrupt_before_the_first_commit_claims_no_checkpoint(tmp_path):
    from types import SimpleNamespace

    from evobiped.usecases.evolving import stop_report

    line = stop_report(SimpleNamespace(optimizer=SimpleNamespace(generation=0), done=False, dir=tmp_path))
    assert "generation -1" not in line and "checkpoint saved" not in line and "no checkpoint yet" in line


@pytest.mark.parametrize("optimizer", ["cma", "es"])
def test_population_one_is_not_the_gas_to_refuse(tmp_path, capsys, optimizer):
    cli("evolve", "--optimizer", optimizer, "--population", 1, "--generations", 1, "--seconds", 0.5, "--backend",
        "serial", "--quiet", "--out", tmp_path / "run")
    assert "ga.population" not in capsys.readouterr().err


def test_a_video_larger_than_the_framebuffer_names_the_framebuffer(plain_run, tmp_path, capsys):
    assert cli("replay", plain_run, "--seconds", 0.5, "--video", tmp_path / "v.mp4", "--video-size", 1280, 720,
               "--out", tmp_path / "r.rrd") == 2
    err = capsys.readouterr().err
    one_line_error(err, "--video-size 1280 720", "640 x 480")
    assert "libegl" not in err and not list(tmp_path.iterdir())


def test_a_config_that_is_a_directory_says_so(tmp_path, capsys):
    assert cli("evolve", "--config", tmp_path, "--out", tmp_path / "run") == 2
    one_line_error(capsys.readouterr().err, "is a directory")


def test_a_settings_file_with_a_byte_order_mark_is_read(tmp_path):
    (tmp_path / "s.toml").write_bytes(b"\xef\xbb\xbfseed = 4\n")
    assert cli("evolve", "--config", tmp_path / "s.toml", *TINY[:-3], "--backend", "serial", "--quiet", "--out",
               tmp_path / "run") == 0
    assert '"seed": 4' in (tmp_path / "run" / "config.json").read_text()


def test_out_of_a_directory_of_other_files_suggests_no_resume_and_leaves_no_lock(tmp_path, capsys):
    (tmp_path / "notes.txt").write_text("mine")
    assert cli("evolve", *TINY, "--backend", "serial", "--out", tmp_path) == 2
    err = capsys.readouterr().err
    one_line_error(err, "holds other files, not a run")
    assert "--resume" not in err and [p.name for p in tmp_path.iterdir()] == ["notes.txt"]


def test_out_of_a_run_suggests_resume_and_leaves_its_lock_alone(plain_run, capsys):
    had = (plain_run / ".lock").exists()
    assert cli("evolve", *TINY, "--backend", "serial", "--out", plain_run) == 2
    one_line_error(capsys.readouterr().err, f"--resume {plain_run}")
    assert (plain_run / ".lock").exists() == had


# ---- presets that tune a given genome
STARTED = ["repertoire-balance", "steer-generalist", "walker-simbicon-robust", "walker-simbicon-teacher",
           "walker-ctrnn-distilled"]


@pytest.mark.parametrize("preset", STARTED)
def test_a_preset_that_needs_from_refuses_to_start_without_it(tmp_path, capsys, preset):
    assert cli("evolve", "--preset", preset, "--out", tmp_path / "run") == 2
    one_line_error(capsys.readouterr().err, f"--preset {preset}", "--from")
    assert not (tmp_path / "run").exists()


def test_presets_marks_those_that_need_from(capsys):
    assert cli("presets") == 0
    listed = dict(line.split(None, 1) for line in capsys.readouterr().out.splitlines())
    for preset in STARTED:
        assert listed[preset].endswith("(needs --from)"), preset
    assert not listed["walker"].endswith("(needs --from)") if "walker" in listed else True


# ---- a command's outputs are one set: a kill between them never leaves a new file beside an old one
def _killed_at(n: int, *args) -> subprocess.CompletedProcess:
    return guarded(*args, env={"EVOBIPED_FAULT_KILL_AT_REPLACE": str(n)}, timeout=300)


def test_a_replay_killed_between_its_outputs_leaves_no_old_figure_beside_a_new_recording(plain_run, tmp_path):
    import shutil

    d = tmp_path / "run"
    shutil.copytree(plain_run, d)
    assert guarded("replay", d, "--seconds", "0.5", "--figures", "--quiet", timeout=300).returncode == 0
    assert list((d / "figures_best").glob("*.png"))
    r = _killed_at(3, "replay", d, "--seconds", "0.5", "--figures", "--quiet")  # the mark, the recording, then killed
    assert r.returncode == -signal.SIGKILL
    assert not list((d / "figures_best").glob("*.png")), "the previous replay's figures beside the new recording"
    r = guarded("replay", d, "--seconds", "0.5", "--figures", "--quiet", timeout=300)
    assert r.returncode == 0 and "the previous replay was cut short" in r.stderr, r.stderr
    assert list((d / "figures_best").glob("*.png")) and not list(d.glob(".*incomplete"))
    assert not [p for p in (d / "figures_best").iterdir() if p.name.endswith(".tmp")]


def test_a_robustness_battery_killed_between_its_files_leaves_no_old_figure_beside_new_results(plain_run, tmp_path):
    import shutil

    d = tmp_path / "run"
    shutil.copytree(plain_run, d)
    battery = ["robustness", d, "--seconds", "1.5", "--push-after", "1", "--quiet"]
    assert guarded(*battery, timeout=300).returncode == 0
    r = _killed_at(2, *battery)  # the mark, then killed before the second rename
    assert r.returncode == -signal.SIGKILL
    assert not ((d / "robustness.json").exists() and (d / "robustness.png").exists()), "one file of each battery"
    r = guarded(*battery, timeout=300)
    assert r.returncode == 0 and "the previous robustness was cut short" in r.stderr, r.stderr
    assert (d / "robustness.json").exists() and (d / "robustness.png").exists()


def test_a_select_killed_while_it_marks_its_set_leaves_no_temporary(plain_run, tmp_path):
    import shutil

    d = tmp_path / "run"
    shutil.copytree(plain_run, d)
    assert _killed_at(1, "select", d, "--seconds", "1").returncode == -signal.SIGKILL  # the mark's own write
    assert guarded("select", d, "--seconds", "1").returncode == 0
    assert not [p.name for p in d.iterdir() if p.name.endswith(".tmp") or p.name.endswith(".incomplete")]


def test_a_select_killed_between_its_two_files_leaves_no_old_candidates_beside_a_new_choice(plain_run, tmp_path):
    import shutil

    d = tmp_path / "run"
    shutil.copytree(plain_run, d)
    assert cli("select", d, "--seconds", "1") == 0
    r = _killed_at(2, "select", d, "--seconds", "1")
    assert r.returncode == -signal.SIGKILL
    assert not ((d / "selected.json").exists() and (d / "selected_candidates.json").exists()), "one file of each select"
    r = guarded("select", d, "--seconds", "1")
    assert r.returncode == 0 and "the previous select was cut short" in r.stderr, r.stderr
    assert (d / "selected.json").exists() and (d / "selected_candidates.json").exists() and not list(d.glob(
        ".*incomplete"))


# ---- Ray's agents end with a killed run
@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="reads the process table from /proc")
def test_no_ray_process_outlives_a_killed_run(tmp_path):
    pytest.importorskip("ray")
    from .test_faults import children

    d = tmp_path / "run"
    p = subprocess.Popen([sys.executable, "-m", "evobiped", "evolve", "--population", "8", "--generations", "200",
                          "--seconds", "2",
                          "--backend", "ray", "--workers", "2", "--quiet", "--out", str(d)],
                         env={**os.environ, "PYTHONPATH": str(ROOT)},
                         stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    deadline = time.time() + 240
    while not (d / "checkpoint.json").exists() and time.time() < deadline:
        time.sleep(0.1)
    assert (d / "checkpoint.json").exists()
    ray = [k for k in _descendants(p.pid, children) if b"ray::" in _cmdline(k)]  # the agents and workers
    assert any(b"Agent" in _cmdline(k) for k in ray), "no Ray agent found"
    p.kill()
    p.wait()
    deadline = time.time() + 10  # they lived 50-65 s more before
    while [k for k in ray if _alive(k)] and time.time() < deadline:
        time.sleep(0.2)
    assert not [k for k in ray if _alive(k)], [_cmdline(k) for k in ray if _alive(k)]


def _descendants(pid: int, children) -> list[int]:
    out, todo = [], [pid]
    while todo:
        k = todo.pop()
        kids = children(k)
        out += kids
        todo += kids
    return out


def _cmdline(pid: int) -> bytes:
    try:
        return Path(f"/proc/{pid}/cmdline").read_bytes()
    except OSError:
        return b""


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


# ---- too little address space (ulimit -v): one line before NumPy, MuJoCo or Rerun is loaded
@pytest.mark.parametrize("kib", [100_000, 300_000, 524_287])
@pytest.mark.parametrize("command", [["presets"], ["episode", "--seconds", "0.5"], ["evolve", *TINY, "--out", "run"]])
def test_too_little_address_space_is_one_line_naming_the_limit_the_minimum_and_the_fix(tmp_path, kib, command):
    r = guarded(*command, memory=kib * 1024, cwd=tmp_path)
    assert r.returncode == 2, r.stderr
    one_line_error(r.stderr, f"may take {kib:,} KiB of address space (ulimit -v {kib})", "524,288 KiB (512 MiB)",
                   "raise the limit (ulimit -v 524288)")
    assert not list(tmp_path.iterdir())


def test_the_least_address_space_runs_presets_and_an_episode(tmp_path):
    from evobiped import MIN_ADDRESS_SPACE

    walker = ROOT / "docs/walkers/ctrnn_walk_seed1.json"
    for command in (["presets"], ["episode", "--genome", walker, "--seconds", "0.5"]):
        r = guarded(*command, memory=MIN_ADDRESS_SPACE, cwd=tmp_path)
        assert r.returncode == 0 and "Traceback" not in r.stderr, r.stderr


def test_importing_the_package_under_a_low_limit_checks_nothing_and_leaves_ctrl_c_alone():
    def limit():  # and Ctrl-C as a shell's new process has it, whatever this test process inherited
        resource.setrlimit(resource.RLIMIT_AS, (100_000 * 1024, 100_000 * 1024))
        signal.signal(signal.SIGINT, signal.SIG_DFL)

    code = ("import signal, sys, evobiped; "
            "print(signal.getsignal(signal.SIGINT) is signal.default_int_handler, 'numpy' in sys.modules)")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, preexec_fn=limit, timeout=60,
                       env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert (r.returncode, r.stdout, r.stderr) == (0, "True False\n", "")


@pytest.mark.parametrize("kib, command", [
    (524_288, ["replay", ROOT / "docs/walkers/ctrnn_walk_seed1.json", "--seconds", "0.5", "--out", "r.rrd"]),
    (600_000, ["evolve", *TINY, "--backend", "serial", "--out", "run"])])
def test_a_command_whose_libraries_need_more_than_the_minimum_names_the_limit_in_one_line(tmp_path, kib, command):
    """Rerun's and Arrow's libraries (replay, evolve's last files) need more than the 512 MiB the command starts in:
    one line naming the limit and its fix, never a library's own traceback.  The run has no worker (a worker's own
    need raced the last files); under the limit the ``auto`` kernel steps NumPy (numba's compiler on a cold cache
    spun there without end)."""
    r = guarded(*command, memory=kib * 1024, cwd=tmp_path)
    assert r.returncode == 2 and "Traceback" not in r.stderr, r.stderr
    one_line_error(r.stderr, f"out of address space: this process may take {kib:,} KiB (ulimit -v {kib})",
                   "raise the limit (ulimit -v unlimited)")


def test_workers_that_cannot_load_their_libraries_die_quietly_and_the_run_names_the_limit(tmp_path):
    """At 512 MiB a worker's numba and MuJoCo mostly do not fit (some runs they do: then the run completes)."""
    from evobiped import MIN_ADDRESS_SPACE

    r = guarded("evolve", *TINY, "--backend", "process", "--workers", "1", "--out", "run", memory=MIN_ADDRESS_SPACE,
                cwd=tmp_path)
    assert "Traceback" not in r.stderr and r.returncode in (0, 2), r.stderr
    if r.returncode == 2:
        last = r.stderr.strip().splitlines()[-1]
        assert last.startswith("evobiped: error: ") and "(ulimit -v 524288)" in last, r.stderr
