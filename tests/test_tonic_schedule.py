"""The matsuoka controller's tonic input u0 as a schedule over an episode (one parser with g3's GO signal), and the
one-line refusals of a bad schedule or a sense the body does not declare."""

from __future__ import annotations

import numpy as np
import pytest

from evobiped.core.errors import ConfigError
from evobiped.core.schedule import level_at, timed_levels
from evobiped.episode import EpisodeConfig
from evobiped.experiments.taga.parameters import preset_genome


def _taga(u0, seconds: float) -> EpisodeConfig:
    return EpisodeConfig(body="taga", controller="matsuoka", task="walk", seconds=seconds,
                         body_options={"timestep": 0.0005}, controller_options={"u0": u0})


def _walk(cfg: EpisodeConfig, pieces=((None, 1.5),)) -> list[np.ndarray]:
    """Taga's walker under ``cfg``, advanced piece by piece (``(u0 set in params or None, seconds)``): its end state."""
    ep = cfg.build()
    st = ep.start(preset_genome(ep.controller)[None], seconds=sum(s for _, s in pieces))
    for u0, seconds in pieces:
        if u0 is not None:
            st.params["u0"][:] = u0  # how the experiments change u0 (TagaWalker.set_u0)
        ep.advance(st, seconds)
    return [st.controller["u"], st.controller["v"], st.sims.qpos.copy(), st.sims.qvel.copy()]


def _same(a: list[np.ndarray], b: list[np.ndarray]) -> bool:
    return all(np.array_equal(x, y) for x, y in zip(a, b))


def test_a_constant_u0_walks_the_same_to_the_last_bit_as_a_level_or_a_one_step_schedule():
    """5.5, [[0, 5.5]] and a schedule that keeps 5.5 (read at each tick) give the same bits: the constant path is the
    decoded params["u0"] as before, and the schedule's level enters the same sum."""
    level = _walk(_taga(5.5, 1.5))
    assert _same(level, _walk(_taga([[0.0, 5.5]], 1.5)))
    assert _same(level, _walk(_taga([[0.0, 5.5], [50.0, 5.5]], 1.5)))


def test_a_u0_schedule_switches_at_its_time_exactly_as_setting_u0_between_two_pieces_did():
    switched = _walk(_taga(5.5, 1.5), ((None, 0.75), (6.5, 0.75)))
    scheduled = _walk(_taga([[0.0, 5.5], [0.75, 6.5]], 1.5))
    assert _same(scheduled, switched)
    assert not _same(scheduled, _walk(_taga(5.5, 1.5)))


def test_one_parser_reads_both_commands_and_its_level_is_zero_before_the_first_step():
    t, v = timed_levels([[1.0, 0.1], [2.0, 0.3]])
    assert level_at(t, v, [0.5, 1.0, 1.5, 2.0 - 1e-12, 7.0]).tolist() == [0.0, 0.1, 0.1, 0.3, 0.3]
    assert [a.tolist() for a in timed_levels(5.5)] == [[0.0], [5.5]]


@pytest.mark.parametrize("u0, words", [
    (-1.0, "u0: must be >= 0, got -1.0"), (float("nan"), "u0: must be finite"), ([], "u0: the schedule is empty"),
    ([[1.0, 5.0], [0.5, 6.0]], "u0: a schedule's times must increase"),
    ([[0.0, -1.0]], "u0: a schedule's levels and times must be finite and >= 0"),
    ([[0.0, float("inf")]], "finite and >= 0"), ("fast", "must be a level or a list of [time_s, level] pairs"),
    ([[0.0, 1.0, 2.0]], "must be a level or a list")])
def test_a_bad_u0_schedule_is_one_config_error_line(u0, words):
    with pytest.raises(ConfigError) as e:
        _taga(u0, 1.0).build()
    assert words in str(e.value) and "\n" not in str(e.value)


def _evolve(tmp_path, capsys, controller: str, options: str) -> tuple[int, str]:
    from evobiped.cli import main

    f = tmp_path / "f.toml"
    f.write_text(f'generations = 1\n[episode]\nbody = "reil"\ncontroller = "{controller}"\ntask = "walk"\n'
                 f'seconds = 1.0\n[episode.controller_options]\n{options}\n')
    code = main(["evolve", "--controller", controller, "--config", str(f), "--out", str(tmp_path / "run")])
    return code, capsys.readouterr().err


@pytest.mark.parametrize("controller", ["matsuoka", "g3"])
def test_evolve_refuses_feedback_from_a_sense_the_body_does_not_declare_in_one_line(tmp_path, capsys, controller):
    code, err = _evolve(tmp_path, capsys, controller, 'feedback = "senses"\ninputs = ["nosuch"]')
    assert code == 2 and err.count("\n") == 1 and "inputs ['nosuch'] are not sensors of the body or task" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["f.toml"]


@pytest.mark.parametrize("controller, option", [("matsuoka", "u0"), ("g3", "go")])
def test_evolve_refuses_a_bad_schedule_in_one_line(tmp_path, capsys, controller, option):
    code, err = _evolve(tmp_path, capsys, controller, f"{option} = [[2.0, 1.0], [1.0, 2.0]]")
    assert code == 2 and err.count("\n") == 1 and f"{option}: a schedule's times must increase" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["f.toml"]
