"""The GA's survivors under a context that changes between generations: scored again by default, never compared by a
fitness kept from an earlier generation's normaliser, phase, disturbances or sources."""

import numpy as np
import pytest

from evobiped.run import RunConfig
from evobiped.run.run_config import make_optimizer

from .conftest import cli

CHANGING = [
    ({"normalise": {"running": True}, "episode": {"controller": "linear", "controller_options": {"frame": "stance"}}},
     "normalise.running"),
    ({"curriculum": {"phases": [{"distance": 1.0}, {"distance": 2.0}]},
      "episode": {"task_options": {"fitness": "weighted"}}},
     "curriculum"),
    ({"episode": {"perturbations": {"pose_noise": 0.01}}}, "episode.perturbations"),
    ({"episode": {"perturbations": {"pushes": 1}}}, "episode.perturbations"),
    ({"episode": {"perturbations": {"presentations": 2,
                                    "target_offset": {"start": 0.0, "end": 0.02, "generations": 5}}}},
     "episode.perturbations"),
    ({"episode": {"task": "steer", "task_options": {
        "random_sources": 2, "source_distance": [5.0, 15.0], "source_bearing": [-60.0, 60.0]}}}, "random sources"),
]


def survivors_after_one_generation(table: dict) -> np.ndarray:
    """The fitness the GA of this config carries into generation 1 for its survivors (NaN: to be scored again)."""
    ga = make_optimizer(RunConfig.from_dict({"ga": {"population": 4}, **table}))
    pop, unknown = ga.ask()
    ga.tell(np.arange(4.0))
    ga.next_generation()
    return ga.fitness[: ga.config.n_survivors]


@pytest.mark.parametrize("table, what", CHANGING)
def test_survivors_are_scored_again_where_each_generation_is_scored_differently(table, what):
    assert np.isnan(survivors_after_one_generation(table)).all()
    from evobiped.run.run_config import changing_context

    assert changing_context(RunConfig.from_dict(table)) == what


def test_survivors_keep_their_fitness_where_nothing_changes_or_where_the_config_says_so():
    """The paper's GA (a nominal, deterministic episode) keeps its survivors' fitness, as it always did; an explicit
    ``reevaluate_survivors = false`` keeps the first-shipped behaviour under a changing context too."""
    assert survivors_after_one_generation({}).tolist() == [3.0, 2.0]
    assert survivors_after_one_generation({"episode": {"perturbations": {"presentations": 2}}}).tolist() == [3.0, 2.0]
    kept = {"ga": {"population": 4, "reevaluate_survivors": False}, "episode": {"perturbations": {"pose_noise": 0.01}}}
    ga = make_optimizer(RunConfig.from_dict(kept))
    ga.tell(np.arange(4.0))
    ga.next_generation()
    assert ga.fitness[:2].tolist() == [3.0, 2.0]


def test_a_bad_reevaluate_survivors_is_one_line(tmp_path, capsys):
    (tmp_path / "c.toml").write_text("[ga]\nreevaluate_survivors = 'yes'\n")
    code = cli("evolve", "--config", tmp_path / "c.toml", "--out", tmp_path / "r", "--generations", 1)
    err = capsys.readouterr().err
    assert code == 2 and len(
        err.strip().splitlines()) == 1 and "ga.reevaluate_survivors: must be true or false" in err, err
    assert not (tmp_path / "r").exists()
