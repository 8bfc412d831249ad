"""Fault injection on ``evobiped evolve``: kills between every pair of writes, a killed run's processes, a dead worker,
a lost Ray node, two writers, a full disk, tampered files (huge numbers, foreign formats) and hostile configs.

Each fault ends in a completed run equal to an undisturbed one (wall times aside) or in one line on
stderr with exit status 2 and nothing lost.  Runs are tiny (4 walkers, 0.5 s episodes, 2 generations):
a whole evolve takes about a second.
"""

import csv
import json
import os
import re
import resource
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from evobiped.files.rundir import HISTORY_COLUMNS

from .conftest import cli

ROOT = Path(__file__).resolve().parents[1]
RUN = ["--population", "4", "--generations", "2", "--episode-seconds", "0.5", "--backend", "serial", "--seed", "3",
       "--quiet"]
#: atomic renames of an undisturbed RUN: config, history header, 5 per generation, summary
WRITES = 2 + 5 * 2 + 1


def evolve(*args, env=None, **kw) -> subprocess.CompletedProcess:
    """``python -m evobiped evolve ARGS`` in a child process (a kill there does not touch the tests)."""
    env = {**os.environ, "PYTHONPATH": str(ROOT), **(env or {})}
    return subprocess.run([sys.executable, "-m", "evobiped", "evolve", *map(str, args)], capture_output=True, text=True,
                          env=env, **kw)



def contents(d: Path) -> dict:
    """Every file of a run directory, wall-clock times left out (the evolution recording as its series)."""
    from evobiped.record.recordings.evolution_log import recording_series

    out = {}
    for p in sorted(d.rglob("*")):
        name = str(p.relative_to(d))
        if not p.is_file() or name == ".lock":
            continue
        if name == "evolution.rrd":
            for s in ("best", "mean", "median", "worst", "counts/evaluations", "counts/falls", "counts/unstable",
                      "terms/best_distance"):
                out[f"{name}:{s}"] = recording_series(p, f"/evolution/{s}")
        elif name == "history.csv":
            wall = HISTORY_COLUMNS.index("wall_seconds")
            out[name] = [r[:wall] + r[wall + 1 :] for r in csv.reader(p.read_text().splitlines())]
        elif name in ("checkpoint.json", "summary.json"):
            obj = json.loads(p.read_text())
            obj.pop("wall_seconds")
            for row in obj.get("history", []):
                row.pop()
            out[name] = obj
        else:
            out[name] = p.read_bytes()
    return out


@pytest.fixture(scope="module")
def reference(tmp_path_factory) -> Path:
    d = tmp_path_factory.mktemp("ref") / "run"
    r = evolve(*RUN, "--out", d)
    assert r.returncode == 0, r.stderr
    return d


@pytest.fixture
def done(reference, tmp_path) -> Path:
    """A completed run to damage."""
    d = tmp_path / "run"
    shutil.copytree(reference, d)
    return d


def files(d: Path) -> dict:
    """Every file's bytes (the lock, which names its last holder, left out)."""
    return {p: p.read_bytes() for p in d.rglob("*") if p.is_file() and p.name != ".lock"}


def one_line_error(err: str, *words: str) -> None:
    assert err.count("\n") == 1 and err.startswith("evobiped: error: ") and "Traceback" not in err, err
    for w in words:
        assert w in err, err


# ---- kills between every pair of writes
@pytest.mark.parametrize("n", range(1, WRITES + 1))
def test_kill_at_every_write_then_resume_equals_an_undisturbed_run(reference, tmp_path, n):
    d = tmp_path / "run"
    killed = evolve(*RUN, "--out", d, env={"EVOBIPED_FAULT_KILL_AT_REPLACE": str(n)})
    assert killed.returncode == -signal.SIGKILL
    if not (d / "config.json").exists():  # killed before the config was written: nothing to resume, start again
        r = evolve("--resume", d)
        assert r.returncode == 2 and "holds no run yet" in r.stderr and r.stderr.count("\n") == 1
        assert evolve(*RUN, "--out", d).returncode == 0
    else:
        r = evolve("--resume", d, "--quiet")
        assert r.returncode == 0, r.stderr
        assert "Traceback" not in r.stderr
    assert contents(d) == contents(reference)
    assert not list(d.rglob(".*.tmp"))


def test_the_hook_kills_exactly_at_the_last_write(tmp_path):
    """WRITES is the number of renames of RUN: one more kill point finds a finished run."""
    r = evolve(*RUN, "--out", tmp_path / "r", env={"EVOBIPED_FAULT_KILL_AT_REPLACE": str(WRITES + 1)})
    assert r.returncode == 0


# ---- derived files damaged: rebuilt from the checkpoint
DAMAGE = {
    "history deleted": ("history.csv", lambda p: p.unlink()),
    "history emptied": ("history.csv", lambda p: p.write_text("")),
    "history random bytes": ("history.csv", lambda p: p.write_bytes(os.urandom(300))),
    "history last row lost": ("history.csv", lambda p: p.write_text("".join(p.read_text().splitlines(True)[:-1]))),
    "history overwritten": ("history.csv", lambda p: p.write_text("generation,best,mean\n0,99,1\n")),
    "best deleted": ("best.json", lambda p: p.unlink()),
    "best tampered": ("best.json", lambda p: p.write_text(p.read_text().replace('"fitness": ', '"fitness": 1'))),
    "recording deleted": ("evolution.rrd", lambda p: p.unlink()),
    "recording cut": ("evolution.rrd", lambda p: p.write_bytes(p.read_bytes()[: p.stat().st_size // 2])),
    "recording garbage": ("evolution.rrd", lambda p: p.write_bytes(os.urandom(1000))),
    "summary deleted": ("summary.json", lambda p: p.unlink()),
    "summary tampered": ("summary.json", lambda p: p.write_text("{}")),
}


@pytest.mark.parametrize("name", DAMAGE)
def test_damaged_derived_file_is_rebuilt_on_resume(reference, done, capsys, name):
    file, damage = DAMAGE[name]
    damage(done / file)
    assert cli("evolve", "--resume", done) == 0
    captured = capsys.readouterr()
    assert f"evobiped: repaired: {file} " in captured.err and "already complete" in captured.out
    assert contents(done) == contents(reference)


def test_a_run_cut_after_its_last_checkpoint_gets_its_summary(reference, done, capsys):
    (done / "summary.json").unlink()
    (done / "evolution.rrd").unlink()
    assert cli("evolve", "--resume", done) == 0
    assert "repaired: summary.json written" in capsys.readouterr().err
    assert contents(done) == contents(reference)
    assert cli("evolve", "--resume", done) == 0  # now nothing to repair
    assert "repaired" not in capsys.readouterr().err


# ---- the checkpoint tampered with: one line, exit 2, nothing changed
def tamper(path: Path, change) -> None:
    ck = json.loads(path.read_text())
    path.write_text(json.dumps(change(ck)))


TAMPER = {
    "history is a number": (lambda ck: {**ck, "history": 5}, "history must be a list"),
    "best is a string": (lambda ck: {**ck, "best": "x"}, "best must be a table"),
    "best fitness inf": (lambda ck: {**ck, "best": {**ck["best"], "fitness": float("inf")}},
                         "best.fitness must be finite"),
    "best fitness not in the history": (lambda ck: {**ck, "best": {**ck["best"], "fitness": 1e9}},
                                        "best.fitness must be the best fitness of"),
    "fitness list too short": (lambda ck: {**ck,
                                           "optimizer": {**ck["optimizer"], "fitness": ck["optimizer"]["fitness"][:2]}},
                               "ga.fitness must be a list of 4"),
    "gene 1e300": (lambda ck: {**ck, "optimizer": {**ck["optimizer"],
                                                   "population": [[1e300] + r[1:]
                                                                  for r in ck["optimizer"]["population"]]}},
                   "outside the gene's bounds"),
    "best gene 1e300": (lambda ck: {**ck, "best_genome": [1e300] + ck["best_genome"][1:]},
                        "best_genome[0] must be within"),
    "history row of text": (lambda ck: {**ck, "history": [["a"] * 9] * 2},
                            "history[0].generation must be a whole number"),
    "generation is text": (lambda ck: {**ck, "optimizer": {**ck["optimizer"], "generation": "2"}},
                           "ga.generation must be a whole number"),
    "no optimizer state": (lambda ck: {k: v for k, v in ck.items() if k != "optimizer"}, "optimizer is missing"),
    "written by CMA-ES": (lambda ck: {**ck, "optimizer": {**ck["optimizer"], "name": "cma"}},
                          "written by the 'cma' optimizer"),
    "null": (lambda ck: None, "is null"),
    "a list": (lambda ck: [], "expected a table"),
}


@pytest.mark.parametrize("name", TAMPER)
def test_tampered_checkpoint_is_one_line_and_changes_nothing(done, capsys, name):
    change, words = TAMPER[name]
    tamper(done / "checkpoint.json", change)
    before = files(done)
    assert cli("evolve", "--resume", done) == 2
    one_line_error(capsys.readouterr().err, words)
    assert files(done) == before


def test_a_deleted_checkpoint_does_not_restart_the_run(done, capsys):
    (done / "checkpoint.json").unlink()
    before = files(done)
    assert cli("evolve", "--resume", done) == 2
    one_line_error(capsys.readouterr().err, "checkpoint.json is missing", "cannot be resumed")
    assert files(done) == before


# ---- two writers
def test_two_runs_into_one_directory_one_wins(tmp_path, reference):
    d = tmp_path / "run"
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    procs = [subprocess.Popen([sys.executable, "-m", "evobiped", "evolve", *RUN[:-3], "--seed", str(seed), "--quiet",
                               "--out", str(d)],
                              stderr=subprocess.PIPE, text=True, env=env) for seed in (3, 4)]
    results = [(p.wait(timeout=120), p.stderr.read()) for p in procs]
    codes = sorted(rc for rc, _ in results)
    assert codes == [0, 2], results
    loser = next(err for rc, err in results if rc == 2)
    assert ("is in use by process" in loser or "already holds a run" in loser) and loser.count("\n") == 1
    if json.loads((d / "config.json").read_text())["seed"] == 3:
        assert contents(d) == contents(reference)
    assert cli("evolve", "--resume", d) == 0  # a consistent run: nothing to repair


def test_resume_of_a_running_run_is_refused_and_a_dead_owner_frees_it(tmp_path, reference, capsys):
    d = tmp_path / "run"
    slow = [*RUN[:2], "--generations", "2000", *RUN[4:]]
    proc = subprocess.Popen([sys.executable, "-m", "evobiped", "evolve", *slow, "--out", str(d)],
                            env={**os.environ, "PYTHONPATH": str(ROOT)})
    try:
        deadline = time.time() + 60
        while not (d / "checkpoint.json").exists() and time.time() < deadline:
            time.sleep(0.05)
        assert cli("evolve", "--resume", d) == 2
        one_line_error(capsys.readouterr().err, f"is in use by process {proc.pid}")
        second = evolve(*slow, "--out", d)
        assert second.returncode == 2 and f"in use by process {proc.pid}" in second.stderr
    finally:
        proc.kill()
        proc.wait()
    # the owner died holding the lock: the kernel released it
    r = evolve("--resume", d, "--quiet", env={"EVOBIPED_FAULT_KILL_AT_REPLACE": "1"})
    assert r.returncode == -signal.SIGKILL  # it got the lock and went on to write


# ---- a worker dies
@pytest.mark.parametrize("backend, timeout", [("process", 120), ("ray", 300)])
def test_a_dead_worker_is_replaced_and_its_batch_evaluated_again(tmp_path, reference, backend, timeout):
    """A pool worker (or Ray actor) that dies: its batch is evaluated again, and the run equals an undisturbed one."""
    if backend == "ray":
        pytest.importorskip("ray")
    marker = tmp_path / "kill-one-worker"
    marker.touch()
    d = tmp_path / "run"
    r = evolve(*RUN[:-3], "--seed", "3", "--quiet", "--backend", backend, "--workers", "2", "--out", d,
               env={"EVOBIPED_FAULT_KILL_WORKER": str(marker)}, timeout=timeout)
    assert r.returncode == 0, r.stderr
    assert not marker.exists()  # a worker took the hook and died
    if backend == "process":
        assert "a worker died; evaluating its batch again (retry 1 of 3)" in r.stderr
    got, want = contents(d), contents(reference)
    got.pop("config.json"), want.pop("config.json")  # backend and workers differ
    assert got == want


def test_workers_that_keep_dying_stop_the_generation_after_the_last_retry(tmp_path, monkeypatch):
    from evobiped.episode import EpisodeConfig
    from evobiped.core.errors import UserError
    from evobiped.evaluation import MAX_RETRIES, ProcessPoolEvaluator

    marker = tmp_path / "kill-one-worker"
    marker.touch()
    monkeypatch.setenv("EVOBIPED_FAULT_KILL_WORKER", str(marker))
    retries = []

    def again(n, limit):  # every new pool loses a worker too
        retries.append((n, limit))
        marker.touch()

    cfg = EpisodeConfig(seconds=0.1)
    with ProcessPoolEvaluator(cfg, 1, on_retry=again) as ev, pytest.raises(UserError, match="workers died 4 times"):
        ev.evaluate(np.zeros((2, cfg.build().controller.layout.size)))
    assert retries == [(n, MAX_RETRIES) for n in range(1, MAX_RETRIES + 1)]


# ---- a full disk
def test_full_disk_is_one_line_and_the_run_completes_later(tmp_path, reference):
    d = tmp_path / "run"
    limit = lambda: resource.setrlimit(resource.RLIMIT_FSIZE, (20_000, 20_000))  # noqa: E731
    r = evolve(*RUN, "--out", d, preexec_fn=limit)
    assert r.returncode == 2
    one_line_error(r.stderr, "cannot write", "File too large")
    assert not (d / "summary.json").exists()
    r = evolve("--resume", d, "--quiet")
    assert r.returncode == 0, r.stderr
    assert contents(d) == contents(reference)


# ---- places that cannot be written
def test_out_under_a_file(tmp_path, capsys):
    (tmp_path / "file").write_text("x")
    assert cli("evolve", *RUN, "--out", tmp_path / "file" / "run") == 2
    one_line_error(capsys.readouterr().err, "cannot write", "Not a directory")


#: as root (which writes anywhere), the resume runs without the capabilities that override file permissions
AS_USER = ["setpriv", "--bounding-set", "-dac_override,-dac_read_search"]


def test_read_only_run_directory(done, capsys):
    probe = done / "probe"
    probe.mkdir(mode=0o555)
    try:
        (probe / "x").touch()
        root = True
    except PermissionError:
        root = False
    (probe / "x").unlink(missing_ok=True)
    probe.rmdir()
    if root and shutil.which(AS_USER[0]) is None:
        pytest.skip("this user writes into read-only directories (root) and has no setpriv to drop that power")
    (done / "summary.json").unlink()
    for p in [done, done / "generations"]:
        p.chmod(0o555)
    try:
        if root:
            r = subprocess.run([*AS_USER, sys.executable, "-m", "evobiped", "evolve", "--resume", str(done)],
                               capture_output=True, text=True, env={**os.environ, "PYTHONPATH": str(ROOT)})
            rc, err = r.returncode, r.stderr
        else:
            rc, err = cli("evolve", "--resume", done), capsys.readouterr().err
        assert rc == 2
        one_line_error(err, "cannot write", "Permission denied")
    finally:
        for p in [done, done / "generations"]:
            p.chmod(0o755)


# ---- hostile configs: one line, exit 2, nothing written
HOSTILE = {
    "[episode.body_options]\ntimestep = 0": "episode.body_options.timestep: must be in",
    "[episode.body_options]\ntimestep = nan": "episode.body_options.timestep: must be finite",
    "[episode.body_options]\ntimestep = 'fast'": "episode.body_options.timestep: must be a number",
    "[episode.body_options]\ntimestep = 1e-9": "episode.body_options.timestep: must be in",
    "[episode]\nseconds = inf": "episode.seconds: must be finite",
    "[episode]\nseconds = 1e-9": "control ticks",
    "[episode]\nseconds = true": "episode.seconds: must be a number",
    "[episode.task_options]\ncyclic_weight = inf": "episode.task_options.cyclic_weight: must be finite",
    "[episode.task_options]\ncyclic_weight = nan": "episode.task_options.cyclic_weight: must be finite",
    "[ga]\npopulation = 1000000000": "ga.population: must be in",
    "[ga]\npopulation = 5000000": "GiB",
    "generations = true": "generations: must be a whole number",
    "[ga]\nmutations_per_genome = inf": "ga.mutations_per_genome: must be finite",
}


@pytest.mark.parametrize("text", HOSTILE, ids=[t.replace("\n", " ") for t in HOSTILE])
def test_hostile_config_is_one_line_and_writes_nothing(tmp_path, capsys, text, monkeypatch):
    from evobiped.run import run_config

    monkeypatch.setattr(run_config, "WALKER_BYTES", 2**30)  # any machine: 5e6 walkers of 1 GiB do not fit
    cfg = tmp_path / "c.toml"
    cfg.write_text(text)
    assert cli("evolve", "--config", cfg, "--out", tmp_path / "run", "--backend", "serial", "--quiet") == 2
    one_line_error(capsys.readouterr().err, HOSTILE[text])
    assert not (tmp_path / "run").exists()


@pytest.mark.parametrize("episode, words", [({"seconds": 0}, "episode.seconds: must be > 0"),
                                            ({"seconds": True}, "must be a number"),
                                             ({"body_options": {"timestep": 0}},
                                              "episode.body_options.timestep: must be in")])
def test_replaying_a_genome_with_a_hostile_episode_is_one_line(reference, tmp_path, capsys, episode, words):
    g = json.loads((reference / "best.json").read_text())
    g["episode"].update(episode)
    f = tmp_path / "g.json"
    f.write_text(json.dumps(g))
    assert cli("replay", f, "--out", tmp_path / "r.rrd", "--quiet") == 2
    one_line_error(capsys.readouterr().err, words)


# ---- the process that evolves is killed: no worker, no resource tracker outlives it
def children(pid: int) -> list[int]:
    """The live processes whose parent is ``pid`` (zombies left out)."""
    out = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except (OSError, IndexError):
            continue
        if int(fields[1]) == pid and fields[0] != "Z":
            out.append(int(stat.parent.name))
    return out


def alive(pid: int) -> bool:
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except (OSError, IndexError):
        return False


#: a process-backend run long enough to be killed in the middle
LONG = [*RUN[:2], "--generations", "2000", *RUN[4:6], "--seed", "3", "--backend", "process", "--workers", "2"]


def start_long(d: Path) -> tuple[subprocess.Popen, list[int]]:
    """A long process-backend run into ``d``, once its first generation is committed; its pool workers and resource
    tracker."""
    def defaults():  # as a terminal delivers them, even where this test runs under nohup or in a background job
        for s in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
            signal.signal(s, signal.SIG_DFL)

    proc = subprocess.Popen([sys.executable, "-m", "evobiped", "evolve", *LONG, "--quiet", "--out", str(d)],
                            stderr=subprocess.PIPE, text=True,
                            env={**os.environ, "PYTHONPATH": str(ROOT)}, preexec_fn=defaults)
    deadline = time.time() + 60
    while not (d / "checkpoint.json").exists() and time.time() < deadline:
        time.sleep(0.05)
    kids = children(proc.pid)
    assert len(kids) == 3, kids  # two workers and the resource tracker
    return proc, kids


def gone(pids: list[int], within: float = 5.0) -> list[int]:
    """Those of ``pids`` still alive after ``within`` s."""
    deadline = time.time() + within
    while any(map(alive, pids)) and time.time() < deadline:
        time.sleep(0.05)
    return [p for p in pids if alive(p)]


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="reads the process table from /proc")
@pytest.mark.parametrize("sig", [signal.SIGKILL, signal.SIGTERM, signal.SIGHUP], ids=lambda s: s.name)
def test_no_process_of_a_killed_run_survives_it(tmp_path, sig):
    """SIGKILL (the out-of-memory killer), SIGTERM, SIGHUP: the workers and the resource tracker end with the run;
    SIGTERM and SIGHUP stop it as Ctrl-C does (checkpoint kept, one line with the resume command, exit 128 + n)."""
    d = tmp_path / "run"
    proc, kids = start_long(d)
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=60)
    assert gone(kids) == []
    if sig == signal.SIGKILL:
        assert proc.returncode == -sig
        return
    assert proc.returncode == 128 + sig, err
    one_line = err.count("\n") == 1 and "Traceback" not in err
    assert one_line and f"checkpoint saved; continue with: evobiped evolve --resume {d}" in err, err
    done = len(json.loads((d / "checkpoint.json").read_text())["history"])
    assert f"interrupted after generation {done - 1} " in err
    assert (d / "history.csv").read_text().count("\n") == done + 1


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="reads the process table from /proc")
def test_a_killed_resource_tracker_prints_nothing(tmp_path):
    d = tmp_path / "run"
    proc, kids = start_long(d)
    tracker = next(p for p in kids if b"resource_tracker" in Path(f"/proc/{p}/cmdline").read_bytes())
    os.kill(tracker, signal.SIGKILL)
    time.sleep(1)
    proc.send_signal(signal.SIGTERM)  # the pool shuts down: its semaphores are unregistered with a relaunched tracker
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 128 + signal.SIGTERM
    assert err.count("\n") == 1 and "interrupted after generation" in err, err
    assert gone(children(proc.pid) + kids) == []


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM, signal.SIGHUP])
def test_a_stop_signal_during_a_checkpoint_waits_for_both_files(tmp_path, monkeypatch, signum):
    """Ctrl-C, SIGTERM or SIGHUP between writing checkpoint.json and history.csv stops the run only after both are
    written (KeyboardInterrupt; Interrupted carrying the signal for the other two)."""
    import evobiped.run.checkpoint as commit_point
    from evobiped.core.errors import stop_on_signals
    from evobiped.evaluation import make_evaluator
    from evobiped.run.run import Run
    from evobiped.run.run_config import RunConfig

    config = RunConfig.from_dict({"episode": {"seconds": 0.5}, "ga": {"population": 4}, "generations": 2,
                                  "backend": "serial"})
    run = Run.create(tmp_path / "r", config)
    write = commit_point.write_json

    def write_then_signal(path, obj):
        write(path, obj)
        if Path(path).name == "checkpoint.json":
            # to this (the main) thread: a process-directed kill may land in another thread (Rerun's, say)
            # and reach the interpreter only after the deferral ended, which makes the test flaky
            signal.raise_signal(signum)

    monkeypatch.setattr(commit_point, "write_json", write_then_signal)
    # the default handlers, as a terminal or a process manager meets them (a background job ignores SIGINT)
    old = signal.signal(signum, signal.default_int_handler if signum == signal.SIGINT else signal.SIG_DFL)
    restore = stop_on_signals()
    try:
        with make_evaluator(config.episode, "serial") as ev, pytest.raises(KeyboardInterrupt) as caught:
            run.evolve(ev)
    finally:
        restore()
        signal.signal(signum, old)
        run.close()
    assert getattr(caught.value, "signum", signal.SIGINT) == signum
    ck = json.loads((run.dir / "checkpoint.json").read_text())
    assert len(ck["history"]) == 1 and (run.dir / "history.csv").read_text().count("\n") == 2


# ---- a value only a worker would have refused: checked once, in this process, before anything is written
TIMING = {"seconds = 1e-9": "control ticks", "seconds = 1e300": "control ticks"}


@pytest.mark.parametrize("backend", ["serial", "thread", "process", "ray"])
@pytest.mark.parametrize("text", TIMING)
def test_episode_length_is_refused_before_any_worker_or_file(tmp_path, capsys, backend, text):
    cfg = tmp_path / "c.toml"
    cfg.write_text(f"[episode]\n{text}\n")
    workers = [] if backend == "serial" else ["--workers", "2"]
    assert cli("evolve", "--config", cfg, "--out", tmp_path / "run", "--backend", backend, *workers, "--quiet") == 2
    one_line_error(capsys.readouterr().err, TIMING[text])
    assert not (tmp_path / "run").exists()


@pytest.mark.parametrize("backend", ["serial", "thread", "process", "ray"])
def test_episode_seconds_flag_is_refused_before_any_worker_or_file(tmp_path, capsys, backend):
    workers = [] if backend == "serial" else ["--workers", "2"]
    assert cli("evolve", *RUN[:4], "--episode-seconds", "1e-9", "--backend", backend, *workers, "--quiet", "--out",
               tmp_path / "run") == 2
    one_line_error(capsys.readouterr().err, "episode seconds = 1e-09 gives 5e-08 control ticks")
    assert not (tmp_path / "run").exists()


@pytest.mark.parametrize("backend", ["serial", "process"])
def test_resume_of_a_run_with_a_bad_episode_length_is_one_line(done, capsys, backend):
    (done / "summary.json").unlink()
    cfg = json.loads((done / "config.json").read_text())
    cfg["episode"]["seconds"] = 1e-9
    (done / "config.json").write_text(json.dumps(cfg))
    before = files(done)
    assert cli("evolve", "--resume", done, "--backend", backend) == 2
    one_line_error(capsys.readouterr().err, "differs from the one this checkpoint was made with: episode.seconds 0.5 → "
                                            "1e-09")
    assert files(done) == before


# ---- no room for the lock's pid
def test_full_disk_at_the_lock_is_one_line_and_leaves_no_empty_lock(tmp_path, capsys, monkeypatch, reference):
    import errno

    from evobiped.files.rundir import locking

    def full(fd, data, offset):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    d = tmp_path / "run"
    d.mkdir()
    (d / ".lock").touch()  # an empty lock an earlier version left
    monkeypatch.setattr(locking.os, "pwrite", full)
    assert cli("evolve", *RUN, "--out", d) == 2
    one_line_error(capsys.readouterr().err, f"cannot write {d.resolve() / '.lock'}: No space left on device")
    assert list(d.iterdir()) == []
    done = tmp_path / "done"
    shutil.copytree(reference, done)
    (done / ".lock").unlink()
    (done / "summary.json").unlink()
    before = files(done)
    assert cli("evolve", "--resume", done) == 2  # the same on resume
    one_line_error(capsys.readouterr().err, "cannot write", ".lock: No space left on device")
    assert files(done) == before and not (done / ".lock").exists()
    monkeypatch.undo()  # space again: the run completes
    assert cli("evolve", "--resume", done, "--quiet") == 0
    assert contents(done) == contents(reference)


# ---- files evobiped reads: numbers too long to read, formats of other programs
HUGE = "9" * 5000


@pytest.mark.parametrize("command", ["evolve --resume", "replay", "episode --genome", "robustness"])
def test_a_number_of_5000_digits_is_one_line(done, capsys, command):
    if command == "evolve --resume":
        path = done / "checkpoint.json"
        path.write_text(re.sub(r'"wall_seconds": [0-9.e+-]+', f'"wall_seconds": {HUGE}', path.read_text()))
        (done / "summary.json").unlink()
        args = ["evolve", "--resume", done]
    else:
        path = done / "best.json"
        path.write_text(re.sub(r'"generation": [0-9]+', f'"generation": {HUGE}', path.read_text()))
        args = [*command.split(), path, *(["--out", done / "x.rrd"] if command == "replay" else [])]
    before = files(done)
    assert cli(*args) == 2
    one_line_error(capsys.readouterr().err, str(path), "a whole number of more than 4300 digits")
    assert files(done) == before


@pytest.mark.parametrize("name", ["best.json", "generations/gen_0001.json", "checkpoint.json"])
def test_a_file_in_another_format_is_one_line(done, capsys, name):
    path = done / name
    obj = json.loads(path.read_text())
    obj["format"] = "other/9"
    path.write_text(json.dumps(obj))
    if name == "checkpoint.json":
        (done / "summary.json").unlink()
        args = ["evolve", "--resume", done]
    else:
        args = ["episode", "--genome", path]
    before = files(done)
    assert cli(*args) == 2
    one_line_error(capsys.readouterr().err, str(path), "is in format 'other/9'")
    assert files(done) == before


def test_a_run_directory_that_cannot_be_listed(tmp_path, capsys):
    d = tmp_path / "run"
    d.mkdir(mode=0o333)  # write and enter, not list
    try:
        if os.geteuid() == 0:
            if shutil.which(AS_USER[0]) is None:
                pytest.skip("root lists any directory and there is no setpriv to drop that power")
            r = subprocess.run([*AS_USER, sys.executable, "-m", "evobiped", "evolve", *RUN, "--out", str(d)],
                               capture_output=True, text=True, env={**os.environ, "PYTHONPATH": str(ROOT)})
            rc, err = r.returncode, r.stderr
        else:
            rc, err = cli("evolve", *RUN, "--out", d), capsys.readouterr().err
        assert rc == 2
        one_line_error(err, f"cannot write {d}: Permission denied")
    finally:
        d.chmod(0o755)


# ---- a Ray worker lost for good (its node died)
class FakeActorPool:
    """Ray's ActorPool whose results are ``outcome()`` (an exception to raise)."""

    outcome = None

    def __init__(self, actors):
        self.pending = 0

    def submit(self, fn, value):
        self.pending += 1

    def has_next(self):
        return self.pending > 0

    def get_next(self, timeout=None):
        raise self.outcome()


@pytest.mark.parametrize("how", ["node died error", "node dead while waiting"])
def test_a_lost_ray_worker_is_one_line(monkeypatch, how):
    ray = pytest.importorskip("ray")
    from types import SimpleNamespace

    from evobiped.episode import EpisodeConfig
    from evobiped.core.errors import UserError
    from evobiped.evaluation.ray_backend import RayEvaluator

    if how == "node died error":  # the result of a task on the lost node
        monkeypatch.setattr(FakeActorPool, "outcome",
                            staticmethod(lambda: ray.exceptions.NodeDiedError("the node running this actor died")))
        words = r"^Ray lost a worker \(NodeDiedError: .*resume the run with evobiped evolve --resume$"
    else:  # Ray waits for room to restart the actor: no result, ever
        monkeypatch.setattr(FakeActorPool, "outcome",
                            staticmethod(lambda: TimeoutError("Timed out waiting for result")))
        words = r"^a Ray node running this run's workers died \(1 of 2 nodes lost\); .*evobiped evolve --resume$"
    ev = RayEvaluator.__new__(RayEvaluator)  # no cluster: actors on nodes a and b, b dead
    ev.config, ev.chunk, ev.actors, ev.nodes = EpisodeConfig(seconds=0.1), None, [None, None], {"a", "b"}
    nodes = lambda: [{"NodeID": "a", "Alive": True}, {"NodeID": "b", "Alive": False}]  # noqa: E731
    ev.ray = SimpleNamespace(util=SimpleNamespace(ActorPool=FakeActorPool), exceptions=ray.exceptions, nodes=nodes)
    with pytest.raises(UserError, match=words):
        ev.evaluate(np.zeros((2, 3)))


def test_a_generation_lost_to_the_evaluator_keeps_the_run_resumable(tmp_path, capsys, monkeypatch, reference):
    """The UserError of a lost Ray node in the middle of a run: exit 2, one line, and --resume completes the run
    as if nothing had happened."""
    from evobiped.core.errors import UserError
    from evobiped.evaluation import backends as evaluate

    real = evaluate.make_evaluator

    class LosesSecondGeneration(evaluate.SerialEvaluator):
        calls = 0

        def evaluate(self, genomes, key=None):
            LosesSecondGeneration.calls += 1
            if LosesSecondGeneration.calls == 2:
                raise UserError("Ray lost a worker (NodeDiedError: ...); the last checkpoint is kept: resume the run "
                                "with evobiped evolve --resume")
            return super().evaluate(genomes, key)

    monkeypatch.setattr(evaluate, "make_evaluator", lambda episode, *a, **k: LosesSecondGeneration(episode))
    d = tmp_path / "run"
    assert cli("evolve", *RUN, "--out", d) == 2
    one_line_error(capsys.readouterr().err, "Ray lost a worker")
    assert len(json.loads((d / "checkpoint.json").read_text())["history"]) == 1
    monkeypatch.setattr(evaluate, "make_evaluator", real)
    assert cli("evolve", "--resume", d, "--quiet") == 0
    assert contents(d) == contents(reference)
