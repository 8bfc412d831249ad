"""A steering policy trained over random sources: the declared source distribution (drawn per generation, shared by
every genome), the reward for lingering at the source, moving a walker's genes onto new inputs, and bad input."""

import dataclasses
import json
import tomllib

import numpy as np
import pytest

from evobiped.episode import EpisodeConfig
from evobiped.files.genome_file import load_genome
from evobiped.core.options import given
from evobiped.files.presets import path as preset_path
from evobiped.episode.remap import remap_inputs, remap_norm
from evobiped.tasks.states import SteerState
from evobiped.tasks.steer import SteerTask

from .conftest import WALKERS, cli

SEED = WALKERS / "ctrnn_es_seed5.json"
RANDOM = {"fitness": "arrive", "random_sources": 3, "source_distance": [5.0, 15.0], "source_bearing": [-60.0, 60.0],
          "sources": [[10, 3], [10, -3], [6, 0]]}


def test_a_generation_draws_its_sources_from_the_declared_distribution_and_every_genome_hears_them():
    """The sources of generation (seed, g) lie in the declared ranges, are the same for every call, differ between
    generations; a genome's episode under them equals the same genome with those sources fixed."""
    ep = EpisodeConfig(task="steer", controller="simbicon", seconds=2.0, task_options=RANDOM).build()
    a, b, c = (ep.trials_for(k).sources for k in ((4, 7), (4, 7), (4, 8)))
    assert a.shape == (3, 2) and np.array_equal(a, b) and not np.allclose(a, c)
    d, bearing = np.hypot(*a.T), np.degrees(np.arctan2(a[:, 1], a[:, 0]))
    assert ((5 <= d) & (d <= 15)).all() and (np.abs(bearing) <= 60).all()
    many = np.concatenate([ep.trials_for((0, g)).sources for g in range(40)])
    assert np.hypot(*many.T).min() < 6 and np.hypot(*many.T).max() > 14  # the whole range is drawn
    g = load_genome(WALKERS / "steer_simbicon_seed0.json")[0]
    drawn = ep.run(np.stack([g, g]), trials=ep.trials_for((4, 7)))
    fixed = EpisodeConfig(task="steer", controller="simbicon", seconds=2.0,
                          task_options={**RANDOM, "sources": a.tolist()}).build().run(g)
    assert drawn.fitness[0] == drawn.fitness[1] == pytest.approx(fixed.fitness[0], abs=1e-12)
    assert ep.trials_for(None) is None  # a nominal episode (replay, battery) presents the fixed sources
    from evobiped.tasks.sound import with_sources

    given_sources = with_sources(EpisodeConfig(task="steer", controller="simbicon", task_options=RANDOM), [[6, 0]])
    assert given_sources.build().task.presentations == 1  # --source X Y: fixed sources replace the distribution


def test_lingering_within_reach_is_paid_and_a_fall_stays_below_any_walker_up():
    task = SteerTask(sources=[[10, 0], [5, 5]], fitness="arrive", reach=0.5, reach_bonus=4.0)
    src = task.sources
    state = SteerState(start=np.zeros((2, 2)), position=src + [[0.3, 0.0], [3.0, 0.0]], source=src,
                       near=np.array([50.0, 0.0]), ticks=100, end_time=np.array([30.0, 30.0]), seconds=30.0)
    f = task.fitness(state)
    assert f == pytest.approx([-0.3 + 4.0 * 0.5, -3.0])
    worst_up = task.fitness(dataclasses.replace(state, position=src + 1e3, near=np.zeros(2))).mean()
    best_fall = task.fitness(dataclasses.replace(state, position=src.copy(), near=np.array([100.0, 100.0]),
                                                 end_time=np.array([29.99, 30.0]))).mean()
    assert best_fall < worst_up
    plain = SteerTask(sources=[[10, 0], [5, 5]], fitness="arrive")
    assert plain.fitness(state) == pytest.approx([-0.3, -3.0])  # no reach: the arrive fitness as before


def test_a_walker_moved_onto_reordered_inputs_walks_exactly_as_before():
    """Its heading sense moved from the first input to the last: the input rows follow their names (input weights and
    direct weights), the normaliser too; the episode is the same (to rounding: the sums run in another order)."""
    g, old, _ = load_genome(SEED)
    inputs = list(old.controller_options.inputs)
    opts = {**given(old.controller_options), "inputs": inputs[1:] + inputs[:1]}
    new = dataclasses.replace(old, controller_options=opts)
    new = dataclasses.replace(new, controller_options={**opts,
                                                       "input_norm": remap_norm(old.controller_options.input_norm, old,
                                                                                new)})
    moved = remap_inputs(g, old, new)
    assert not np.array_equal(moved, g)
    a, b = old.build().run(g, seconds=3.0), new.build().run(moved, seconds=3.0)
    assert b.fitness[0] == pytest.approx(a.fitness[0],
                                         rel=1e-9) and np.allclose(a.end_position, b.end_position, rtol=0, atol=1e-9)
    heard = remap_inputs(g, old, new, copy={})
    assert np.array_equal(heard, moved)


def test_the_hearing_start_replaces_the_heading_by_the_ear_signal(tmp_path):
    """evobiped genome hearing-start: the sound rows are minus the heading rows, every other gene the walker's; the
    steer-es preset's episode takes the genome."""
    out = tmp_path / "h.json"
    assert cli("genome", "hearing-start", out, "--walker", SEED) == 0
    g, cfg, _ = load_genome(out)
    old_g, old, _ = load_genome(SEED)
    c, c_old = cfg.build().controller, old.build().controller
    s, s_old = c.layout.slices(), c_old.layout.slices()
    for block in ("input_weights", "direct_weights"):
        rows, rows_old = g[s[block]].reshape(c.n_inputs, -1), old_g[s_old[block]].reshape(c_old.n_inputs, -1)
        assert np.array_equal(rows[0], -rows_old[0])  # sound in heading_error's place
        assert np.array_equal(rows[1:], rows_old[1:])
    assert np.array_equal(g[s["weights"]], old_g[s_old["weights"]])
    table = tomllib.loads(preset_path("steer-es").read_text())
    assert cfg.controller_options.inputs == table["episode"]["controller_options"]["inputs"]


def test_a_walking_network_hears_under_its_own_integration(tmp_path):
    """hearing-start --preset steer-walk from the walking route's network: the steer-walk episode, integrated exactly as
    the walker was evolved; with the source straight ahead 5 km away (s near 0) the hearing walker walks its first 10 s
    as the walker did (within 10 % of its distance: the ear signal is not the heading it held)."""
    walker = WALKERS / "ctrnn_walk_preset_seed1.json"
    out = tmp_path / "h.json"
    assert cli("genome", "hearing-start", out, "--walker", walker, "--preset", "steer-walk") == 0
    g, cfg, _ = load_genome(out)
    old_g, old, _ = load_genome(walker)
    assert cfg.controller_options.integration == old.controller_options.integration == "exponential"
    heard = dataclasses.replace(cfg.nominal(), seconds=10.0,
                                task_options={**given(cfg.task_options), "sources": [[5000.0, 0.0]],
                                              "random_sources": 0})
    walked = dataclasses.replace(old.nominal(), seconds=10.0)
    a, b = heard.build().run(g[None]), walked.build().run(old_g[None])
    assert not a.fell[0] and not b.fell[0] and b.walk()["distance"] > 5.0
    assert a.walk()["distance"] == pytest.approx(b.walk()["distance"], rel=0.1)


@pytest.mark.parametrize("options, words", [
    ({"source_distance": [0.2, 8.0]}, "inside the walker's start"),
    ({"source_bearing": [-200.0, 60.0]}, "[-180, 180]"),
    ({"source_distance": []}, "the distribution is empty"),
    ({"source_distance": [9.0, 5.0]}, "low <= high"),
    ({"sources": [[10, 3]]}, "must be 3 too"),
])
def test_bad_source_distributions_are_refused_with_one_line(tmp_path, capsys, options, words):
    cfg = tmp_path / "c.toml"
    table = {**RANDOM, **options}
    cfg.write_text("[episode]\ntask = \"steer\"\ncontroller = \"simbicon\"\nseconds = 1.0\n[episode.task_options]\n"
                   + "".join(f"{k} = {json.dumps(v)}\n" for k, v in table.items()))
    assert cli("evolve", "--config", cfg, "--generations", "1", "--backend", "serial", "--out", tmp_path / "o") == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and words in err[0], err
    assert not (tmp_path / "o").exists()


def test_offsets_on_a_body_of_torques_are_refused_with_one_line(tmp_path, capsys):
    cfg = tmp_path / "t.toml"
    cfg.write_text('[episode]\nbody = "taga"\ncontroller = "matsuoka"\nseconds = '
                   '1.0\n[episode.perturbations]\ntarget_offset = 0.05\n')
    assert cli("evolve", "--config", cfg, "--generations", "1", "--backend", "serial", "--out", tmp_path / "o") == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "target_offset" in err[0] and "torques" in err[0]
    assert not (tmp_path / "o").exists()


def test_the_distance_cue_is_the_ears_mean_intensity_capped_at_1_and_offered_only_when_asked():
    """loudness = min(1, (1/|l - q|^2 + 1/|r - q|^2) / 2) at the start (ears at (0, +-0.25) m); without the option
    the task offers the ear signal alone (every walker so far reads the same senses)."""
    assert SteerTask().sensor_widths() == {"sound": 1}
    sources = [[10.0, 0.0], [0.0, 2.0], [0.6, 0.0]]
    ep = EpisodeConfig(task="steer", task_options={"sources": sources, "loudness": True}).build()
    sims = ep.sims(3)
    ep.body.reset(sims)
    sims.forward()
    cue = ep.task.sensors(ep.body, sims, ep.task.start(ep.body, sims))["loudness"][:, 0]
    e = 0.25
    by_hand = [1 / (100 + e**2), (1 / (2 - e) ** 2 + 1 / (2 + e) ** 2) / 2, 1.0]  # (0.6, 0): 2.37, capped
    assert cue == pytest.approx(by_hand, rel=1e-6)


def test_a_hearing_walker_given_the_distance_cue_with_zero_weights_walks_as_before():
    """The shipped hearing CTRNN moved onto inputs with loudness added (its rows zero) walks exactly as before; a weight
    on the cue changes the walk (the cue reaches the network)."""
    g, old, _ = load_genome(WALKERS / "steer_ctrnn_es_seed0.json")
    co = {k: v for k, v in given(old.controller_options).items() if k != "input_norm"}
    inputs = list(co["inputs"])
    inputs.insert(1, "loudness")
    new = dataclasses.replace(old, task_options={**given(old.task_options), "loudness": True},
                              controller_options={**co, "inputs": inputs})
    norm = remap_norm(old.controller_options.input_norm, old, new, {"loudness": ([0.0], [0.1])})
    new = dataclasses.replace(new, controller_options={**given(new.controller_options), "input_norm": norm})
    moved = remap_inputs(g, old, new)
    a, b = old.nominal().build().run(g, seconds=4.0), new.nominal().build().run(moved, seconds=4.0)
    assert np.array_equal(a.end_position, b.end_position) and np.array_equal(a.end_time, b.end_time)
    rows, w = new.parts()[1].layout.slices()["direct_weights"], moved.copy()
    # loudness (input 1) to six motors
    w[rows] = np.where(np.arange(rows.stop - rows.start) // 6 == 1, 0.5, moved[rows])
    c = new.nominal().build().run(w, seconds=4.0)
    assert not np.allclose(c.end_position, b.end_position, atol=1e-3)


def test_the_rewired_start_walks_as_before_with_zero_side_weights_and_turns_both_ways_with_them(tmp_path):
    """evobiped genome rewire adds stance_side to the from-scratch walker with zero rows: with its heading sense kept
    it walks exactly as before.  Without the heading sense (which steers it back to its first facing), +-0.2 on the
    side's direct weights to the two hip-roll motors turns it: the two signs turn it opposite ways, each more than
    5 deg/s from the symmetric network's own drift, and both walk the whole 20 s."""
    def rewire(out, *flags):
        assert cli("genome", "rewire", out, "--walker", SEED, *flags) == 0
        return load_genome(out)

    g, old, _ = load_genome(SEED)
    kept, cfg, _ = rewire(tmp_path / "kept.json", "--drop", "since_touchdown", "--add", "since_touchdown", "--add",
                          "stance_side")
    assert cfg.controller_options.inputs[-2:] == ["since_touchdown", "stance_side"]
    a, b = old.nominal().build().run(g, seconds=4.0), cfg.nominal().build().run(kept, seconds=4.0)
    assert np.array_equal(a.end_position, b.end_position) and np.array_equal(a.end_time, b.end_time)

    side, cfg, _ = rewire(tmp_path / "side.json")
    assert "heading_error" not in cfg.controller_options.inputs and cfg.controller_options.inputs[-1] == "stance_side"
    shipped = WALKERS.parent / "repertoire"
    start, start_cfg, _ = load_genome(shipped / "es_turning_start.json")
    assert np.array_equal(start, side) and start_cfg == cfg
    table = tomllib.loads((shipped / "es_turning.toml").read_text())["episode"]["controller_options"]
    assert table["inputs"] == cfg.controller_options.inputs and table["input_norm"] == cfg.controller_options.input_norm
    cfg = dataclasses.replace(cfg, task_options={**given(cfg.task_options), "gait_measures": True})
    c = cfg.parts()[1]
    block = c.layout.slices()["direct_weights"]
    genomes = np.tile(side, (3, 1))
    for row, w in ((1, 0.2), (2, -0.2)):
        rows = genomes[row, block].reshape(c.n_inputs, -1)
        rows[-1] = w * np.array([0, 1, 0, 0, -1, 0])  # left and right hip roll
        genomes[row, block] = rows.ravel()
    r = cfg.nominal().build().run(genomes)
    turning = r.terms["turning"]
    assert not r.fell.any() and (r.end_time == 20.0).all()
    assert (turning[1] - turning[0]) * (turning[2] - turning[0]) < 0
    assert min(abs(turning[1] - turning[0]), abs(turning[2] - turning[0])) > 5.0


def test_stance_side_is_read_only_when_named_and_the_stance_frame_leaves_its_sign():
    """A stance-frame controller's default inputs leave stance_side out; named, it reads +1 on the left stance row and
    -1 on the right one (normalised by 1), while stance_leg reads +1 on both (the frame mirrors it)."""
    base = dict(body="reil", controller="linear", task="walk", seconds=1.0, task_options={"fitness": "weighted"})
    default = EpisodeConfig(**base, controller_options={"frame": "stance"}).build().controller
    assert "stance_leg" in default.input_names and "stance_side" not in default.input_names
    ep = EpisodeConfig(**base, controller_options={"frame": "stance", "inputs": ["stance_leg", "stance_side"]}).build()
    state = ep.start(np.zeros((2, ep.controller.layout.size)))
    state.sims.extra["gait"] = {"stance": np.array([0, 1]), "touchdown": np.zeros(2), "lifted": np.full((2, 2), np.inf)}
    inputs, flip = ep._inputs(state, 2)
    assert flip.tolist() == [False, True]
    assert inputs.tolist() == [[1.0, 1.0], [1.0, -1.0]]
