"""Numbers a command must refuse before any work (non-finite, beyond a physical or memory bound, a negative seed), and
an environment that MuJoCo's import would stop at: one line on stderr, exit status 2, nothing written, no traceback.
The cases are :data:`tests.fault_cases.NUMBERS`, which the release campaign runs too."""

import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

from .conftest import ROOT, cli
from .fault_cases import NUMBERS, number_case
from .test_faults import one_line_error


@pytest.mark.parametrize("name", list(NUMBERS))
def test_a_number_beyond_its_bound_is_one_line_before_any_work(tmp_path, capsys, name):
    args, words = number_case(name, ROOT, tmp_path)
    t0 = time.perf_counter()
    assert cli(*args) == 2
    one_line_error(capsys.readouterr().err, words)
    assert time.perf_counter() - t0 < 20, "refused only after work"
    assert not list(tmp_path.iterdir()) and not list(Path.cwd().iterdir()), "something was written"


@pytest.mark.parametrize("value", ["-1e3", "-10", "-.5"])
def test_a_negative_number_is_a_value_not_a_flag(tmp_path, capsys, value):
    out = tmp_path / "out.json"
    assert cli("genome", "ranges", WALKER, out, "--block", "weights", value, "1e3") in (0, 2)
    err = capsys.readouterr().err
    assert "expected 3 arguments" not in err and "unrecognized" not in err, err


WALKER = ROOT / "docs" / "walkers" / "ctrnn_walk_seed1.json"


def _run(*args, env: dict) -> subprocess.CompletedProcess:
    e = {k: v for k, v in os.environ.items() if k != "MUJOCO_GL"}
    return subprocess.run([sys.executable, "-m", "evobiped", *map(str, args)], capture_output=True, text=True,
                          timeout=120, env={**e, "PYTHONPATH": str(ROOT), **env})


@pytest.mark.parametrize("value", ["osmesa-not-a-backend", "bogus", "EGL "])
def test_a_command_that_renders_nothing_runs_whatever_mujoco_gl_says(value):
    r = _run("presets", env={"MUJOCO_GL": value})
    assert r.returncode == 0 and "Traceback" not in r.stderr and "walker-ctrnn" in r.stdout, r.stderr


def test_a_mujoco_gl_mujoco_rejects_is_one_line_naming_the_fix_when_rendering(tmp_path):
    r = _run("replay", WALKER, "--seconds", "0.2", "--video", tmp_path / "v.mp4", "--out", tmp_path / "r.rrd",
             env={"MUJOCO_GL": "bogus"})
    assert r.returncode == 2, r.stderr
    one_line_error(r.stderr, "MUJOCO_GL=bogus cannot be used here", "unset MUJOCO_GL")
    assert not list(tmp_path.iterdir())


def test_a_missing_headless_library_is_set_aside():
    from evobiped.core.glbackend import rejected

    assert rejected("osmesa", "linux", loadable=lambda names: False) == "libOSMesa.so.8 does not load"
    assert rejected("osmesa", "linux", loadable=lambda names: True) is None
    assert rejected("egl", "linux", loadable=lambda names: True) is None and rejected("glfw", "linux") is None
    assert "MuJoCo takes" in rejected("wgl", "linux") and rejected("wgl", "win32") is None


# ---- the project's exceptions cross process boundaries (a pool's worker to the command)
def _exception_classes() -> list[type]:
    import importlib
    import pkgutil

    import evobiped

    for m in pkgutil.walk_packages(evobiped.__path__, "evobiped."):
        if not m.name.endswith("__main__"):
            importlib.import_module(m.name)
    found, todo = set(), [BaseException]
    while todo:
        for c in todo.pop().__subclasses__():
            todo.append(c)
            if c.__module__.startswith("evobiped."):
                found.add(c)
    return sorted(found, key=lambda c: c.__qualname__)


def _instance(cls: type) -> BaseException:
    import inspect
    import signal

    params = [p for p in inspect.signature(cls.__init__).parameters.values() if p.name != "self"
              and p.default is p.empty]
    if cls.__name__ == "Interrupted":
        return cls(signal.SIGTERM)
    if [p.name for p in params] == ["path", "exc"]:
        return cls("/full/disk/f.json", OSError(28, "No space left on device"))
    return cls("a reason")


def test_every_exception_of_the_project_pickles_round_trip():
    import pickle

    classes = _exception_classes()
    assert {"UserError", "ConfigError", "GenomeError", "WriteError", "Interrupted"} <= {c.__name__ for c in classes}
    for cls in classes:
        exc = _instance(cls)
        back = pickle.loads(pickle.dumps(exc))
        assert type(back) is cls and str(back) == str(exc) and vars(back) == vars(exc), cls


@pytest.mark.parametrize("files", [12, 14])  # 12: the pool cannot start; 14: its workers die of too few
def test_too_few_file_descriptors_for_the_pool_is_one_line(tmp_path, files):
    import resource

    def few():
        resource.setrlimit(resource.RLIMIT_NOFILE, (files, resource.getrlimit(resource.RLIMIT_NOFILE)[1]))

    r = subprocess.run([sys.executable, "-m", "evobiped", "evolve", "--population", "4", "--generations", "2",
                        "--seconds", "0.5",
                        "--backend", "process", "--workers", "2", "--quiet", "--out", str(tmp_path / "run")],
                       capture_output=True,
                       text=True, timeout=120, env={**os.environ, "PYTHONPATH": str(ROOT)}, preexec_fn=few)
    assert r.returncode == 2, r.stderr
    one_line_error("".join(x for x in r.stderr.splitlines(True) if not x.startswith("evobiped: a worker died")),
                   "too many open files", "ulimit -n")


def test_mujocos_warnings_leave_no_log_file_in_the_current_folder(tmp_path):
    code = ("import mujoco\nfrom evobiped.physics.models import load_model, models_dir\n"
            "m = load_model(models_dir() / 'reil_biped.xml'); d = mujoco.MjData(m); d.qvel[:] = 1e300; "
            "mujoco.mj_step(m, d)\nassert d.warning[mujoco.mjtWarning.mjWARN_BADQVEL].number == 1\n")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60, cwd=tmp_path,
                       env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert r.returncode == 0 and "The simulation is unstable" in r.stderr, r.stderr
    assert not list(tmp_path.iterdir()), "MuJoCo's log in the current folder"
