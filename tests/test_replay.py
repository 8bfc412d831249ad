"""``evobiped replay``: run directories and genome files, bit-exact fitness, bad sources.

The run directory comes from a real ``evobiped evolve`` run whose genomes were
evaluated in batches in worker processes; the replay simulates one genome alone.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from evobiped.cli import main
from evobiped.episode import EpisodeConfig
from evobiped.files.genome_file import save_genome

from .conftest import random_genomes

pytest.importorskip("rerun")

SECONDS = 2.0


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    """A real (small) `evobiped evolve` run: 2 worker processes, each evaluating batches of genomes."""
    run = tmp_path_factory.mktemp("runs") / "run"
    args = ["evolve", "--population", "8", "--generations", "3", "--episode-seconds", str(SECONDS), "--seed", "7",
            "--backend", "process", "--workers", "2", "--out", str(run), "--quiet"]
    assert main(args) == 0
    return run


def stored(path):
    return json.loads(path.read_text())["fitness"]


def replayed(out: str) -> float:
    line = next(l for l in out.splitlines() if l.startswith("replayed fitness = "))
    return float(line.split("= ")[1].split(" ")[0].rstrip(";:"))


def test_replay_of_a_run_directory_reproduces_the_stored_fitness_bit_for_bit(run_dir, capsys):
    assert main(["replay", str(run_dir)]) == 0
    out = capsys.readouterr().out
    assert replayed(out) == stored(run_dir / "best.json")
    assert "equals it bit for bit" in out
    assert (run_dir / "replay_best.rrd").stat().st_size > 10_000
    assert not list(run_dir.glob(".*tmp"))


def test_replay_of_each_generation(run_dir, capsys):
    for gen in range(3):
        assert main(["replay", str(run_dir), "--generation", str(gen)]) == 0
        out = capsys.readouterr().out
        assert replayed(out) == stored(run_dir / "generations" / f"gen_{gen:04d}.json")
        assert (run_dir / f"replay_gen_{gen:04d}.rrd").is_file()


def test_run_directory_recording_holds_the_evolution_and_figures(run_dir, tmp_path, capsys):
    import rerun as rr

    out = tmp_path / "r.rrd"
    assert main(["replay", str(run_dir), "--out", str(out), "--figures", str(tmp_path / "figs")]) == 0
    best = {}
    for c in rr.chunk.RrdReader(out).stream():
        if c.entity_path == "/evolution/best" and not c.is_static:
            rb = c.to_record_batch()
            best.update(zip(rb.column("generation").to_pylist(),
                            (v[0] for v in rb.column("Scalars:scalars").to_pylist())))
    history = np.loadtxt(run_dir / "history.csv", delimiter=",", skiprows=1)
    assert best == {int(g): b for g, b in history[:, :2]}
    names = sorted(p.name for p in (tmp_path / "figs").iterdir())
    assert names == ["fitness.png", "footfalls.png", "ground_trajectory.png", "motion_sequence.png",
                     "motor_neurons.png", "stick_figure.png"]


def test_replay_of_a_genome_file_writes_under_runs_not_beside_it(tmp_path, capsys):
    """A genome file may sit in a repository: the default recording goes to ./runs/<stem>/, not beside it."""
    from pathlib import Path

    cfg = EpisodeConfig(seconds=1.0)
    ep = cfg.build()
    g = random_genomes(ep.controller.layout, 1, seed=3)[0]
    r = ep.run(g)
    (tmp_path / "repo").mkdir()
    save_genome(tmp_path / "repo" / "walker.json", g, cfg, fitness=r.fitness[0])
    assert main(["replay", str(tmp_path / "repo" / "walker.json"), "--figures"]) == 0
    out = capsys.readouterr().out
    assert replayed(out) == r.fitness[0]
    assert sorted(p.name for p in (tmp_path / "repo").iterdir()) == ["walker.json"]
    assert (Path.cwd() / "runs" / "walker" / "replay_walker.rrd").is_file()
    assert (Path.cwd() / "runs" / "walker" / "figures_walker" / "ground_trajectory.png").is_file()
    # a shorter replay is not compared with the stored fitness
    assert main(["replay", str(tmp_path / "repo" / "walker.json"), "--seconds", "0.1", "--out",
                 str(tmp_path / "short.rrd")]) == 0
    assert "not compared" in capsys.readouterr().out


def test_a_different_stored_fitness_is_reported_and_fails(tmp_path, capsys):
    cfg = EpisodeConfig(seconds=1.0)
    ep = cfg.build()
    g = random_genomes(ep.controller.layout, 1, seed=3)[0]
    save_genome(tmp_path / "w.json", g, cfg, fitness=float(ep.run(g).fitness[0]) + 1e-12)
    assert main(["replay", str(tmp_path / "w.json")]) == 1
    assert "DIFFERS by" in capsys.readouterr().out


def _walker_file(path, *, environment=None, outcome_change=None, fitness_change=0.0):
    """A shipped walker copied to ``path`` with its recorded environment, outcome and fitness altered."""
    from evobiped.files.genome_file import load_genome

    from .conftest import WALKERS

    g, cfg, meta = load_genome(WALKERS / "simbicon_cma_seed5.json")
    r = cfg.build().run(g)
    from evobiped.files.outcome import outcome

    done = outcome(r)
    if outcome_change:
        done["rows"][0].update(outcome_change)
    save_genome(path, g, cfg, fitness=float(r.fitness[0]) + fitness_change, fell=False, end_time=50.0, outcome=done)
    if environment is not None:
        obj = json.loads(path.read_text())
        obj["environment"].update(environment)
        path.write_text(json.dumps(obj))


def test_a_replay_in_another_numerical_environment_reports_the_drift_and_checks_the_outcome(tmp_path, capsys):
    """Recorded under other numpy kernels: a fitness 1e-9 off is drift, not failure (exit 0) while the outcome
    holds; an outcome 5 m and 10 deg away from the replay's is a failure (exit 1)."""
    _walker_file(tmp_path / "w.json", environment={"numpy_simd": ["SOME_OTHER_KERNELS"]}, fitness_change=1e-9)
    assert main(["replay", str(tmp_path / "w.json"), "--quiet", "--out", str(tmp_path / "w.rrd")]) == 0
    out = capsys.readouterr().out
    assert "numerical environment differs from the stored one: numpy SIMD SOME_OTHER_KERNELS -> " in out
    assert "drift -1e-09" in out and "outcome holds within the declared tolerance" in out
    assert "up 50 s (as stored)" in out
    _walker_file(tmp_path / "far.json", environment={"numpy_simd": ["SOME_OTHER_KERNELS"]},
                 outcome_change={"distance": 33.0})
    assert main(["replay", str(tmp_path / "far.json"), "--quiet", "--out", str(tmp_path / "w.rrd")]) == 1
    assert "outcome DIFFERS: distance 38.63 m, stored 33.00 m (allowed +-1.65 m)" in capsys.readouterr().out
    # in the recorded environment the same 1e-9 is a failure: bit for bit is promised there
    _walker_file(tmp_path / "same.json", fitness_change=1e-9)
    assert main(["replay", str(tmp_path / "same.json"), "--quiet", "--out", str(tmp_path / "w.rrd")]) == 1
    assert "DIFFERS by -1e-09" in capsys.readouterr().out


def test_every_written_file_records_its_numerical_environment(run_dir):
    """config.json and every genome file of a run: versions, numpy's SIMD kernels, the machine."""
    from evobiped.core import provenance

    here = provenance.current()
    for path in [run_dir / "config.json", run_dir / "best.json", *sorted((run_dir / "generations").glob("*.json"))]:
        env = json.loads(path.read_text())["environment"]
        assert env == json.loads(json.dumps(here)), path
        assert set(env) >= {"evobiped", "python", "mujoco", "numpy", "numpy_simd", "machine", "system"}


def _bad_sources(tmp_path, run_dir):
    ep = EpisodeConfig(seconds=1.0).build()
    short = tmp_path / "short.json"
    save_genome(short, np.zeros(ep.controller.layout.size - 3), EpisodeConfig(seconds=1.0), fitness=0.0)
    (tmp_path / "notgenome.json").write_text(json.dumps({"hello": 1}))
    (tmp_path / "garbage.json").write_text("{not json")
    (tmp_path / "emptydir").mkdir()
    return {
        "missing": ([str(tmp_path / "nope")], "no such run directory"),
        "not a run dir": ([str(tmp_path / "emptydir")], "no best.json"),
        "wrong size": ([str(short)], "genes, the layout needs 120"),
        "not a genome": ([str(tmp_path / "notgenome.json")], "not an evobiped genome file"),
        "not json": ([str(tmp_path / "garbage.json")], "not valid JSON"),
        "no such generation": ([str(run_dir), "--generation", "9"], "no generation 9 (generations saved: 0000..0002)"),
        "generation of a file": ([str(short), "--generation", "1"], "--generation needs a run directory"),
    }


def test_bad_sources_give_one_line_exit_2_and_write_nothing(tmp_path, run_dir, capsys):
    cases = _bad_sources(tmp_path, run_dir)
    before = {p: sorted(x.name for x in p.iterdir()) for p in (tmp_path, run_dir)}
    for name, (args, message) in cases.items():
        assert main(["replay", *args]) == 2, name
        cap = capsys.readouterr()
        lines = cap.err.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("evobiped: error: "), (name, cap.err)
        assert message in lines[0], (name, lines[0])
        assert cap.out == ""
    after = {p: sorted(x.name for x in p.iterdir()) for p in (tmp_path, run_dir)}
    assert after == before


def test_connect_to_an_absent_viewer_is_one_line_exit_2(tmp_path, run_dir, capsys):
    import socket

    with socket.socket() as s:  # a free port that nothing listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    assert main(["replay", str(run_dir / "best.json"), "--connect", f"127.0.0.1:{port}"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"no Rerun viewer at 127.0.0.1:{port}" in err[0]


def test_spawn_streams_to_a_new_viewer_and_writes_no_file(tmp_path, monkeypatch, capsys):
    import rerun as rr

    calls = []
    monkeypatch.setenv("DISPLAY", ":0")
    monkeypatch.setattr(rr.RecordingStream, "spawn", lambda self, **kw: calls.append(kw) or self.memory_recording())
    cfg = EpisodeConfig(seconds=0.5)
    g = random_genomes(cfg.build().controller.layout, 1, seed=3)[0]
    save_genome(tmp_path / "w.json", g, cfg, fitness=cfg.build().run(g).fitness[0])
    assert main(["replay", str(tmp_path / "w.json"), "--spawn"]) == 0
    assert len(calls) == 1
    assert "recording streamed to the viewer" in capsys.readouterr().out
    assert sorted(p.name for p in tmp_path.iterdir()) == ["w.json"]


def test_the_report_says_why_a_stored_fitness_is_not_compared(tmp_path):
    """ReplayReport.not_compared: None for the stored episode; --seconds, --source (a steering walker's sources) and a
    fitness aggregated over perturbed presentations each say so; the command prints the report's words."""
    from evobiped.usecases.replaying import replay, stored_walker

    def reason(cfg, **kw):
        g = random_genomes(cfg.build().controller.layout, 1, seed=3)[0]
        path = tmp_path / f"w{len(list(tmp_path.glob('w*.json')))}.json"
        save_genome(path, g, cfg, fitness=1.0)
        return replay(stored_walker(path), out=tmp_path / "r.rrd", **kw).not_compared

    plain, steer = EpisodeConfig(seconds=0.3), EpisodeConfig(seconds=0.3, controller="simbicon", task="steer")
    assert reason(plain) is None
    assert reason(plain, seconds=0.2) == "--seconds changed the episode length"
    assert reason(steer, sources=[[5.0, 1.0], [5.0, -1.0]]) == "--source changed the sources"
    assert reason(steer, seconds=0.2, sources=[[5.0, 1.0], [5.0, -1.0]]) == "--seconds changed the episode length"
    noisy = EpisodeConfig(seconds=0.3, perturbations={"presentations": 2, "pose_noise": 0.01})
    assert reason(noisy).startswith("it is the aggregate over the perturbed presentations")
