"""MAP-Elites: the walk task's gait measures against an independent calculation, the archive's cells against the
grid arithmetic, a resume bit-identical to an uninterrupted run, archive.json, and bad settings refused."""

import json
import shutil

import numpy as np
import pytest

pytest.importorskip("ribs")

from evobiped.episode import EpisodeConfig  # noqa: E402
from evobiped.core.errors import UserError  # noqa: E402
from evobiped.run import Run, RunConfig  # noqa: E402
from evobiped.evaluation import make_evaluator  # noqa: E402
from evobiped.files.rundir.archive_file import read_archive  # noqa: E402
from evobiped.optimizers.map_elites import MapElites, MapElitesOptions  # noqa: E402
from evobiped.core.fileio import packed_floats, unpacked_floats  # noqa: E402
from evobiped.files.genome_file import load_genome  # noqa: E402

from .conftest import WALKERS, cli  # noqa: E402

GAIT = {"fitness": "weighted", "weights": {"time_up": 1.0}, "gait_measures": True}
#: a short balance-controller repertoire run
TINY = {"optimizer": "map-elites", "generations": 4, "seed": 2, "backend": "serial",
        "episode": {"body": "reil", "controller": "simbicon", "seconds": 1.0, "task_options": GAIT},
        "map_elites": {"resolution": [5, 4], "low": [0.0, -40.0], "high": [1.0, 40.0], "batch": 6, "sigma": 0.05,
                       "line_sigma": 0.3}}


class Track:
    """A listener keeping the pelvis's planar position and facing after every tick of row 0."""

    def __init__(self, body):
        self.body, self.xy, self.facing = body, [], []

    def start(self, episode, sims):
        self.xy.append(self.body.planar_position(sims)[0].copy())
        self.facing.append(self.body.heading(sims)[0].copy())

    def tick(self, t, sims, ids, neurons, action, tstate):
        if 0 in ids:
            self.start(None, sims)

    def end(self, result):
        pass


def test_gait_measures_match_an_independent_calculation_and_leave_the_fitness_alone():
    """speed = the path's steps projected on the facing after each step / time up; turning = np.unwrap of the facing's
    angle, end minus start / time up, in deg/s.  The shipped walker that turns round in its first 4 s (-184 deg) and the
    straight one; the fitness with the measures on is bit for bit the fitness without."""
    for name, turns in (("simbicon_cma_seed3.json", True), ("simbicon_cma_seed5.json", False)):
        genome, cfg, _ = load_genome(WALKERS / name)
        d = {**cfg.to_dict(), "seconds": 6.0}
        ep = EpisodeConfig(**{**d, "task_options": {**d["task_options"], "gait_measures": True}}).build()
        track = Track(ep.body)
        r = ep.run(genome[None], listener=track)
        xy, f = np.array(track.xy), np.array(track.facing)
        speed = np.sum(np.einsum("ti,ti->t", np.diff(xy, axis=0), f[1:])) / r.end_time[0]
        yaw = np.unwrap(np.arctan2(f[:, 1], f[:, 0]))
        turning = np.degrees(yaw[-1] - yaw[0]) / r.end_time[0]
        assert r.terms["speed"][0] == pytest.approx(speed, rel=1e-9)
        assert r.terms["turning"][0] == pytest.approx(turning, rel=1e-9, abs=1e-9)
        assert (abs(turning) > 20) == turns  # seed 3 turns round (about 180 deg in 6 s), seed 5 walks straight
        plain = EpisodeConfig(**d).build().run(genome[None])
        assert plain.fitness[0] == r.fitness[0] and "speed" not in plain.terms


def test_the_archive_keeps_the_fittest_of_each_cell_of_the_grid():
    """Cells by the grid arithmetic (floor((m - low) / width), beyond the bounds the edge cell); of two genomes in one
    cell the fitter stays, a later worse one does not replace it; a non-finite measure is left out."""
    layout = EpisodeConfig(body="reil", controller="simbicon").layout()
    opt = MapElites(layout, MapElitesOptions(resolution=[4, 3], low=[0.0, -30.0], high=[1.0, 30.0], batch=5), seed=0)

    class R:
        def __init__(self, f, m):
            self.fitness, self.fell, self.end_time = np.array(f, float), np.zeros(len(f)), np.full(len(f), 2.0)
            self.terms = {"speed": np.array(m)[:, 0], "turning": np.array(m)[:, 1]}

    m = [[0.1, -29.0], [0.12, -25.0], [0.6, 5.0], [2.0, 99.0], [np.nan, 0.0]]
    opt.tell(R([1.0, 3.0, 2.0, 4.0, 9.0], m))
    e = opt.elites()
    expect = [(0, 0), (2, 1), (3, 2)]  # speed 0.1/0.12 -> column 0 (both; the fitter 3.0), 0.6 -> 2, 2.0 -> the edge 3
    assert [tuple(c) for c in opt.cells(e["index"])] == expect
    assert e["objective"].tolist() == [3.0, 2.0, 4.0]
    assert np.array_equal(e["genome"][0], opt.population[1])
    opt.next_generation()
    opt.tell(R([2.5, 1.0, 1.0, 1.0, 1.0], [[0.05, -28.0]] * 5))
    assert opt.elites()["objective"][0] == 3.0 and opt.progress[-1][:2] == [10, 3]


def test_a_map_elites_run_resumes_bit_identically_and_derives_its_archive(tmp_path):
    """Stopped after generation 1 and resumed on two workers: the same checkpoint state (the elites as data), history,
    archive.json; the archive's elites are the checkpoint's, and its progress counts every evaluation."""
    from .test_evolve import fitness_history, whole_and_resumed

    config = RunConfig.from_dict(TINY)
    whole, cut_dir = whole_and_resumed(tmp_path, config, stop_after=1)
    a, b = (json.loads((d / "checkpoint.json").read_text()) for d in (whole.dir, cut_dir))
    assert a["optimizer"] == b["optimizer"] and a["best_genome"] == b["best_genome"]
    assert fitness_history(whole.dir) == fitness_history(cut_dir)
    assert (whole.dir / "archive.json").read_text() == (cut_dir / "archive.json").read_text()
    arch = read_archive(whole.dir)
    assert len(arch.cell) == len(a["optimizer"]["index"]) >= 3
    assert arch.progress[:, 0].tolist() == [6, 12, 18, 24] and arch.progress[-1, 1] == len(arch.cell)
    assert np.array_equal(arch.genome, unpacked_floats(a["optimizer"]["genome"], "genome"))


def test_the_elites_genomes_are_packed_exactly_and_a_checkpoint_of_rows_still_resumes(tmp_path):
    """The checkpoint holds the elites' genomes as float64 bytes (compact, exact); a checkpoint from before, with a row
    of numbers per elite, resumes to the same run."""
    from .test_evolve import whole_and_resumed

    config = RunConfig.from_dict(TINY)
    whole, cut_dir = whole_and_resumed(tmp_path, config, stop_after=1)
    table = json.loads((whole.dir / "checkpoint.json").read_text())["optimizer"]["genome"]
    assert set(table) == {"dtype", "shape", "b64"} and table["shape"][1] == config.episode.layout().size
    assert np.array_equal(unpacked_floats(table, "g"), read_archive(whole.dir).genome)
    # the cut run's checkpoint rewritten with rows of numbers, as before, then run on: the same archive
    run2 = tmp_path / "rows"
    shutil.copytree(cut_dir, run2)
    ck = json.loads((run2 / "checkpoint.json").read_text())
    ck["optimizer"]["genome"] = unpacked_floats(ck["optimizer"]["genome"], "g").tolist()
    (run2 / "checkpoint.json").write_text(json.dumps(ck))
    assert cli("evolve", "--resume", run2, "--quiet") == 0
    assert (run2 / "archive.json").read_text() == (whole.dir / "archive.json").read_text()


def test_the_run_recording_holds_the_archive_growth(tmp_path):
    """evolution.rrd records the archive's cells, coverage and QD score per generation, as archive.json counts them."""
    from evobiped.record.recordings.evolution_log import recording_series

    from evobiped.usecases.evolving import run_listeners

    config = RunConfig.from_dict(dict(TINY, generations=3))
    run = Run.create(tmp_path / "run", config, run_listeners())  # the evolve use case's: its recording
    with make_evaluator(config.episode, "serial") as ev:
        run.evolve(ev)
    progress = read_archive(run.dir).progress
    series = {name: recording_series(run.dir / "evolution.rrd", f"/evolution/optimizer/{name}")
              for name in ("evaluations", "cells", "coverage", "qd_score")}
    assert series["qd_score"] == dict(enumerate(progress[:, 2].tolist())) and len(progress) == 3
    assert series["evaluations"] == {0: 6.0, 1: 12.0, 2: 18.0}
    assert series["coverage"] == {g: c / 20 for g, c in enumerate(progress[:, 1].tolist())}  # a 5 x 4 grid
    assert series["cells"][2] == len(read_archive(run.dir).cell) > 0


def test_an_archive_is_seeded_from_a_genome_file(tmp_path):
    """--from: the first batch is the start genome itself and its mutants, and the archive after it holds exactly the
    fittest of them in each cell, by their own episodes and the grid arithmetic (the start genome's cell among them)."""
    config = RunConfig.from_dict({**TINY, "generations": 1, "initial": str(WALKERS / "simbicon_cma_seed5.json")})
    run = Run.create(tmp_path / "run", config)
    start, _, _ = load_genome(WALKERS / "simbicon_cma_seed5.json")
    batch = run.optimizer.population.copy()
    assert len(batch) == TINY["map_elites"]["batch"] and np.array_equal(batch[0], start)
    assert not (batch[1:] == start).all(axis=1).any()
    with make_evaluator(config.episode, "serial") as ev:
        run.evolve(ev)
    r = config.episode.build().run(batch)
    me = TINY["map_elites"]
    low, high, res = (np.array(me[k], float) for k in ("low", "high", "resolution"))
    m = np.stack([r.terms["speed"], r.terms["turning"]], axis=1)
    cells = np.clip(np.floor((m - low) / ((high - low) / res)), 0, res - 1).astype(int)
    fittest = {}
    for cell, f, g in zip(map(tuple, cells.tolist()), r.fitness, batch):
        if cell not in fittest or f > fittest[cell][0]:
            fittest[cell] = (f, g)
    arch = read_archive(run.dir)
    assert {tuple(c): o for c, o in zip(arch.cell.tolist(), arch.objective)} == {c: f for c, (f, _) in fittest.items()}
    assert all(np.array_equal(g, fittest[tuple(c)][1]) for c, g in zip(arch.cell.tolist(), arch.genome))
    assert tuple(cells[0]) in fittest and len(fittest) >= 2


@pytest.mark.parametrize("setting, words", [
    ("measures = ['speed', 'cadence']", "cadence names no term of the walk task"),
    ("resolution = [0, 10]", "cells per measure must be 1 to 1000"),
    ("low = [1.0, -30.0]\nhigh = [0.5, 30.0]", "low 1 must be below high 0.5"),
])
def test_bad_map_elites_settings_one_line_exit_2_nothing_written(tmp_path, capsys, setting, words):
    cfg = tmp_path / "me.toml"
    cfg.write_text("optimizer = 'map-elites'\n[episode]\ncontroller = 'simbicon'\nseconds = "
                   "1.0\n[episode.task_options]\nfitness = 'weighted'\ngait_measures = true\n[map_elites]\n" + setting
                       + "\n")
    out = tmp_path / "run"
    assert cli("evolve", "--config", cfg, "--out", out, "--quiet") == 2
    err = capsys.readouterr().err.strip()
    assert words in err and "\n" not in err and "Traceback" not in err
    assert not out.exists()


def test_without_pyribs_one_line(monkeypatch):
    import sys

    monkeypatch.setitem(sys.modules, "ribs", None)
    with pytest.raises(UserError, match="needs pyribs"):
        MapElites(EpisodeConfig(controller="simbicon").layout(), MapElitesOptions(), seed=0)


@pytest.mark.parametrize("field, value, words", [
    ("genome", "x", "map-elites.genome must be a list of rows of 13 finite numbers"),
    ("genome", [0.5] * 5, "map-elites.genome must be a list of rows of 13 finite numbers"),  # a row of another length
    ("genome", {"dtype": "<f8", "b64": "AAAAAAAA+H8=", "shape": [1, 1]}, "map-elites.genome must hold finite numbers"),
    ("fitness", "x", "map-elites.fitness must be a list of finite numbers or nulls"),
    ("genome", {"dtype": "<f8", "b64": "AAAA", "shape": [1, 13]}, "map-elites.genome: 3 bytes do not hold 1 x 13 "
                                                                  "float64 numbers"),
    ("genome", {"dtype": "<f8", "b64": "not base64!", "shape": [0, 13]}, "map-elites.genome: b64 is not base64"),
    ("genome", {"dtype": "<f4", "b64": "", "shape": [0, 13]}, 'map-elites.genome must be a list of numbers or {dtype: '
                                                              '"<f8", shape, b64}'),
    ("index", 999, "map-elites.index must be different cells 0 to 19"),
    ("measures", [[5.0, 0.0]], "map-elites.measures do not lie in the cells map-elites.index names"),
])
def test_a_damaged_archive_in_the_checkpoint_is_refused_in_one_line(tmp_path, capsys, field, value, words):
    config = RunConfig.from_dict({**TINY, "generations": 1})
    run = Run.create(tmp_path / "run", config)
    with make_evaluator(config.episode, "serial") as ev:
        run.evolve(ev)
    run.close()
    path = tmp_path / "run" / "checkpoint.json"
    ck = json.loads(path.read_text())
    table = ck["optimizer"]
    rows = unpacked_floats(table["genome"], "genome")
    if field == "measures":  # one elite whose measures lie in another cell
        table["index"], table["genome"], table["objective"] = table["index"][:1], packed_floats(rows[:1]), table[
            "objective"][:1]
        table["fell"], table["end_time"], table["task_fitness"] = table["fell"][:1], table["end_time"][:1], table[
            "task_fitness"][:1]
        table["index"][0] = 0
    if field == "genome":
        table[field] = value if isinstance(value, dict) else [value] + rows[1:].tolist()
    else:
        table[field] = value if field == "measures" else [value] + table[field][1:]
    path.write_text(json.dumps(ck))
    assert cli("evolve", "--resume", tmp_path / "run") == 2
    err = capsys.readouterr().err.strip()
    assert words in err and "\n" not in err


def test_parents_up_draws_only_elites_that_stayed_up():
    """parents = up: with a vanishing step each new genome is a copy of an elite that did not fall; all: of any
    elite."""
    layout = EpisodeConfig(body="reil", controller="simbicon").layout()
    drawn = {}
    for parents in ("up", "all"):
        opt = MapElites(layout, MapElitesOptions(resolution=[4, 3], batch=40, sigma=1e-12, parents=parents), seed=0)
        fitness = np.r_[1.0, 2.0, 3.0, np.full(37, -np.inf)]  # three elites; the rest unstable, kept out
        opt.tell(_result(fitness, np.r_[1.0, 0.0, 1.0, np.ones(37)], np.r_[0.1, 0.5, 0.9, np.zeros(37)]))
        e = opt.elites()
        opt.next_generation()
        near = np.abs(opt.population[:, None, :] - e["genome"][None]).max(axis=2) < 1e-9  # (batch, elites)
        assert near.any(axis=1).all()
        drawn[parents] = set(np.flatnonzero(near.any(axis=0)))
    assert drawn["up"] == {1} and drawn["all"] == {0, 1, 2}


def _result(fitness, fell, speed):
    class R:
        pass
    r = R()
    r.fitness, r.fell, r.end_time = np.asarray(fitness, float), np.asarray(fell, float), np.full(len(fitness), 2.0)
    r.terms = {"speed": np.asarray(speed, float), "turning": np.zeros(len(fitness))}
    return r


@pytest.mark.parametrize("backend", ["thread", "ray"])
def test_the_archive_is_the_same_on_threads_and_on_ray_actors(tmp_path, backend):
    """The same short repertoire run evaluated serially, on two threads and on two Ray actors: archive.json and the
    checkpoint's elites are identical (the batch's rows are evaluated wherever, and their results come back in
    order)."""
    if backend == "ray":
        pytest.importorskip("ray")
    config = RunConfig.from_dict({**TINY, "generations": 2})
    dirs = []
    for name, workers in (("serial", None), (backend, 2)):
        run = Run.create(tmp_path / name, config)
        with make_evaluator(config.episode, name, workers=workers) as ev:
            run.evolve(ev)
        run.close()
        dirs.append(run.dir)
    a, b = (d / "archive.json" for d in dirs)
    assert a.read_text() == b.read_text() and len(read_archive(dirs[0]).cell) >= 3
