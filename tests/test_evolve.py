"""Evolution runs: backends agree, resume equals uninterrupted, bad input, blow-ups.

Tiny populations and 1-2 s episodes keep these fast; the paper's sizes are
measured by ``evobiped bench`` and real runs.
"""

import csv
import dataclasses
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from evobiped.episode import EpisodeConfig
from evobiped.optimizers import GAOptions
from evobiped.run import Run, RunConfig
from evobiped.evaluation import make_evaluator
from evobiped.files.rundir import HISTORY_COLUMNS
from evobiped.run.run_context import HISTORY_EXTRA, STOP_COLUMN

from .conftest import cli

SMALL = RunConfig(episode=EpisodeConfig(seconds=1.5), optimizer_options={"ga": GAOptions(population=8)}, generations=3,
                  seed=7, backend="serial")


def fitness_history(run_dir) -> list[list[str]]:
    """history.csv without the wall-clock column (the best's terms after the fixed columns)."""
    with open(Path(run_dir) / "history.csv") as f:
        rows = list(csv.reader(f))
    assert rows[0][: len(HISTORY_COLUMNS)] == list(HISTORY_COLUMNS)
    assert all(c.startswith("best_") or c in HISTORY_EXTRA + (STOP_COLUMN,) for c in rows[0][len(HISTORY_COLUMNS) :])
    wall = HISTORY_COLUMNS.index("wall_seconds")
    return [r[:wall] + r[wall + 1 :] for r in rows[1:]]


def evolve_with(tmp_path, name, backend, workers=None, config=SMALL):
    run = Run.create(tmp_path / name, config)
    with make_evaluator(config.episode, backend, workers) as ev:
        run.evolve(ev)
    return fitness_history(run.dir), json.loads((run.dir / "best.json").read_text())


def test_history_identical_on_every_backend(tmp_path):
    """Seeds come from (run seed, generation, index): serial = 1 worker = 2 workers = 3 threads = Ray."""
    ref, best = evolve_with(tmp_path, "serial", "serial")
    assert len(ref) == SMALL.generations
    assert float(ref[-1][1]) > 0  # somebody moved
    runs = [evolve_with(tmp_path, "p1", "process", 1), evolve_with(tmp_path, "p2", "process", 2),
            evolve_with(tmp_path, "t3", "thread", 3)]
    pytest.importorskip("ray")
    runs.append(evolve_with(tmp_path, "ray", "ray", 2))
    for hist, b in runs:
        assert hist == ref
        assert b["genome"] == best["genome"] and b["fitness"] == best["fitness"]


def test_batches_join_into_one_episode_result():
    """The thread backend, one genome per batch, gives the one-batch EpisodeResult field for field,
    the per-presentation rows of a two-source steer task included."""
    import dataclasses

    from evobiped.evaluation import SerialEvaluator, ThreadEvaluator

    cfg = EpisodeConfig(task="steer", seconds=0.6)
    rng = np.random.default_rng(3)
    lay = cfg.build().controller.layout
    genomes = np.clip(rng.normal(lay.init_mean, lay.init_sigma, (3, lay.size)), lay.low, lay.high)
    with SerialEvaluator(cfg) as one, ThreadEvaluator(cfg, 2, chunk=1) as many:
        a, b = one.evaluate(genomes), many.evaluate(genomes)
    assert a.rows is not None and len(a.rows.fitness) == 6 and len(b.rows.fitness) == 6
    assert b.end_position.shape == (3, 2, 2)

    def same(x, y, where):
        if dataclasses.is_dataclass(x):
            for f in dataclasses.fields(x):
                same(getattr(x, f.name), getattr(y, f.name), f"{where}.{f.name}")
        elif isinstance(x, dict):
            assert x.keys() == y.keys(), where
            for k in x:
                same(x[k], y[k], f"{where}[{k!r}]")
        elif x is None:
            assert y is None, where
        else:
            assert np.array_equal(x, y, equal_nan=True), where

    same(a, b, "result")


class Stop(Exception):
    pass


def whole_and_resumed(tmp_path, config, stop_after: int = 1) -> tuple[Run, Path]:
    """``config`` run uninterrupted (serially), and again stopped after generation ``stop_after`` and resumed on two
    worker processes: (the whole run, the resumed run's directory)."""
    whole = Run.create(tmp_path / "whole", config)
    with make_evaluator(config.episode, "serial") as ev:
        whole.evolve(ev)
    cut = Run.create(tmp_path / "cut", config)

    def stop(stats):
        if stats.generation == stop_after:
            raise Stop

    with make_evaluator(config.episode, "serial") as ev, pytest.raises(Stop):
        cut.evolve(ev, stop)
    assert len(fitness_history(cut.dir)) == stop_after + 1
    resumed = Run.resume(cut.dir)
    with make_evaluator(config.episode, "process", 2) as ev:
        resumed.evolve(ev)
    return whole, cut.dir


def test_resume_equals_uninterrupted(tmp_path):
    config = RunConfig(**{**SMALL.__dict__, "generations": 5})
    ref, ref_best = evolve_with(tmp_path, "whole", "serial", config=config)

    run = Run.create(tmp_path / "cut", config)

    def stop_after_two(stats):
        if stats.generation == 1:
            raise Stop

    with make_evaluator(config.episode, "serial") as ev, pytest.raises(Stop):
        run.evolve(ev, stop_after_two)
    assert len(fitness_history(run.dir)) == 2 and not (run.dir / "summary.json").exists()
    resumed = Run.resume(run.dir)
    assert resumed.optimizer.generation == 2
    with make_evaluator(config.episode, "process", 2) as ev:
        summary = resumed.evolve(ev)
    assert fitness_history(run.dir) == ref
    best = json.loads((run.dir / "best.json").read_text())
    assert best["genome"] == ref_best["genome"] and summary["best"]["fitness"] == ref_best["fitness"]
    assert sorted(p.name for p in (run.dir / "generations").iterdir()) == [f"gen_{g:04d}.json" for g in range(5)]


def test_the_optimizer_state_is_a_frozen_value(tmp_path):
    """The GA's state is a value: read-only arrays that later generations leave alone; restored into a fresh
    GA, it asks the same and both continue alike."""
    from evobiped.run.run_config import make_optimizer

    run = Run.create(tmp_path / "r", SMALL)
    with make_evaluator(SMALL.episode, "serial") as ev:
        run.step(ev)
        state = run.optimizer.state()
        kept = state.population.copy()
        with pytest.raises(ValueError):
            state.population[0, 0] = 0.0
        with pytest.raises(dataclasses.FrozenInstanceError):
            state.generation = 5
        other = make_optimizer(SMALL)
        other.restore(other.state_from(json.loads(json.dumps(state.to_dict()))))
        assert other.generation == 1 and np.array_equal(other.ask()[0], run.optimizer.ask()[0])
        run.step(ev)
    assert np.array_equal(state.population, kept) and state.generation == 1 and run.optimizer.generation == 2


def test_a_checkpoint_of_before_the_optimizer_key_resumes_bit_identically(tmp_path):
    """Checkpoints written before the state was named ``optimizer`` kept it under ``ga`` (its name under
    ``optimizer``): such a run resumes exactly as an uninterrupted one."""
    config = RunConfig(**{**SMALL.__dict__, "generations": 3})
    ref, ref_best = evolve_with(tmp_path, "whole", "serial", config=config)
    run = Run.create(tmp_path / "old", config)
    with make_evaluator(config.episode, "serial") as ev:
        run.step(ev)
        run.checkpoint()
    path = run.dir / "checkpoint.json"
    ck = json.loads(path.read_text())
    del ck["format"]  # written before the format was
    state = ck.pop("optimizer")
    state["optimizer"] = state.pop("name")
    path.write_text(json.dumps({"ga": state, **ck}))
    run.close()
    resumed = Run.resume(run.dir)
    with make_evaluator(config.episode, "serial") as ev:
        resumed.evolve(ev)
    assert fitness_history(run.dir) == ref
    assert json.loads((run.dir / "best.json").read_text())["genome"] == ref_best["genome"]
    assert "optimizer" in json.loads(path.read_text())  # the next commit writes the current key


def test_resume_discards_files_of_an_unfinished_generation(tmp_path):
    """A kill between a generation's genome files and its checkpoint leaves no trace after resume."""
    run = Run.create(tmp_path / "r", SMALL)
    with make_evaluator(SMALL.episode, "serial") as ev:
        run.step(ev)
        run.checkpoint()
        kept = (run.dir / "best.json").read_text()
        run.optimizer.population[:] = run.optimizer.population[::-1]  # a different generation 1...
        run.step(ev)  # ...whose files are written, but no checkpoint
    (run.dir / "best.json").write_text(kept.replace('"generation": 0', '"generation": 1'))
    resumed = Run.resume(run.dir)
    assert not (run.dir / "generations" / "gen_0001.json").exists()
    assert (run.dir / "best.json").read_text() == kept
    assert resumed.optimizer.generation == 1



def test_individuals_jsonl_records_every_row_with_its_lineage(tmp_path):
    """individuals.jsonl: every row of every generation; a GA's survivors are the previous generation's rows of
    the same outcome, its children bred from the fittest rows before them (the truncation selection, recomputed
    here from the previous lines); each generation's fittest line is its generation file's walker; rows not yet
    evaluated are null in the checkpoint, never zeros."""
    from evobiped.files.rundir import read_individuals

    run = Run.create(tmp_path / "r", SMALL)
    with make_evaluator(SMALL.episode, "serial") as ev:
        run.evolve(ev)
    lines = read_individuals(run.dir / "individuals.jsonl")
    P, k = SMALL.options.population, SMALL.options.n_survivors
    assert [(r["generation"], r["row"]) for r in lines] == [(g, i) for g in range(SMALL.generations) for i in range(P)]
    by = [lines[g * P:(g + 1) * P] for g in range(SMALL.generations)]
    assert all(r["evaluated"] and r["previous"] is None and r["parents"] is None for r in by[0])
    outcome = ("fitness", "fell", "unstable", "end_time", "terms")
    for g in range(1, SMALL.generations):
        fittest = sorted(range(P), key=lambda i: -by[g - 1][i]["fitness"])[:k]
        survivors = [r for r in by[g] if not r["evaluated"]]
        assert [r["previous"] for r in survivors] == fittest and all(r["parents"] is None for r in survivors)
        for r in survivors:
            assert {f: r[f] for f in outcome} == {f: by[g - 1][r["previous"]][f] for f in outcome}
        children = [r for r in by[g] if r["evaluated"]]
        assert len(children) == P - k and all(r["previous"] is None and r["parents"][0] in fittest for r in children)
        assert {r["parents"][0] for r in children} == set(fittest)
    for g, rows in enumerate(by):
        best = max(rows, key=lambda r: r["fitness"])
        stored = json.loads((run.dir / "generations" / f"gen_{g:04d}.json").read_text())
        assert {f: best[f] for f in ("fitness", "fell", "end_time",
                                     "terms")} == {f: stored[f] for f in ("fitness", "fell", "end_time", "terms")}
    ck = json.loads((run.dir / "checkpoint.json").read_text())["outcome"]
    new = [i for i, r in enumerate(ck["previous"]) if r is None]
    assert len(new) == P - k and all(ck[f][i] is None for f in ("fell", "unstable", "end_time") for i in new)
    assert all(ck["terms"]["distance"][i] is None for i in new) and all(ck["end_time"][i] > 0 for i in range(P)
                                                                        if i not in new)
    # each child of the next generation is nearest, gene by gene, to the survivor that was its parent (a few mutated
    # loci)
    pop = np.array(json.loads((run.dir / "checkpoint.json").read_text())["optimizer"]["population"])
    holder = {p: j for j, p in enumerate(ck["previous"]) if p is not None}
    for i in new:
        nearest = int(np.argmin([np.sum(pop[i] != pop[j]) for j in range(k)]))
        assert nearest == holder[ck["parents"][i]]


def test_a_resume_cuts_individuals_back_to_its_committed_generations(tmp_path):
    """A crash after a generation's lines were appended (whole, or cut in the middle of a line) and before its
    commit: the resumed run's individuals.jsonl is the uninterrupted run's, byte for byte."""
    whole = Run.create(tmp_path / "whole", SMALL)
    with make_evaluator(SMALL.episode, "serial") as ev:
        whole.evolve(ev)
        cut = Run.create(tmp_path / "cut", SMALL)
        cut.step(ev)
        cut.checkpoint()
        cut.step(ev)  # generation 1's lines appended, never committed
    with (cut.dir / "individuals.jsonl").open("a") as f:
        f.write('{"generation":2,"row":0,"evalu')  # and a line cut short
    cut.close()
    resumed = Run.resume(cut.dir)
    assert any("individuals.jsonl cut back" in r for r in resumed.repairs)
    with make_evaluator(SMALL.episode, "serial") as ev:
        resumed.evolve(ev)
    assert (cut.dir / "individuals.jsonl").read_bytes() == (whole.dir / "individuals.jsonl").read_bytes()


def test_what_a_resume_keeps_of_individuals_jsonl(tmp_path):
    """The committed generations' whole lines in order are kept, from wherever the file starts (a run made before
    the file was kept starts it when resumed); a line cut short, a gap or a generation not committed ends what is
    kept; a resume that finds committed generations missing says so."""
    from evobiped.files.rundir import committed_size, individuals_text

    rows = lambda g, n: [{"generation": g, "row": i, "evaluated": True, "previous": None, "parents": None,
                          "fitness": 1.0,  # noqa: E731
                          "fell": False, "unstable": False, "end_time": 1.0, "terms": {}} for i in range(n)]
    path = tmp_path / "individuals.jsonl"
    three, four = individuals_text(rows(3, 2)), individuals_text(rows(4, 2))
    path.write_text(three + four + '{"generation":5,"ro')
    assert committed_size(path, 5) == (len(three + four), 5)
    assert committed_size(path, 4) == (len(three), 4)
    path.write_text(three + individuals_text(rows(5, 2)))
    assert committed_size(path, 9) == (len(three), 4)
    run = Run.create(tmp_path / "r", SMALL)
    with make_evaluator(SMALL.episode, "serial") as ev:
        run.evolve(ev)
    run.close()
    (run.dir / "individuals.jsonl").unlink()
    lost = f"individuals.jsonl lacks generations 0..{SMALL.generations - 1} (not in the checkpoint: lost)"
    assert lost in Run.resume(run.dir).repairs


def snapshot(d: Path) -> dict:
    return {p.relative_to(d): (p.stat().st_mtime_ns, p.read_bytes()) for p in d.rglob("*") if p.is_file()}


@pytest.fixture
def finished_run(tmp_path):
    d = tmp_path / "done"
    assert cli("evolve", "--population", 4, "--generations", 1, "--episode-seconds", 0.5, "--backend", "serial",
               "--out", d, "--quiet") == 0
    return d


BAD_FLAGS = [
    (["--body", "quadruped"], "unknown body 'quadruped'"),
    (["--controller", "lstm"], "unknown controller 'lstm'"),
    (["--task", "swim"], "unknown task 'swim'"),
    (["--backend", "mpi"], "backend: must be one of serial, process, thread, ray, got 'mpi'"),
    (["--population", "0"], "--population: must be > 0"),
    (["--generations", "-3"], "--generations: must be > 0"),
    (["--workers", "0"], "--workers: must be > 0"),
    (["--episode-seconds", "nan"], "--seconds/--episode-seconds: must be a finite number, got nan"),
    (["--seconds", "-1"], "--seconds/--episode-seconds: must be > 0, got -1"),
    (["--seed", "-1"], "seed: must be >= 0"),
    (["--population", "1"], "population"),
    (["--backend", "ray", "--address", "127.0.0.1:1"], "cannot reach a Ray cluster at 127.0.0.1:1"),
    (["--backend", "ray", "--address", "no-port"], "bad Ray address"),
    (["--from", "/nonexistent/run"], "no such run directory or genome file"),
]


@pytest.mark.parametrize("flags, words", BAD_FLAGS, ids=[" ".join(f) for f, _ in BAD_FLAGS])
def test_bad_flags_one_line_exit_2_nothing_written(tmp_path, capsys, flags, words):
    out = tmp_path / "run"
    assert cli("evolve", *flags, "--out", out, "--quiet") == 2
    err = capsys.readouterr().err
    assert words in err and err.count("\n") == 1 and "Traceback" not in err
    assert not out.exists()


BAD_TOML = [
    ("generations = [", "is not valid TOML"),
    ("generatons = 3", "generatons: unknown option (choose from episode, optimizer,"),
    ("[episode]\nbody = 'nope'", "unknown body 'nope'"),
    ("[ga]\nfittest_fraction = 1.5", "fittest_fraction"),
    ("[ga]\nmutations_per_genome = -1", "mutations_per_genome"),
    ("episode = 3", "episode: must be a table of options, got 3"),
    ("[episode.body_options]\nkp = -5", "episode.body_options.kp: must be > 0 N m/rad, got -5"),
    ("[episode.body_options]\nwheels = 4", "episode.body_options.wheels: unknown option (choose from timestep, kp,"),
    ("[episode.controller_options]\nn_neurons = 2.5", "episode.controller_options.n_neurons: must be a whole number"),
    ("[episode.task_options]\nfitness = 'far'", "episode.task_options.fitness: must be one of distance, forward"),
]


@pytest.mark.parametrize("text, words", BAD_TOML, ids=[w for _, w in BAD_TOML])
def test_bad_config_file(tmp_path, capsys, text, words):
    cfg = tmp_path / "c.toml"
    cfg.write_text(text)
    out = tmp_path / "run"
    assert cli("evolve", "--config", cfg, "--out", out, "--quiet") == 2
    err = capsys.readouterr().err
    assert words in err and err.count("\n") == 1
    assert not out.exists()


def test_flags_override_config_file(tmp_path):
    cfg = tmp_path / "c.toml"
    cfg.write_text("generations = 9\nseed = 3\n[ga]\npopulation = 6\n[episode]\nseconds = 0.5\n")
    out = tmp_path / "run"
    assert cli("evolve", "--config", cfg, "--generations", 1, "--backend", "serial", "--out", out, "--quiet") == 0
    saved = json.loads((out / "config.json").read_text())
    assert (saved["generations"], saved["seed"], saved["ga"]["population"],
            saved["episode"]["seconds"]) == (1, 3, 6, 0.5)
    assert len(fitness_history(out)) == 1


def test_existing_run_directory_is_left_untouched(finished_run, capsys):
    before = snapshot(finished_run)
    assert cli("evolve", "--generations", 1, "--out", finished_run, "--quiet") == 2
    assert "already holds a run (continue it with --resume" in capsys.readouterr().err
    assert snapshot(finished_run) == before


def test_no_worker_starts_before_the_run_directory_and_the_start_genome_are_checked(
    finished_run, tmp_path, monkeypatch, capsys):
    """The evolve use case checks everything, creates or resumes the run, and only then starts the evaluator (the
    process pool); an evaluator that cannot start removes the new run again."""
    from evobiped.core.errors import UserError
    from evobiped.evaluation import backends as evaluate

    started = []
    monkeypatch.setattr(evaluate, "make_evaluator", lambda *a, **k: started.append(a)
                        or pytest.fail("a worker started"))
    for flags, words in ((["--out", finished_run], "already holds a run"),
                         (["--from", tmp_path / "gone.json", "--out", tmp_path / "x"],
                                                                               "no such run directory or genome file")):
        assert cli("evolve", "--generations", 1, "--backend", "process", "--workers", 2, *flags, "--quiet") == 2
        assert words in capsys.readouterr().err and not started
    assert not (tmp_path / "x").exists()

    def fails(*a, **k):
        started.append(a)
        raise UserError("cannot start the workers")

    monkeypatch.setattr(evaluate, "make_evaluator", fails)
    assert cli("evolve", "--generations", 1, "--population", 4, "--backend", "process", "--workers", 2, "--out",
               tmp_path / "y", "--quiet") == 2
    assert "cannot start the workers" in capsys.readouterr().err and len(started) == 1
    assert not (tmp_path / "y").exists()  # the run it had created is gone: the same --out works again


@pytest.mark.parametrize(
    "damage, words",
    [
        (lambda d: (d / "checkpoint.json").write_text('{"ga": {"generation": 1, "popul'), "not valid JSON"),
        (lambda d: (d / "checkpoint.json").write_text('{"ga": {}, "history": []}'), "malformed"),
        (lambda d: (d / "config.json").write_text('{"generations": "many"}'), "generations: must be a whole number"),
        (lambda d: (d / "config.json").unlink(), "run config not found"),
    ],
    ids=["truncated checkpoint", "checkpoint without state", "bad config", "no config"],
)
def test_damaged_run_directory_on_resume(finished_run, capsys, damage, words):
    damage(finished_run)
    before = snapshot(finished_run)
    assert cli("evolve", "--resume", finished_run) == 2
    err = capsys.readouterr().err
    assert words in err and err.count("\n") == 1
    assert snapshot(finished_run) == before


def test_mismatched_checkpoint(finished_run, capsys):
    """A checkpoint from a run with another population size does not load: config.json's edit is named; a checkpoint
    of before the settings were recorded meets the optimizer's own check."""
    cfg = json.loads((finished_run / "config.json").read_text())
    cfg["ga"]["population"] = 6
    (finished_run / "config.json").write_text(json.dumps(cfg))
    assert cli("evolve", "--resume", finished_run) == 2
    differs = "config.json differs from the one this checkpoint was made with: ga.population 4 → 6"
    assert differs in capsys.readouterr().err
    ck = json.loads((finished_run / "checkpoint.json").read_text())
    older = {k: v for k, v in ck.items() if k not in ("settings", "start", "format")}
    (finished_run / "checkpoint.json").write_text(json.dumps(older))
    assert cli("evolve", "--resume", finished_run) == 2
    assert "checkpoint population has shape (4, 120), the config needs (6, 120)" in capsys.readouterr().err


def test_resume_of_a_complete_run_changes_nothing(finished_run, capsys):
    before = snapshot(finished_run)
    assert cli("evolve", "--resume", finished_run) == 0
    assert "already complete" in capsys.readouterr().out
    assert snapshot(finished_run) == before


def test_unstable_simulation_scores_as_a_fall(tmp_path):
    """PD gains far beyond what the 20 ms step can integrate blow every walker up: the run goes on."""
    cfg = RunConfig(
        episode=EpisodeConfig(seconds=1.0, body_options={"timestep": 0.02, "kp": 1e6, "kv": 0.0}),
        optimizer_options={"ga": GAOptions(population=6)},
        generations=2,
        backend="serial",
    )
    run = Run.create(tmp_path / "r", cfg)
    with make_evaluator(cfg.episode, "serial") as ev:
        summary = run.evolve(ev)
    rows = [dict(zip(HISTORY_COLUMNS, map(float, r))) for r in run.record.history]
    assert rows[0]["unstable"] > 0 and rows[0]["falls"] >= rows[0]["unstable"]
    assert all(np.isfinite([r["best"], r["mean"], r["worst"]]).all() for r in rows)
    assert summary["generations"] == 2 and summary["best"]["fell"]


def test_ctrl_c_stops_at_a_generation_boundary_and_resumes(tmp_path):
    """SIGINT to a real `evobiped evolve`: exit 130, a valid checkpoint, and --resume finishes the same history."""
    cfg = tmp_path / "c.toml"
    # no early ends: ~0.2 s per generation
    cfg.write_text("[episode.body_options]\nfall_height = 0.01\nfall_tilt = 3.14159\n")
    args = ["--config", str(cfg), "--population", "6", "--generations", "12", "--episode-seconds", "3", "--seed", "4",
            "--backend", "serial"]
    ref = tmp_path / "ref"
    assert cli("evolve", *args, "--out", ref, "--quiet") == 0
    cut = tmp_path / "cut"
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    # Ctrl-C as a terminal delivers it, even when this test runs in a background job (which ignores SIGINT, and children
    # inherit that)
    proc = subprocess.Popen([sys.executable, "-m", "evobiped.cli", "evolve", *args, "--out", str(cut)],
                            stderr=subprocess.PIPE, text=True, env=env,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    deadline = time.time() + 60
    while time.time() < deadline and not (cut / "checkpoint.json").exists():
        time.sleep(0.05)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    if proc.returncode == 0:
        pytest.skip("the run finished before the signal arrived")
    assert proc.returncode == 130, err
    assert "Traceback" not in err and f"evobiped evolve --resume {cut}" in err
    done = len(json.loads((cut / "checkpoint.json").read_text())["history"])
    assert 1 <= done < 12 and len(fitness_history(cut)) == done
    # generations are numbered from 0 everywhere: the last one the message names is the last row of history.csv
    assert f"interrupted after generation {done - 1} " in err and fitness_history(cut)[-1][0] == str(done - 1)
    assert cli("evolve", "--resume", cut, "--quiet") == 0
    assert fitness_history(cut) == fitness_history(ref)
    # the run's own recording, restarted on resume with the history so far, holds every generation
    best = {int(r[0]): float(r[1]) for r in fitness_history(ref)}
    assert rerun_series(cut / "evolution.rrd", "/evolution/best") == best
    assert rerun_series(ref / "evolution.rrd", "/evolution/best") == best


def rerun_series(path, entity) -> dict[int, float]:
    rr = pytest.importorskip("rerun")
    out = {}
    for c in rr.chunk.RrdReader(path).stream():
        if c.entity_path == entity and not c.is_static:
            rb = c.to_record_batch()
            out.update(zip(rb.column("generation").to_pylist(),
                           (v[0] for v in rb.column("Scalars:scalars").to_pylist())))
    return out


def test_a_resume_in_another_numerical_environment_says_so(tmp_path, capsys):
    """config.json records where the run started; a resume elsewhere notes that bit-identity ends there."""
    from evobiped.cli import main

    run = tmp_path / "run"
    assert main(["evolve", "--population", "4", "--generations", "1", "--episode-seconds", "0.2", "--backend", "serial",
                 "--out", str(run), "--quiet"]) == 0
    assert main(["evolve", "--resume", str(run)]) == 0
    assert "numerical environment" not in capsys.readouterr().err
    cfg = json.loads((run / "config.json").read_text())
    cfg["environment"]["numpy_simd"] = ["ELSEWHERE"]
    (run / "config.json").write_text(json.dumps(cfg))
    assert main(["evolve", "--resume", str(run)]) == 2  # config.json alone edited: refused by name
    assert 'environment.numpy_simd ' in capsys.readouterr().err
    ck = json.loads((run / "checkpoint.json").read_text())  # a run that did start elsewhere recorded it there too
    ck["settings"]["environment"]["numpy_simd"] = ["ELSEWHERE"]
    (run / "checkpoint.json").write_text(json.dumps(ck))
    assert main(["evolve", "--resume", str(run)]) == 0
    err = capsys.readouterr().err
    assert "note: this run started in another numerical environment (numpy SIMD ELSEWHERE -> " in err
