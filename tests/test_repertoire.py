"""A gait repertoire in use: replaying an elite, the figures, the speed knob, damage and intelligent trial and error."""

import dataclasses

import numpy as np
import pytest

pytest.importorskip("ribs")

from evobiped.run import Run, RunConfig  # noqa: E402
from evobiped.evaluation import make_evaluator  # noqa: E402
from evobiped.files.genome_file import load_genome  # noqa: E402
from evobiped.repertoire.damage import damaged_episode, parse_damage  # noqa: E402
from evobiped.repertoire.elites import load_repertoire as load  # noqa: E402
from evobiped.repertoire.speed import Stretch, follow, hysteresis  # noqa: E402
from evobiped.repertoire.trial_error import TrialAndError, matern52, posterior, prior_distance  # noqa: E402

from .conftest import WALKERS, cli  # noqa: E402

SEED5 = WALKERS / "simbicon_cma_seed5.json"


@pytest.fixture(scope="module")
def archive_run(tmp_path_factory):
    """Two generations of six 3 s episodes from the shipped straight walker: an archive with walking elites."""
    config = RunConfig.from_dict({
        "optimizer": "map-elites", "generations": 2, "seed": 1, "backend": "serial", "initial": str(SEED5),
        "episode": {"body": "reil", "controller": "simbicon", "seconds": 3.0,
                    "task_options": {"fitness": "weighted", "weights": {"time_up": 1.0}, "gait_measures": True}},
        "map_elites": {"resolution": [20, 10], "low": [0.0, -30.0], "high": [1.0, 30.0], "batch": 6, "sigma": 0.01}})
    run = Run.create(tmp_path_factory.mktemp("rep") / "run", config)
    with make_evaluator(config.episode, "serial") as ev:
        run.evolve(ev)
    run.close()
    return run.dir


def test_an_elite_replays_bit_for_bit_and_the_figures_are_drawn(archive_run, capsys):
    rep = load(archive_run)
    k = int(np.flatnonzero(rep.walking())[0])
    i, j = rep.archive.cell[k]
    assert cli("replay", archive_run, "--cell", f"{i},{j}", "--out", archive_run / "cell.rrd", "--quiet") == 0
    out = capsys.readouterr().out
    assert "the replay equals it bit for bit" in out and "stayed up for 3.0 s" in out
    assert cli("repertoire", archive_run, "--list") == 0
    out = capsys.readouterr().out
    assert f"{len(rep.archive.cell)} elites in 200 cells after 12 evaluations; {int(rep.walking().sum())} walk" in out
    assert f"cell {i},{j}: speed" in out
    assert (archive_run / "figures_archive" / "archive.png").stat().st_size > 10_000
    assert (archive_run / "figures_archive" / "archive_progress.png").stat().st_size > 10_000


@pytest.mark.parametrize("args, words", [
    (("replay", "{run}", "--cell", "19,0"), "cell 19,0 holds no elite"),
    (("replay", "{run}", "--cell", "x"), "--cell: expected I,J"),
    (("gait", "{run}", "--speed", "3.5"), "speed 3.5 m/s is outside the archive's walking gaits ("),
    (("gait", "{run}", "--speed", "0.5", "--turning", "80"), "turning rate 80 deg/s is outside"),
    (("gait", "{run}", "--speed", "0.5", "--correction", "-1"), "--correction: must be a finite number >= 0 s"),
    (("gait", "{run}", "--speed", "0.5", "--ramp-down", "nan"), "--ramp-down: must be a finite number"),
    (("gait", "{run}", "--speed", "0.5", "--overshoot", "1"), "--overshoot: must be a fraction in [0, 1)"),
    (("adapt", "{run}", "--damage", "weak:left_elbow:0.5"), "the reil body has no joint 'left_elbow' (its joints: "
                                                            "left_hip_pitch"),
    (("adapt", "{run}", "--damage", "short:middle:0.05"), "has no leg 'middle' (its legs: left, right)"),
    (("adapt", "{run}", "--damage", "weak:left_knee:1.5"), "F must be a fraction 0 to 1"),
])
def test_bad_input_one_line_exit_2_nothing_written(archive_run, capsys, args, words):
    before = sorted(p.name for p in archive_run.rglob("*"))
    assert cli(*(a.format(run=archive_run) for a in args)) == 2
    err = capsys.readouterr().err.strip()
    assert words in err and "\n" not in err
    assert sorted(p.name for p in archive_run.rglob("*")) == before


def test_the_speed_knob_walks_the_elites_own_speed_and_switches_without_stopping(archive_run):
    """Open loop, the first stretch, as long as the archive's episodes, is the elite's own evaluation: its speed bit
    for bit; the second stretch runs on from there with the other elite's parameters (not a restart: its speed
    differs from that elite's own evaluation)."""
    rep = load(archive_run)
    walk = np.flatnonzero(rep.walking())
    slow = walk[np.argmin(rep.measure("speed")[walk])]
    v, w = rep.measure("speed")[slow], rep.measure("turning")[slow]
    s = follow(rep, [v, float(rep.measure("speed")[walk].max())], rep.episode.seconds, turning=w, correction=0.0)
    assert s[0].elite == slow and s[0].measured == s[0].archive_speed == v and s[0].up
    assert s[1].elite != slow and s[1].measured != s[1].archive_speed


def test_the_knob_tracks_a_threefold_range_of_speeds_on_the_shipped_repertoire():
    """On the shipped archive, 0.21 -> 0.63 -> 0.21 m/s in steps of about 0.1 m/s, 10 s each: with the distance loop
    every stretch's mean speed is within 10 % of its command and the walker never falls; open loop (the knob asking
    for the command itself) the stretches after a change are further off, as an elite walks faster on the move than
    its mean from a standing start."""
    rep = load(WALKERS.parent / "repertoire")
    schedule = [0.21, 0.3, 0.4, 0.5, 0.63, 0.5, 0.4, 0.3, 0.21]
    closed = follow(rep, schedule, 10.0)
    assert all(s.up for s in closed) and max(s.error for s in closed) < 0.10
    assert max(s.commanded for s in closed) / min(s.commanded for s in closed) >= 3.0
    assert max(s.error for s in follow(rep, schedule, 10.0, correction=0.0)) > 0.10


def test_damage_changes_the_model_as_named():
    """weak: the actuator's stiffness and damping times F; short: the foot 5 cm higher in the initial pose; locked:
    the knee within 5 mrad of its initial angle after 1 s of walking (it bends 0.33 rad unlocked)."""
    genome, cfg, _ = load_genome(SEED5)
    cfg = dataclasses.replace(cfg, seconds=1.0)
    intact = damaged_episode(cfg, None).model
    weak = damaged_episode(cfg, parse_damage("weak:left_knee:0.3", cfg)).model
    a = intact.actuator("left_knee").id
    assert weak.actuator_gainprm[a, 0] == pytest.approx(0.3 * intact.actuator_gainprm[a, 0])
    assert weak.actuator_biasprm[a, 1] == pytest.approx(0.3 * intact.actuator_biasprm[a, 1])
    assert np.array_equal(np.delete(weak.actuator_gainprm, a, 0), np.delete(intact.actuator_gainprm, a, 0))
    ep = damaged_episode(cfg, parse_damage("short:left:0.05", cfg))
    s = ep.sims(1)
    ep.body.reset(s)
    left, right = (s.site_xpos[0, ep.model.site(f"{leg}_foot").id, 2] for leg in ("left", "right"))
    assert left - right == pytest.approx(0.05, abs=1e-9)
    for damage, most in ((None, None), ("locked:right_knee", 5e-3)):
        ep = damaged_episode(cfg, damage and parse_damage(damage, cfg))
        adr = ep.model.jnt_qposadr[ep.model.joint("right_knee").id]
        st = ep.start(genome[None])
        q0 = st.sims.qpos[0, adr]
        ep.advance(st, 1.0)
        moved = abs(st.sims.qpos[0, adr] - q0)
        assert moved < most if most else moved > 0.1


def test_prior_distance_is_the_chord_of_the_circle():
    assert prior_distance(np.array([0.5]), np.array([0.0]), 50.0)[0] == 25.0
    # a full circle
    assert prior_distance(np.array([0.5]), np.array([360 / 50]), 50.0)[0] == pytest.approx(0.0, abs=1e-12)
    r = 0.5 / np.radians(360 / 100)  # half a circle: the diameter
    assert prior_distance(np.array([0.5]), np.array([360 / 100]), 50.0)[0] == pytest.approx(2 * r)


def test_the_gp_after_one_trial_and_the_search_on_a_known_damage():
    """One observation: mu = P + k(x, x1) / (1 + noise) (y1 - P(x1)), s^2 = 1 - k^2 / (1 + noise).  The search on a
    line of 50 gaits whose best half is broken (performance 0): it tries the prior's best first and stops at the
    first trial reaching 0.9 of the best posterior mean (Cully's rule; performances in units of the best prior, 2),
    an unbroken gait, within a few trials; on an intact body it stops after one; only an acceptable trial ends it."""
    x = np.linspace(0, 1, 50)[:, None]
    prior = 1 + x[:, 0]  # the fastest gaits at the right
    mean, sd = posterior(x, prior, [49], np.array([0.2]), rho=0.15, noise=1e-3)
    k = matern52(x, x[[49]], 0.15)[:, 0]
    assert np.allclose(mean, prior + k / (1 + 1e-3) * (0.2 - 2.0))
    assert np.allclose(sd, np.sqrt(1 - k**2 / (1 + 1e-3)))
    true = np.where(x[:, 0] > 0.5, 0.0, prior)
    trials = TrialAndError().run(x, prior, lambda k: (float(true[k]), false_if(true[k]), 50.0, 50.0))
    assert trials[0].elite == 49 and true[trials[-1].elite] > 0 and len(trials) <= 6
    tried = [t.elite for t in trials]
    after, _ = posterior(x, prior / 2, tried, np.array([t.performance for t in trials]) / 2, rho=0.15, noise=1e-3)
    before, _ = posterior(x, prior / 2, tried[:-1], np.array([t.performance for t in trials[:-1]]) / 2, rho=0.15,
                          noise=1e-3)
    assert trials[-1].performance / 2 >= 0.9 * after.max() and max(t.performance
                                                                   for t in trials[:-1]) / 2 < 0.9 * before.max()
    assert len(TrialAndError().run(x, prior, lambda k: (float(prior[k]), False, 50.0, 50.0))) == 1
    # only an acceptable trial (here: performance >= 1.45, gaits 22 to 24) may end the search
    strict = TrialAndError().run(x, prior, lambda k: (float(true[k]), false_if(true[k]), 50.0, 50.0),
                                 acceptable=lambda t: t.performance >= 1.45)
    assert strict[-1].performance >= 1.45 > max(t.performance for t in strict[:-1]) and len(strict) <= 20


def test_the_baseline_orders_try_elites_by_prior_or_at_random_and_stop_by_the_same_rule():
    """``prior`` tries the untried elite with the best prior whatever the trials showed; ``random`` a permutation drawn
    from its seed (another seed, another order); both stop by Cully's rule on the GP's posterior, as ``ucb`` does (an
    intact body: after one trial), and never try an elite twice, even when trials outnumber the elites."""
    x = np.linspace(0, 1, 50)[:, None]
    prior = 1 + x[:, 0]
    broken = lambda k: (0.0, True, 1.0, 50.0)  # noqa: E731: every trial falls at once
    by_prior = TrialAndError(order="prior").run(x, prior, broken)
    assert [t.elite for t in by_prior] == list(range(49, 29, -1))
    first = [t.elite for t in TrialAndError(order="random", seed=1).run(x, prior, broken)]
    assert first == list(np.random.default_rng(1).permutation(50)[:20])
    assert first != [t.elite for t in TrialAndError(order="random", seed=2).run(x, prior, broken)]
    intact = lambda k: (float(prior[k]), False, 50.0, 50.0)  # noqa: E731
    assert [len(TrialAndError(order=o).run(x, prior, intact)) for o in ("ucb", "prior")] == [1, 1]
    assert len(TrialAndError(order="random", trials=80).run(x[:5], prior[:5], broken)) == 5
    with pytest.raises(ValueError, match="order must be one of ucb, prior, random"):
        TrialAndError(order="best")


def test_noisy_trials_are_drawn_per_trial_and_seed(capsys):
    """``--pose-noise``: the same seed gives the same search, another seed other trials; no noise is the nominal search.
    ``--kappa`` below 0 and an unknown ``--order``: one line, exit 2."""
    args = (WALKERS.parent / "repertoire", "--damage", "weak:left_knee:0.5", "--trials", "2", "--order", "prior")
    runs = []
    for extra in (("--pose-noise", "0.05", "--seed", "1"), ("--pose-noise", "0.05", "--seed", "1"),
                  ("--pose-noise", "0.05", "--seed", "2"), ()):
        assert cli("adapt", *args, *extra) == 0
        runs.append([line.split(": ", 1)[1] for line in capsys.readouterr().out.splitlines()
                     if line.strip().startswith("trial ")])
    assert runs[0] == runs[1] and runs[0] != runs[2] and runs[3] != runs[0]
    for bad in (("--kappa", "-1"), ("--order", "best")):
        assert cli("adapt", *args, *bad) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "error: argument --" in err


def false_if(performance: float) -> bool:
    return performance == 0.0


def test_the_knob_switches_to_the_gait_most_like_the_current_one():
    """Among the walking elites within 5 % of the commanded speed, ``like`` picks the genome nearest the current
    elite's; without it, the nearest in speed and turning."""
    from pathlib import Path

    from evobiped.episode import EpisodeConfig
    from evobiped.files.rundir.archive_file import Archive
    from evobiped.repertoire.elites import Repertoire

    g = np.array([[0.0, 0.0], [1.0, 1.0], [0.1, 0.2], [0.15, 0.1]])  # A far from D, B far, C near D
    values = np.array([[0.5, 0.0], [0.51, 0.0], [0.49, 1.0], [0.3, 0.0]])
    arch = Archive(Path("a.json"), ("speed", "turning"), np.array([0.0, -30.0]), np.array([1.0, 30.0]), (20, 60),
                   np.array([[10, 30], [10, 31], [9, 31], [6, 30]]), values, np.full(4, 20.0), np.zeros(4, bool),
                   np.full(4, 20.0), g, np.zeros((1, 3)))
    rep = Repertoire(Path("."), arch, EpisodeConfig(seconds=20.0))
    assert rep.nearest(0.5, 0.0) == 0 and rep.nearest(0.5, 0.0, like=3) == 2
    assert rep.nearest(0.3, 0.0, like=1) == 3  # the only gait within 5 %


def test_hysteresis_pairs_each_command_held_on_the_way_up_with_the_same_command_on_the_way_down():
    """0.2 -> 0.4 -> 0.6 -> 0.4 -> 0.2 and a repeat of the peak: the pairs are (0.2: 1st, 5th) and (0.4: 2nd, 4th);
    the peak and a speed held only once are no pair."""
    s = [Stretch(v, elite, v, measured, True) for v, elite, measured in
         ((0.2, 1, 0.21), (0.4, 2, 0.41), (0.6, 3, 0.6), (0.6, 4, 0.61), (0.4, 5, 0.45), (0.2, 6, 0.25), (0.3, 7, 0.3))]
    got = [(v, up.elite, down.elite, down.measured - up.measured) for v, up, down in hysteresis(s)]
    assert got == [(0.2, 1, 6, pytest.approx(0.04)), (0.4, 2, 5, pytest.approx(0.04))]


def test_a_shipped_archive_is_never_written_into(tmp_path, monkeypatch, capsys):
    """docs/repertoire is an archive without a run of its own (no config.json): its figures and an elite's replay go to
    runs/repertoire/ under the current directory, and nothing is added to or changed in the shipped folder."""
    shipped = WALKERS.parent / "repertoire"
    before = {p.name: p.stat().st_mtime_ns for p in shipped.iterdir()}
    monkeypatch.chdir(tmp_path)
    assert cli("repertoire", shipped) == 0
    assert cli("replay", shipped, "--cell", "20,29", "--quiet") == 0
    assert "the replay equals it bit for bit" in capsys.readouterr().out
    assert {p.name: p.stat().st_mtime_ns for p in shipped.iterdir()} == before
    made = sorted(str(p.relative_to(tmp_path)) for p in (tmp_path / "runs").rglob("*.*"))
    assert made == ["runs/repertoire/figures_archive/archive.png",
                    "runs/repertoire/figures_archive/archive_progress.png", "runs/repertoire/replay_cell_20_29.rrd"]
