"""Sound-source steering: the ear model, presentations, clamped CPG weights, bad input."""

import dataclasses
import json

import numpy as np
import pytest

from evobiped.cli import main
from evobiped.episode import EpisodeConfig
from evobiped.tasks.sound import ear_signal

from .conftest import WALKERS, cli

E = 0.25  # the Reil pelvis: ears 0.25 m either side of its centre


def ears_facing_x(centre=(0.0, 0.0)):
    c = np.array(centre, float)
    return (c + [0, E])[None], (c - [0, E])[None]  # left ear at +y when facing +x


@pytest.mark.parametrize("D", [0.5, 1.0, 3.0, 10.0, 30.0])
@pytest.mark.parametrize("theta", [-2.0, -0.7, -0.1, 0.3, 1.2, 2.5])
def test_signal_equals_the_closed_form(D, theta):
    """s = 2 D e sin(theta) / (D^2 + e^2) for a source at distance D, bearing theta (left > 0)."""
    left, right = ears_facing_x()
    src = np.array([[D * np.cos(theta), D * np.sin(theta)]])
    assert ear_signal(left, right, src)[0] == pytest.approx(2 * D * E * np.sin(theta) / (D**2 + E**2), rel=1e-12)


def test_signal_vanishes_facing_the_source_flips_across_the_midline_and_grows_nearer():
    left, right = ears_facing_x()
    assert ear_signal(left, right, np.array([[10.0, 0.0]]))[0] == 0.0
    assert ear_signal(left, right, np.array([[10.0, 1.0]]))[0] > 0 > ear_signal(left, right,
                                                                                np.array([[10.0, -1.0]]))[0]
    near = [abs(ear_signal(left, right, np.array([[d * np.cos(0.5), d * np.sin(0.5)]]))[0]) for d in (20, 10, 5, 2, 1)]
    assert all(a < b for a, b in zip(near, near[1:]))


def test_the_walker_hears_with_its_pelvis_ears():
    """At the start (facing +x): a source ahead gives 0, on the left > 0, on the right < 0."""
    ep = EpisodeConfig(task="steer", task_options={"sources": [[10, 0], [0, 10], [0, -10]]}).build()
    sims = ep.sims(3)
    ep.body.reset(sims)
    sims.forward()
    state = ep.task.start(ep.body, sims)
    s = ep.task.sensors(ep.body, sims, state)["sound"][:, 0]
    assert abs(s[0]) < 1e-12 and s[1] > 0.04 and s[2] == pytest.approx(-s[1])
    assert s[1] == pytest.approx(2 * 10 * E / (100 + E**2), rel=1e-6)  # theta = 90 degrees, D = 10 m


def test_fitness_is_the_mean_over_presentations_of_minus_the_distance():
    """Two sources side by side in one batch = each source alone; fitness = -(distance to the source)."""
    genomes = np.random.default_rng(3).uniform(-1, 1, (3, 130))
    genomes[:, 100:110] = np.random.default_rng(4).uniform(0.5, 5, (3, 10))
    both = EpisodeConfig(task="steer", seconds=2.0).build()
    a = EpisodeConfig(task="steer", seconds=2.0, task_options={"sources": [[10, 3]]}).build()
    b = EpisodeConfig(task="steer", seconds=2.0, task_options={"sources": [[10, -3]]}).build()
    r, ra, rb = both.run(genomes), a.run(genomes), b.run(genomes)
    assert np.array_equal(r.fitness, (ra.fitness + rb.fitness) / 2)
    assert np.array_equal(r.fell, ra.fell | rb.fell)
    assert np.array_equal(ra.fitness, -np.linalg.norm(ra.end_position - [10, 3], axis=1))
    assert r.end_position.shape == (3, 2, 2)



# ---- the arrive fitness: every fall costs more than any distance
def arrive_state(position, end_time, seconds=50.0):
    """A steer task (arrive fitness, sources (10, 3) and (10, -3) m) and its state at the end: rows = presentations."""
    from evobiped.tasks.states import SteerState
    from evobiped.tasks.steer import SteerTask

    task = SteerTask(sources=[[10, 3], [10, -3]], fitness="arrive")
    src = task.sources[task.presentation_of(len(position))]
    state = SteerState(start=np.zeros((len(position), 2)), position=np.array(position, float), source=src,
                       near=np.zeros(len(position)), end_time=np.array(end_time, float), seconds=seconds)
    return task, state


def test_arrive_fitness_by_hand():
    """Genome 0 up at (10, 0): 3 m from each source.  Genome 1 ends 3 m from (10, 3), up; at (7, -7) 5 m from
    (10, -3), fallen at 20 s of 50: f = -5 - S (R + c (T - t)) = -5 - 2 (100 + 30) = -265.  Genome 2 ran 150 m
    away, up: its distance counts as R = 100 m."""
    task, state = arrive_state([[10, 0], [10, 0], [10, 0], [7, -7], [160, 3], [10, -3]], [50, 50, 50, 20, 50, 50])
    f = task.fitness(state)
    np.testing.assert_allclose(f, [-3, -3, -3, -265, -100, 0], rtol=0, atol=1e-12)
    F = task.combine(f.reshape(3, 2))
    np.testing.assert_allclose(F, [-3, -(3 + 5) / 2 - (100 + 30), -50], rtol=0, atol=1e-12)
    # the paper's fitness of the same ends: the distance alone, fall or not
    from evobiped.tasks.steer import SteerTask

    paper = SteerTask(sources=[[10, 3], [10, -3]])
    np.testing.assert_allclose(paper.fitness(state), [-3, -3, -3, -5, -150, 0], rtol=0, atol=1e-12)


def test_a_fall_anywhere_scores_below_any_walker_that_stays_up():
    """The worst genome that stays up (both ends capped at R) against the best that falls (on both sources, at
    the last tick before the end): -R > -R - (R + c dt)."""
    task, state = arrive_state([[500, 0], [500, 0], [10, 3], [10, -3]], [50, 50, 50, 49.98])
    F = task.combine(task.fitness(state).reshape(2, 2))
    assert F[0] == -100.0 and F[1] == pytest.approx(-(100 + 0.02)) and F[1] < F[0]
    later = task.combine(task.fitness(arrive_state([[10, 3], [10, -3]], [50, 30])[1]).reshape(1, 2))
    assert later[0] == pytest.approx(-(100 + 20)) and F[1] > later[0]  # a later fall costs less


def test_gait_weights_add_the_weighted_gait_terms_to_each_presentation():
    """gait_weights: each presentation's fitness is the fitness without them plus sum w * term, the gait lab's terms of
    that presentation, which join the task's terms (the same episode otherwise: the distances to the sources agree)."""
    from evobiped.core.options import given
    from evobiped.files.genome_file import load_genome

    genome, cfg, _ = load_genome(WALKERS / "steer_ctrnn_es_seed0.json")
    plain = dataclasses.replace(cfg.nominal(), seconds=4.0)
    weights = {"airborne": -100.0, "sliding": -200.0, "duty_asymmetry": -50.0}
    gaited = dataclasses.replace(plain, task_options={**given(plain.task_options), "gait_weights": weights})
    a, b = plain.build().run(genome[None]), gaited.build().run(genome[None])
    assert np.array_equal(a.terms["distance_to_source"], b.terms["distance_to_source"])
    assert "airborne" not in a.terms and b.terms["airborne"].shape == a.terms["distance"].shape
    added = sum(w * b.terms[k] for k, w in weights.items())  # (1, S): per presentation
    assert added.min() < -1.0  # this skipping walker is in the air and slides: a real penalty
    assert b.fitness[0] == pytest.approx(a.fitness[0] + added.mean(), abs=1e-9)


def test_arrive_fitness_of_real_episodes_follows_the_formula():
    """The six-source walker (up) and random balance controllers (they fall) for 3 s: each genome's fitness is
    the formula of its rows' ends, and the distances are the paper fitness's."""
    from evobiped.files.genome_file import load_genome

    cfg = EpisodeConfig(controller="simbicon", task="steer", seconds=3.0,
                        task_options={"sources": [[6, 2], [5, -4], [9, 0]], "fitness": "arrive", "fall_time_cost": 2.0})
    ep = cfg.build()
    g = ep.controller.layout.sample(np.random.default_rng(7), 8)
    g[0] = load_genome(WALKERS / "steer_simbicon_six_sources.json")[0]
    r = ep.run(g)
    rows = r.rows
    d = np.linalg.norm(rows.end_position - np.tile([[6, 2], [5, -4], [9, 0]], (8, 1)), axis=1)
    assert 0 < rows.fell.sum() < len(rows.fell)
    want = (-d.reshape(8, 3).mean(1) - ((100 + 2.0 * (3.0 - rows.end_time)) * rows.fell).reshape(8, 3).sum(1))
    np.testing.assert_allclose(r.fitness, want, rtol=1e-12)
    paper = dataclasses.replace(cfg, task_options={"sources": [[6, 2], [5, -4], [9, 0]]}).build().run(g).rows
    np.testing.assert_array_equal(paper.fitness, -d)


CPG = "weights,time_constants,biases"
SMALL = ["--population", 6, "--generations", 3, "--episode-seconds", 1.5, "--backend", "serial", "--quiet"]


@pytest.fixture(scope="module")
def walker(tmp_path_factory):
    d = tmp_path_factory.mktemp("walker") / "run"
    assert cli("evolve", "--population", 6, "--generations", 2, "--episode-seconds", 1.5, "--backend", "serial",
               "--out", d, "--quiet") == 0
    return d


def test_clamped_cpg_weights_never_change(walker, tmp_path):
    out = tmp_path / "steer"
    assert cli("evolve", "--task", "steer", "--from", walker, "--freeze", CPG, *SMALL, "--out", out) == 0
    cpg = json.loads((walker / "best.json").read_text())["genome"]
    assert len(cpg) == 120
    pop = np.array(json.loads((out / "checkpoint.json").read_text())["optimizer"]["population"])
    assert pop.shape == (6, 130)
    assert np.all(pop[:, :120] == cpg)  # every individual keeps the walker's CPG
    assert np.any(pop[:, 120:] != 0)  # while the 10 sensory weights evolved
    for f in (out / "generations").iterdir():
        assert json.loads(f.read_text())["genome"][:120] == cpg


def test_unclamped_cpg_weights_do_change(walker, tmp_path):
    out = tmp_path / "free"
    assert cli("evolve", "--task", "steer", "--from", walker, *SMALL, "--generations", 6, "--out", out) == 0
    cpg = np.array(json.loads((walker / "best.json").read_text())["genome"])
    pop = np.array(json.loads((out / "checkpoint.json").read_text())["optimizer"]["population"])
    assert np.any(pop[:, :120] != cpg)


@pytest.mark.parametrize(
    "setup, words",
    [
        ("g3-walker", "is a reil/g3 genome; this run needs reil/ctrnn"),
        ("one-number-source", "sources must be a list of [x, y] positions"),
        ("taga", "the body has no ears"),
        ("bad-freeze", "frozen_blocks ['wings'] are not gene blocks"),
        ("no-sources", "sources must be a list of [x, y] positions"),
        ("bad-fitness", "episode.task_options.fitness: must be one of distance, arrive"),
        ("no-penalty", "episode.task_options.fall_penalty: must be > 0"),
        ("bad-gait-term", "episode.task_options.gait_weights: names no gait term: stride"),
        ("nan-gait-weight", "episode.task_options.gait_weights: must be a table of finite weights"),
    ],
)
def test_bad_input(tmp_path, capsys, setup, words):
    args = ["evolve", "--task", "steer", *SMALL, "--out", tmp_path / "out"]
    if setup == "g3-walker":
        g3 = tmp_path / "g3"
        assert cli("evolve", "--controller", "g3", "--population", 4, "--generations", 1, "--episode-seconds", 0.5,
                   "--backend", "serial", "--out", g3, "--quiet") == 0
        capsys.readouterr()
        args += ["--from", g3]
    elif setup == "one-number-source":
        cfg = tmp_path / "c.toml"
        cfg.write_text("[episode.task_options]\nsources = 3\n")
        args += ["--config", cfg]
    elif setup in ("no-sources", "bad-fitness", "no-penalty", "bad-gait-term", "nan-gait-weight"):
        cfg = tmp_path / "c.toml"
        cfg.write_text("[episode.task_options]\n" + {"no-sources": "sources = []", "bad-fitness": 'fitness = "near"',
                                                     "no-penalty": 'fitness = "arrive"\nfall_penalty = 0',
                                                     "bad-gait-term": "gait_weights = {stride = -1.0}",
                                                     "nan-gait-weight": "gait_weights = {airborne = nan}"}[setup]
                       + "\n")
        args += ["--config", cfg]
    elif setup == "taga":
        args += ["--body", "taga"]
    else:
        args += ["--freeze", "wings"]
    assert cli(*args) == 2
    err = capsys.readouterr().err
    assert words in err and err.count("\n") == 1
    assert not (tmp_path / "out").exists()


def test_replay_records_every_presentation_and_draws_figs_12_13(walker, tmp_path, capsys):
    out = tmp_path / "steer"
    assert cli("evolve", "--task", "steer", "--from", walker, "--freeze", CPG, *SMALL, "--out", out) == 0
    assert cli("replay", out, "--figures", tmp_path / "figs") == 0
    text = capsys.readouterr().out
    assert "equals it bit for bit" in text
    names = sorted(p.name for p in (tmp_path / "figs").iterdir())
    assert "steering_trajectories.png" in names and "steering_neuron.png" in names
    import rerun as rr

    paths = {c.entity_path for c in rr.chunk.RrdReader(out / "replay_best.rrd").stream()}
    assert {"/sensors/sound", "/world/source", "/world/sources"} <= paths
    # every presentation: its path, its source and the ear signal on the way
    assert {f"/{w}presentations/{j}/{x}" for j in (1, 2) for w,
            x in (("world/", "path"), ("world/", "source"), ("", "sound"))} <= paths


# ---- sources on the command line: one presentation each
@pytest.fixture(scope="module")
def hearing_walker(tmp_path_factory):
    """A short steering run of the balance controller (it hears through two genes) on two given sources."""
    out = tmp_path_factory.mktemp("steer") / "run"
    assert main(["evolve", "--controller", "simbicon", "--task", "steer", "--source", "8", "2", "--source", "9", "-4",
                 "--population", "4", "--generations", "1", "--episode-seconds", "2", "--backend", "serial", "--quiet",
                 "--out", str(out)]) == 0
    return out


def test_evolve_takes_its_sources_from_the_command_line(hearing_walker):
    cfg = json.loads((hearing_walker / "config.json").read_text())
    assert cfg["episode"]["task_options"]["sources"] == [[8.0, 2.0], [9.0, -4.0]]


def test_episode_prints_the_final_distance_to_each_source(hearing_walker, capsys):
    from evobiped.files.genome_file import load_genome
    from evobiped.tasks.sound import with_sources

    sources = [[6.0, 0.0], [12.0, 5.0], [3.0, -6.0]]
    argv = [a for q in sources for a in ("--source", str(q[0]), str(q[1]))]
    assert main(["episode", "--genome", str(hearing_walker / "best.json"), *argv, "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    genome, cfg, _ = load_genome(hearing_walker / "best.json")
    for q, row in zip(sources, out["sources"]):  # each presentation alone, on a one-source episode
        alone = with_sources(cfg, [q]).build().run(genome)
        assert row["source"] == q and row["final_distance"] == pytest.approx(np.linalg.norm(alone.end_position[0] - q),
                                                                             abs=1e-12)
    final = [row["final_distance"] for row in out["sources"]]
    assert out["median_final_distance"] == final[int(np.argsort(final)[1])] and out["worst_final_distance"] == max(
        final)
    assert out["falls"] == sum(row["fell"] for row in out["sources"])


@pytest.mark.parametrize("argv, words", [
    (["--source", "3"], "expected 2 arguments"),
    (["--source", "0.2", "-0.1"], "at the walker's start"),
    (["--source", "nan", "1"], "--source: must be a finite number"),
])
def test_bad_sources_are_one_line(hearing_walker, tmp_path, capsys, argv, words):
    for cmd in (["episode", "--genome", str(hearing_walker / "best.json")],
                ["evolve", "--task", "steer", "--out", str(tmp_path / "x")]):
        try:
            rc = main([*cmd, *argv])
        except SystemExit as exc:
            rc = exc.code
        err = capsys.readouterr().err.strip()
        assert rc == 2 and words in err and len(err.splitlines()) == 1
        assert not (tmp_path / "x").exists()


def test_a_source_for_a_walking_task_and_a_two_source_battery_are_refused(hearing_walker, tmp_path, capsys):
    assert main(["episode", "--genome", str(WALKERS / "simbicon_cma_seed5.json"), "--source", "3", "3"]) == 2
    assert main(["evolve", "--source", "3", "3", "--out", str(tmp_path / "y")]) == 2 and not (tmp_path / "y").exists()
    assert main(["robustness", str(hearing_walker), "--seconds", "2", "--push-after", "1", "--quiet"]) == 2
    assert "runs one presentation" in capsys.readouterr().err
    assert main(["robustness", str(hearing_walker), "--seconds", "2", "--push-after", "1", "--quiet", "--source", "8",
                 "2", "--out", str(tmp_path / "b")]) == 0
    assert len(json.loads((tmp_path / "b" / "robustness.json").read_text())["trials"]) == 164


def test_terms_per_presentation_are_the_distances_to_each_source():
    """terms: distance_to_source per row is minus the row's fitness, distance is from the start;
    per genome they come as (P, S), S = 2 sources; the task names the sources as its targets."""
    ep = EpisodeConfig(task="steer", seconds=1.0, task_options={"sources": [[10, 3], [10, -3]]}).build()
    lay = ep.controller.layout
    g = np.clip(np.random.default_rng(2).normal(lay.init_mean, lay.init_sigma, (3, lay.size)), lay.low, lay.high)
    r = ep.run(g)
    np.testing.assert_array_equal(ep.task.targets(), [[10, 3], [10, -3]])
    assert set(r.terms) == set(ep.task.term_names) == {"distance", "distance_to_source"}
    rows = r.rows
    np.testing.assert_array_equal(rows.terms["distance_to_source"], -rows.fitness)
    np.testing.assert_allclose(rows.terms["distance"], np.linalg.norm(rows.end_position - rows.start_position, axis=1),
                               rtol=1e-15)
    assert r.terms["distance_to_source"].shape == (3, 2)
    np.testing.assert_array_equal(r.terms["distance_to_source"].mean(axis=1), -r.fitness)


def test_cyclic_flag_is_refused_for_a_task_without_that_criterion(tmp_path, capsys):
    out = tmp_path / "run"
    assert cli("evolve", "--task", "steer", "--cyclic", "--generations", "1", "--out", out) == 2
    err = capsys.readouterr().err
    assert "--cyclic: the steer task has no cyclic criterion" in err and err.count("\n") == 1 and not out.exists()


def test_the_steer_generalist_preset_is_listed_and_runs(tmp_path, capsys):
    """`evobiped presets` lists it; a one-generation run of it from the six-source walker evolves the arrive
    fitness on its sources with the hearing clipped."""
    assert main(["presets"]) == 0
    listed = {line.split()[0]: line.split(None, 1)[1] for line in capsys.readouterr().out.splitlines()}
    assert listed["steer-generalist"].startswith("Steering to any sound source and arriving standing")
    out = tmp_path / "run"
    assert cli("evolve", "--preset", "steer-generalist", "--from", WALKERS / "steer_simbicon_six_sources.json",
               "--population", 4,
               "--generations", 1, "--episode-seconds", 1.0, "--backend", "serial", "--quiet", "--out", out) == 0
    episode = json.loads((out / "config.json").read_text())["episode"]
    assert episode["task"] == "steer" and episode["task_options"]["fitness"] == "arrive"
    assert len(episode["task_options"]["sources"]) == 8 and episode["controller_options"]["sound_limit"] == 0.1

