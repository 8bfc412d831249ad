"""The experiments' outputs as one set (``taga --reproduce``, ``g3 --reproduce``, ``g3 --out``): a kill between two of
their files never leaves a new file beside an old one of the previous run, and the next run says it was cut short."""

import os
import signal
import subprocess
import sys
from pathlib import Path

from evobiped.experiments.g3.g3_reproduce import g3_outputs
from evobiped.experiments.taga.taga_reproduce import taga_outputs

from .conftest import ROOT

OLD = b"the previous run's"


def _run(*args, kill_at: int | None = None) -> subprocess.CompletedProcess:
    """``evobiped ARGS``, SIGKILLed just before its ``kill_at``-th rename where given."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    if kill_at:
        env["EVOBIPED_FAULT_KILL_AT_REPLACE"] = str(kill_at)
    return subprocess.run([sys.executable, "-m", "evobiped", *map(str, args)], capture_output=True, text=True, env=env,
                          timeout=300)


def _old_set(files: list[Path]) -> None:
    files[0].parent.mkdir(parents=True, exist_ok=True)
    for f in files:
        f.write_bytes(OLD)


def _left(d: Path) -> list[str]:
    """A set's mark or a temporary left in ``d``."""
    return sorted(p.name for p in d.iterdir() if p.name.endswith((".incomplete", ".tmp")))


def test_a_g3_out_killed_between_its_figures_leaves_no_old_figure_beside_a_new_one(tmp_path):
    d = tmp_path / "g3"
    assert _run("g3", "fig4", "--out", d).returncode == 0  # one level: its run and its diagram
    assert sorted(p.name for p in d.iterdir()) == ["g3_fig4_diagrams.png", "g3_fig4_run.png"]
    sweep = ["g3", "fig4", "--go", "0.1", "0.2", "--out", d]  # two levels: the diagrams and the frequency plot
    r = _run(*sweep, kill_at=3)  # the mark, the diagrams, then killed at the frequency plot's rename
    assert not (d / "g3_fig4_run.png").exists(), "the previous run's figure beside the new diagrams"
    assert r.returncode == -signal.SIGKILL, r.stderr
    r = _run(*sweep)
    assert r.returncode == 0 and "the previous g3 fig4 was cut short" in r.stderr, r.stderr
    written = sorted(p.name for p in d.iterdir())
    assert written == ["g3_fig4_diagrams.png", "g3_fig4_frequency.png"], f"a mark or temporary: {written}"


def test_a_g3_reproduction_killed_between_its_files_leaves_none_of_the_previous_one(tmp_path):
    d = tmp_path / "r"
    _old_set(g3_outputs(d))
    reproduce = ["g3", "--reproduce", d, "--step", "0.25", "--t-run", "40"]
    r = _run(*reproduce, kill_at=3)  # the mark, claim 1's figure, then killed at claim 2's table
    assert r.returncode == -signal.SIGKILL, r.stderr
    kept = [p.name for p in g3_outputs(d) if p.exists()]
    assert kept == ["claim1_fig4_walk.png"], f"the previous reproduction's files beside the new one: {kept}"
    assert (d / kept[0]).read_bytes() != OLD
    r = _run(*reproduce)
    assert r.returncode == 0 and "the previous g3 reproduction was cut short" in r.stderr, r.stderr
    written, the_set = {p.name for p in d.iterdir()}, {p.name for p in g3_outputs(d)}
    assert written <= the_set, f"files outside the set: {written - the_set}"
    assert "summary.json" in written and not _left(d)


def test_a_taga_reproduction_killed_between_its_figures_leaves_none_of_the_previous_one(tmp_path):
    d = tmp_path / "r"
    _old_set(taga_outputs(d))
    reproduce = ["taga", "--reproduce", d, "--quick", "--quiet"]
    r = _run(*reproduce, kill_at=3)  # the mark, Fig. 5A, then killed at Fig. 5B's rename
    assert r.returncode == -signal.SIGKILL, r.stderr
    kept = [p.name for p in taga_outputs(d) if p.exists()]
    assert kept == ["fig5a_walk_u5.5.png"], f"the previous reproduction's files beside the new one: {kept}"
    assert (d / kept[0]).read_bytes() != OLD
    r = _run(*reproduce, kill_at=1)  # the next run says so before it writes its mark
    assert r.returncode == -signal.SIGKILL and "the previous taga reproduction was cut short" in r.stderr, r.stderr
    assert not [p for p in taga_outputs(d) if p.exists()]
