"""MAP-Elites' objective and QD score: an offset QD score that only grows, an objective that does not saturate, and the
task's fitness kept beside it for the archive file and replays."""

import json

import numpy as np
import pytest

pytest.importorskip("ribs")

from evobiped.episode import EpisodeConfig  # noqa: E402
from evobiped.files.rundir import archive_text  # noqa: E402
from evobiped.optimizers.map_elites import MapElites, MapElitesOptions  # noqa: E402

from .conftest import cli  # noqa: E402

GRID = dict(resolution=[4, 3], low=[0.0, -30.0], high=[1.0, 30.0], batch=3)


class Result:
    """What an episode gives MAP-Elites: fitness, outcome, terms."""

    def __init__(self, fitness, measures, distance=None):
        n = len(fitness)
        self.fitness, self.fell, self.end_time = np.array(fitness, float), np.zeros(n), np.full(n, 20.0)
        m = np.array(measures, float)
        self.terms = {"speed": m[:, 0], "turning": m[:, 1], "distance": np.zeros(n) if distance is None
                      else np.array(distance)}


def archive(**options) -> MapElites:
    return MapElites(EpisodeConfig(body="reil", controller="simbicon").layout(), MapElitesOptions(**GRID, **options),
                     seed=0)


def test_the_offset_qd_score_grows_when_a_cell_of_negative_objective_is_filled():
    """Objectives below 0 (a walker that went backwards): without an offset a new elite of -8 lowered the QD score; with
    qd_offset = -10 every filled cell adds objective + 10 > 0, as pyribs' own score says."""
    opt = archive(qd_offset=-10.0)
    opt.tell(Result([-5.0, -3.0, -4.0], [[0.1, 0.0], [0.6, 0.0], [0.12, 0.0]]))
    assert opt.progress[-1][2] == pytest.approx(6.0 + 7.0)  # speeds 0.1 and 0.12 share a cell: -4 keeps it
    opt.next_generation()
    # a new cell; two worse than their cells' elites
    opt.tell(Result([-8.0, -9.0, -9.5], [[0.9, 20.0], [0.1, 1.0], [0.6, -1.0]]))
    assert opt.progress[-1][2] == pytest.approx(6.0 + 7.0 + 2.0)
    assert opt.progress[-1][2] == pytest.approx(float(opt.archive.stats.qd_score))
    plain = archive()
    plain.tell(Result([-5.0, -3.0, -4.0], [[0.1, 0.0], [0.6, 0.0], [0.12, 0.0]]))
    assert plain.progress[-1][2] == -7.0  # the default offset 0: the plain sum, as before


def test_objective_terms_keep_the_better_walker_where_the_fitness_saturates(tmp_path):
    """Two walkers of one cell that both stay up (time up 20 s, the fitness saturated): the fitness alone keeps the
    first; with objective_terms = {distance = 0.05} the one that went 3 m replaces the one that went 1 m.
    archive.json's objective is the task's fitness (what a replay compares), the archive's objective the sum."""
    for terms, kept in (({}, 1.0), ({"distance": 0.05}, 3.0)):
        opt = archive(objective_terms=terms)
        opt.tell(Result([20.0, 20.0, 20.0], [[0.1, 0.0], [0.6, 0.0], [0.9, 0.0]], distance=[1.0, 1.0, 1.0]))
        opt.next_generation()
        opt.tell(Result([20.0, 20.0, 20.0], [[0.11, 0.0], [0.61, 0.0], [0.91, 0.0]], distance=[3.0, 0.5, 1.0]))
        e = opt.elites()
        first = np.flatnonzero(opt.cells(e["index"])[:, 0] == 0)[0]
        assert e["objective"][first] == pytest.approx(20.0 + 0.05 * kept) if terms else e["objective"][first] == 20.0
        assert np.array_equal(e["genome"][first], opt.population[0]) is (kept == 3.0)
        assert e["task_fitness"].tolist() == [20.0] * 3
        text = json.loads(archive_text(opt.archive_contents()))
        assert [row["objective"] for row in text["elites"]] == [20.0] * 3


def test_a_checkpoint_written_before_the_task_fitness_resumes_with_the_objective_as_fitness():
    opt = archive()
    opt.tell(Result([2.0, 3.0, 1.0], [[0.1, 0.0], [0.6, 0.0], [0.9, 0.0]]))
    opt.next_generation()
    table = opt.state().to_dict()
    del table["task_fitness"]
    again = archive()
    again.restore(again.state_from(table))
    assert again.elites()["task_fitness"].tolist() == again.elites()["objective"].tolist() == [2.0, 3.0, 1.0]


@pytest.mark.parametrize("setting, words", [
    ("objective_terms = {pace = 1.0}", "map_elites.objective_terms: pace names no term of the walk task"),
    ("objective_terms = {distance = 'far'}", "map_elites.objective_terms: must be a table of finite weights"),
    ("qd_offset = 'low'", "map_elites.qd_offset: must be a number"),
])
def test_bad_objective_settings_are_one_line(tmp_path, capsys, setting, words):
    (tmp_path / "c.toml").write_text(f"[map_elites]\n{setting}\n")
    code = cli("evolve", "--preset", "repertoire-balance", "--config", tmp_path / "c.toml", "--out", tmp_path / "r",
               "--generations", 1)
    err = capsys.readouterr().err
    assert code == 2 and len(err.strip().splitlines()) == 1 and words in err, err
    assert not (tmp_path / "r").exists()
