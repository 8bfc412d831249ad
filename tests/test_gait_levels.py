"""``evobiped gait GENOME --u0/--go``: a rhythm generator's walker through levels of its one command, with physics:
Taga's walker (his Appendix D parameters) walks faster at a larger tonic input, a g3 network's rhythm follows its GO
signal, and bad input is one line, exit 2, nothing written."""

from __future__ import annotations

import json

import numpy as np
import pytest

from evobiped.analysis.rhythm_command import sweep_lines
from evobiped.cli import main
from evobiped.episode import EpisodeConfig
from evobiped.experiments.taga.parameters import preset_genome
from evobiped.files.genome_file import save_genome


def _taga_file(path, **controller) -> str:
    cfg = EpisodeConfig(body="taga", controller="matsuoka", task="walk", seconds=20.0,
                        body_options={"timestep": 0.0005}, controller_options=controller)
    save_genome(path, preset_genome(cfg.build().controller), cfg, preset="taga")
    return str(path)


def _g3_file(path) -> str:
    """A g3 walker on the Reil body held up (it never falls), its outputs the network's x offset by 0.2."""
    cfg = EpisodeConfig(body="reil", controller="g3", task="walk", seconds=20.0,
                        body_options={"fall_height": 1e-3, "fall_tilt": np.pi})
    lay = cfg.layout()
    g = lay.init_mean.copy()
    g[lay.slices()["gain"]] = 1.0
    g[lay.slices()["offset"]] = 0.2
    save_genome(path, g, cfg)
    return str(path)


def test_taga_s_walker_walks_faster_at_a_larger_tonic_input(tmp_path, capsys):
    """Taga et al. 1991: the speed rises with u0.  Measured: 1.12, 1.33, 1.45 m/s at u0 4.5, 5.5, 6.5 (6 s each)."""
    f = _taga_file(tmp_path / "taga.json", u0=5.5)
    assert main(["gait", f, "--u0", "4.5,5.5,6.5", "--hold", "6", "--json", "--out", str(tmp_path / "out")]) == 0
    printed = json.loads(capsys.readouterr().out)
    report = json.loads((tmp_path / "out" / "taga_u0.json").read_text())
    assert (tmp_path / "out" / "taga_u0.png").stat().st_size > 10_000
    assert printed["fit"] == report["fit"] and not report["fell"] and report["notes"] == []
    rows = report["stretches"]
    assert [s["level"] for s in rows] == [4.5, 5.5, 6.5] and not any(s["fell"] or s["down"] for s in rows)
    speeds = [s["speed"] for s in rows]
    assert speeds[0] > 0.8 and np.all(np.diff(speeds) > 0.05)  # rising by 0.21 and 0.12 m/s
    assert all(s["gait"]["airborne"] == 0.0 and 1.0 < s["gait"]["steps_per_s"] < 4.0 for s in rows)
    fit = report["fit"]
    assert fit["monotone"] == "rising" and fit["slope"] > 0.1 and fit["ratio"] == pytest.approx(speeds[2] / speeds[0])
    assert all(abs(d) < 15 for d in fit["deviation_pct"])
    lines = sweep_lines(report)
    assert len(lines) == 1 + 3 + 2 and lines[-2].startswith("speed = ") and "monotone (rising)" in lines[-2]


def test_levels_beyond_the_evolved_range_are_clipped_with_one_line_and_a_walker_without_one_is_not(tmp_path, capsys):
    f = _taga_file(tmp_path / "taga.json", u0=[[0.0, 5.0], [10.0, 6.0]])
    assert main(["gait", f, "--u0", "1,5.5,20", "--hold", "0.2", "--out", str(tmp_path / "a")]) == 0
    notes = [line for line in capsys.readouterr().out.splitlines() if line.startswith("note:")]
    assert notes == ["note: u0 1, 20 are beyond what this walker was evolved for (u0 5-6, widened by 50 %: 2.5-9): "
                     "clipped to 2.5, 9"]
    assert [s["level"] for s in json.loads((tmp_path / "a" / "taga_u0.json").read_text())["stretches"]] == [2.5, 5.5, 9]
    g = _taga_file(tmp_path / "free.json")
    assert main(["gait", g, "--u0", "20", "--hold", "0.2", "--json", "--out", str(tmp_path / "b")]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["notes"] == [] and report["stretches"][0]["level"] == 20


def test_a_g3_walker_s_rhythm_follows_its_go_levels(tmp_path, capsys):
    """The network alone (Fig. 4's cells) steps once per 0.93 s at GO 0.1 and once per 0.63 s at 0.2."""
    f = _g3_file(tmp_path / "g3.json")
    assert main(["gait", f, "--go", "0.1,0.2", "--hold", "10", "--json", "--out", str(tmp_path / "out")]) == 0
    rows = json.loads(capsys.readouterr().out)["stretches"]
    assert (tmp_path / "out" / "g3_go.json").is_file() and (tmp_path / "out" / "g3_go.png").is_file()
    periods = [s["period"] for s in rows]
    assert periods[0] == pytest.approx(0.93, abs=0.05) and periods[1] < 0.75 * periods[0]


@pytest.mark.parametrize("args, words", [
    (["--u0", "nan"], "--u0: expected finite numbers"), (["--u0", "4,x"], "--u0: expected finite numbers"),
    (["--u0", "5,-1"], "--u0: levels must be >= 0"), (["--go", "0.1"], "--go: TAGA is driven by controller "
                                                      "'matsuoka', not 'g3'"),
    (["--u0", "5", "--go", "0.1"], "--u0/--go: give one"), (["--u0", "5", "--speed", "1"], "--speed: do not go"),
    (["--go", "0.1", "--seed", "2", "--range", "1,2"], "--range/--seed: do not go with --go"),
    (["--u0", "5,6", "--hold", "2000"], "a sweep runs at most 3600 s")])
def test_bad_input_is_one_line_exit_2_and_nothing_written(tmp_path, capsys, args, words):
    f = _taga_file(tmp_path / "taga.json", u0=5.5)
    assert main(["gait", f, *args, "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and words.replace("TAGA", f) in err, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["taga.json"]


def test_u0_on_a_g3_genome_and_an_unreadable_genome_are_one_line_exit_2(tmp_path, capsys):
    f = _g3_file(tmp_path / "g3.json")
    assert main(["gait", f, "--u0", "5", "--out", str(tmp_path / "out")]) == 2
    assert f"--u0: {f} is driven by controller 'g3', not 'matsuoka'" in capsys.readouterr().err
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    assert main(["gait", str(bad), "--u0", "5", "--out", str(tmp_path / "out")]) == 2
    assert capsys.readouterr().err.count("\n") == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.json", "g3.json"]
