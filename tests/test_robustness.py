"""The robustness battery: its trial set, its numbers against direct episodes, and bad input."""

import json
from pathlib import Path

import numpy as np
import pytest

from evobiped.cli import main
from evobiped.core.errors import UserError
from evobiped.experiments.taga.parameters import preset_genome
from evobiped.files.genome_file import load_genome, save_genome
from evobiped.physics.trials import Trials
from evobiped.analysis.robustness import battery, score, summarise

from .conftest import WALKERS

WALKER = str(WALKERS / "simbicon_seed1.json")


@pytest.fixture(scope="module")
def trials():
    g, cfg, _ = load_genome(WALKER)
    return battery(cfg.nominal().build(), g, seconds=12.0, push_after=6.0)


def test_the_battery_has_the_documented_trials(trials):
    rows = {r["family"]: r["trials"] for r in summarise(trials)}
    assert rows == {"push 5 N": 32, "push 10 N": 32, "push 15 N": 32, "push 20 N": 32, "offset 0.05 rad": 8,
                    "offset 0.1 rad": 8, "gene noise 1 %": 8, "friction": 4, "slope 3 %": 4, "slope 5 %": 4}
    labels = [t.label for t in trials if t.family == "offset 0.05 rad"]
    assert len(set(labels)) == 8 and "roll opposite -" in labels
    pushes = {t.label for t in trials if t.family == "push 20 N"}
    assert len(pushes) == 32 and {"forward-left, phase 3/4", "backward-right, phase 0/4"} <= pushes
    assert [t.label for t in trials if t.family == "slope 5 %"] == ["5 % uphill", "5 % downhill",
                                                                    "5 % rising to the left", "5 % rising to the right"]
    assert score(trials) == sum(t.survived for t in trials) / 164


def test_a_gene_noise_and_a_slope_trial_equal_their_disturbance_run_on_their_own(trials):
    """'gene noise 1 %, draw 2' is the walker with the battery's third noise draw (seed 1, 1 % of each gene's range)
    alone; '3 % rising to the left' is the episode on that floor."""
    g, cfg, _ = load_genome(WALKER)
    ep = cfg.nominal().build()
    lay = ep.controller.layout
    noise = np.random.default_rng(1).normal(0.0, 0.01, (8, lay.size))[2]
    r = ep.run(np.clip(g + noise * (lay.high - lay.low), lay.low, lay.high), seconds=12.0)
    t = next(t for t in trials if t.label == "draw 2")
    assert t.end_time == r.end_time[0] and t.forward == r.end_position[0, 0] - r.start_position[0, 0]
    r = ep.run(g, seconds=12.0, trials=Trials.nominal(1, 6, slope=0.03, slope_direction=np.pi / 2)).rows
    t = next(t for t in trials if t.label == "3 % rising to the left")
    assert t.end_time == r.end_time[0] and t.forward == r.end_position[0, 0] - r.start_position[0, 0]


def test_a_trial_equals_the_same_disturbance_run_on_its_own(trials):
    """The batched battery row for 'offset 0.05 rad, pitch opposite +' is the episode with that offset alone."""
    g, cfg, _ = load_genome(WALKER)
    ep = cfg.nominal().build()
    off = np.zeros(6)
    off[0], off[3] = 0.05, -0.05  # left hip pitch +, right hip pitch -
    r = ep.run(g, seconds=12.0, trials=Trials.nominal(1, 6, target_offset=off[None])).rows
    t = next(t for t in trials if t.family == "offset 0.05 rad" and t.label == "pitch opposite +")
    assert t.survived == (not r.fell[0]) and t.end_time == r.end_time[0]
    assert t.forward == r.end_position[0, 0] - r.start_position[0, 0]
    # and a friction trial is the episode on a floor of that friction
    r = ep.run(g, seconds=12.0, trials=Trials.nominal(1, 6, friction=0.5)).rows
    t = next(t for t in trials if t.label == "mu = 0.5")
    assert t.end_time == r.end_time[0]


def test_cli_writes_table_json_and_png(tmp_path, capsys):
    g, cfg, meta = load_genome(WALKER)
    save_genome(tmp_path / "w.json", g, cfg, **{k: v for k, v in meta.items() if k in ("fitness", "fell", "seed")})
    assert main(["robustness", str(tmp_path / "w.json"), "--seconds", "8", "--push-after", "4"]) == 0
    out = capsys.readouterr().out
    assert "push 10 N" in out and "offset 0.05 rad" in out
    report = json.loads((Path.cwd() / "runs" / "w" / "w_robustness.json").read_text())  # never beside the genome file
    assert len(report["trials"]) == 164 and report["seconds"] == 8.0
    survived = sum(t["survived"] for t in report["trials"])
    assert report["score"] == survived / 164
    assert f"robustness score: {survived / 164:.3f} ({survived} of 164 trials survived)" in out
    assert (Path.cwd() / "runs" / "w" / "w_robustness.png").read_bytes()[:4] == b"\x89PNG"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["w.json"]


@pytest.mark.parametrize("args, msg", [
    (["--seconds", "5", "--push-after", "6"], "--push-after"),
    (["--generation", "3"], "--generation needs a run directory"),
])
def test_bad_arguments_one_line(tmp_path, capsys, args, msg):
    assert main(["robustness", WALKER, "--out", str(tmp_path / "o"), *args]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and msg in err[0]
    assert not (tmp_path / "o").exists()


def test_on_the_sagittal_taga_body_the_battery_is_the_forward_and_backward_pushes_and_the_gene_noise():
    """Found by role: Taga's left-foot contacts time the pushes; no hip-roll or PD-target offsets, no MuJoCo
    ground to change, no sideways pushes or slopes.  Taga's walker pushed forward goes further than pushed back."""
    from evobiped.episode import EpisodeConfig

    ep = EpisodeConfig(body="taga", controller="matsuoka", seconds=3.0).build()
    trials = battery(ep, preset_genome(ep.controller), seconds=3.0, push_after=1.0)
    assert [t.family for t in trials] == [f"push {f} N" for f in (5, 10, 15, 20)
                                          for _ in range(8)] + ["gene noise 1 %"] * 8
    assert {t.label.split(",")[0] for t in trials if t.family.startswith("push")} == {"forward", "backward"}
    fwd = {t.label: t.forward for t in trials if t.family == "push 15 N"}
    assert all(fwd[f"forward, phase {i}/4"] > fwd[f"backward, phase {i}/4"] + 0.01 for i in range(4))


def test_a_body_without_a_contact_sensor_is_refused(tmp_path, capsys):
    from evobiped.bodies.taga import TagaBiped
    from evobiped.episode import Episode, EpisodeConfig

    class Numb(TagaBiped):
        contact_sensor = None

    _, ctrl, task = EpisodeConfig(body="taga", controller="matsuoka").parts()
    with pytest.raises(UserError, match="needs a body that declares its left foot's contact sensor; 'taga' does not"):
        battery(Episode(Numb(), ctrl, task, seconds=2.0), preset_genome(ctrl), seconds=2.0, push_after=1.0)


def test_pushes_at_random_phases_fall_where_their_seed_says_and_each_equals_its_push_alone():
    """--phase-seed: each push trial at its own phase of the stride, drawn from the seed; a trial equals that push run
    alone, the same seed gives the same phases, another seed other ones, and the fixed phases are still i/4."""
    from evobiped.analysis.robustness import DIRECTIONS, PHASES, push_phases, stride, unit

    g, cfg, _ = load_genome(WALKER)
    ep = cfg.nominal().build()
    assert np.array_equal(push_phases(128, None)[:8], [0, 0.25, 0.5, 0.75] * 2)
    a, b = push_phases(128, 7), push_phases(128, 8)
    assert np.array_equal(a, push_phases(128, 7)) and not np.allclose(a, b) and ((0 <= a) & (a < 1)).all()
    assert len(np.unique(np.round(a, 2))) > 60  # not four phases again
    trials = battery(ep, g, seconds=8.0, push_after=4.0, phase_seed=7)
    pushes = [t for t in trials if t.family.startswith("push")]
    assert len(pushes) == 128 and len({t.label for t in pushes if t.family == "push 20 N"}) == 32
    t0, period = stride(ep, g, 8.0, 4.0)
    k = 32 + 2 * PHASES + 3  # push 10 N, third direction (left), fourth trial
    d = list(DIRECTIONS)[2]
    t = pushes[k]
    assert t.family == "push 10 N" and t.label == f"{d}, phase {a[k]:.2f}"
    ux, uy = unit(d)
    r = ep.run(g, seconds=8.0, trials=Trials.nominal(1, 6, push_start=np.array([[t0 + period * a[k]]]),
                                                      push_force=np.array([[[10 * ux, 10 * uy, 0.0]]]),
                                                     push_duration=0.1)).rows
    assert t.end_time == r.end_time[0] and t.forward == r.end_position[0, 0] - r.start_position[0, 0]


def test_cli_phase_seed_writes_its_own_report_and_refuses_a_negative_seed(tmp_path, capsys):
    assert main(["robustness", WALKER, "--seconds", "6", "--push-after", "3", "--phase-seed", "3", "--out",
                 str(tmp_path), "--quiet"]) == 0
    out = capsys.readouterr().out
    assert "push 10 N" in out and "gene noise 1 %" in out
    report = json.loads((tmp_path / "simbicon_seed1_phases3_robustness.json").read_text())
    assert report["phase_seed"] == 3 and (tmp_path / "simbicon_seed1_phases3_robustness.png").exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["simbicon_seed1_phases3_robustness.json",
                                                          "simbicon_seed1_phases3_robustness.png"]
    with pytest.raises(SystemExit) as refused:  # an argument's refusal: argparse's exit, status 2
        main(["robustness", WALKER, "--phase-seed", "-1", "--out", str(tmp_path / "o")])
    assert refused.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--phase-seed" in err[0] and not (tmp_path / "o").exists()
