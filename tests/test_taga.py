"""The Taga biped and its Matsuoka rhythm generator against Taga, Yamaguchi & Shimizu 1991
(walking, running, push recovery, the rhythm generator), the stride metrics on synthetic contact sequences, and the
CLI."""

import re

import numpy as np
import pytest

from evobiped.experiments.taga import stride
from evobiped.experiments.taga import generator, protocols, walking
from evobiped.experiments.taga.parameters import preset_genome
from evobiped.bodies.taga import TagaBiped
from evobiped.cli import main
from evobiped.controllers.matsuoka import Matsuoka, taga_feedback
from evobiped.core.errors import UserError
from evobiped.physics.sim import Sims

from .conftest import ActionRecorder


# ---------------------------------------------------------------- structure
def test_model_masses_and_rod_inertias():
    body = TagaBiped()
    m = body.build_model()
    mass = {m.body(i).name: m.body_mass[i] for i in range(m.nbody)}
    assert (mass["hip"], mass["right_thigh"], mass["right_shank"]) == (48.0, 7.0, 4.0)
    assert m.body_inertia[m.body("left_thigh").id][1] == pytest.approx(7 * 0.5**2 / 12)
    assert m.body_inertia[m.body("left_shank").id][1] == pytest.approx(4 * 0.6**2 / 12)
    assert m.nv == 6 and m.opt.timestep == 0.0005


def test_initial_condition_is_appendix_e():
    body = TagaBiped()
    sims = Sims(body.build_model(), 1)
    body.reset(sims)
    k = body.links(sims)
    assert np.allclose(k["thigh"][0], [0.45 * np.pi, 0.57 * np.pi])
    assert np.allclose(k["shank"][0], k["thigh"][0])
    # x_10 = x_2 - l1 sin x_5 - (l2/2) sin x_11, so the ankle is l2/2 lower
    ankle_y = 1.09 - 1.1 * np.sin(np.array([0.45, 0.57]) * np.pi)
    assert np.allclose(k["ankle"][0, :, 1], ankle_y)
    assert np.allclose(k["ankle"][0, :, 0], 1.1 * np.cos(np.array([0.45, 0.57]) * np.pi))


def test_standing_ground_spring_carries_the_weight():
    """Legs straight down, no torques: the ground springs settle at m g / (2 k_g) per leg."""
    body = TagaBiped()
    sims = Sims(body.build_model(), 1)
    body.reset(sims)
    sims.qpos[0, :] = [0, 1.1, 0, 0, 0, 0]
    sims.forward()
    for _ in range(6000):  # 3 s
        body.apply(sims, np.array([0]), np.zeros((1, 6)))
        body.substep(sims, np.array([0]))
        sims.step(np.array([0]), 1)
    total = 48 + 2 * (7 + 4)
    f = body.sensors(sims)["ground_force"][0]
    assert f[1] + f[3] == pytest.approx(total * 9.8, rel=1e-3)
    assert body.hip_height(sims)[0] == pytest.approx(1.1 - total * 9.8 / (2 * 1e4), abs=2e-4)


def _step(body, sims, torque, n):
    ids = np.arange(sims.n)
    for _ in range(n):
        body.apply(sims, ids, np.broadcast_to(torque, (sims.n, 6)))
        body.substep(sims, ids)
        sims.step(ids, 1)


def test_ankle_torque_acts_only_in_contact_and_rest_point_is_the_touchdown_point():
    body = TagaBiped()
    sims = Sims(body.build_model(), 2)
    body.reset(sims)
    sims.qpos[:, :2] = [0.0, 1.2]  # both ankles ~0.1 m above the ground
    sims.qvel[:, 0] = 1.0  # moving forward
    sims.forward()
    ankle_torque = np.array([0, 0, 300.0, 0, 0, 300.0])
    body.apply(sims, np.array([0]), ankle_torque[None])
    body.apply(sims, np.array([1]), np.zeros((1, 6)))
    _step(body, sims, np.zeros(6), 0)
    ids = np.arange(2)
    for _ in range(20):  # 10 ms in the air: the ankle torque does nothing
        body.apply(sims, ids[:1], ankle_torque[None])
        body.apply(sims, ids[1:], np.zeros((1, 6)))
        body.substep(sims, ids)
        sims.step(ids, 1)
    assert np.array_equal(sims.qpos[0], sims.qpos[1])
    st = body._ground(sims)
    while not st["contact"][1].any():  # fall to the ground
        x_before = body.links(sims)["ankle"][1, :, 0].copy()
        _step(body, sims, np.zeros(6), 1)
    leg = int(np.flatnonzero(st["contact"][1])[0])
    k = body.links(sims)
    # the rest point is where this ankle first went below the ground, not the origin
    # (contact is tested on the state before each physics step, the one x_before saw)
    assert st["rest"][1, leg, 0] == pytest.approx(x_before[leg], abs=1e-12) and x_before[leg] > 0.2
    assert abs(k["ankle"][1, leg, 0] - x_before[leg]) < 1e-3
    assert st["rest"][1, leg, 1] == 0.0
    _step(body, sims, np.zeros(6), 10)
    f = body.sensors(sims)["ground_force"][1]
    assert f[2 * leg] < 0  # the horizontal spring-damper resists the forward slide
    assert f[2 * leg + 1] > 0


def test_knee_stop_is_a_one_sided_spring():
    """A hyperextended knee (x5 - x11 = 0.02 rad) feels k_k * 0.02 = 200 N m back towards flexion."""
    body = TagaBiped()
    sims = Sims(body.build_model(), 1)
    body.reset(sims)
    sims.qpos[0] = [0, 2.0, 0, -0.02, 0, 0.02]  # right knee hyperextended, left flexed; far above the ground
    sims.forward()
    body.apply(sims, np.array([0]), np.zeros((1, 6)))
    body.substep(sims, np.array([0]))
    q = sims.qfrc_applied[0]
    assert q[3] == pytest.approx(10000.0 * 0.02)  # right knee: pushed back (towards flexion)
    assert q[5] == 0.0  # left knee flexed: no stop force
    assert q[2] == 0.0 and q[4] == 0.0  # thighs vertical and at rest: no hip friction


def test_taga_weights_from_j_to_i():
    c = Matsuoka(n_outputs=6, actuators=TagaBiped.actuators)
    W = c.decode(preset_genome(c)[None])["W"][0]
    order = c._taga_order  # Taga's neuron k (0-based) -> internal index
    Wt = W[np.ix_(order, order)]  # Taga numbering
    fe = [(1, 2), (2, 1), (3, 4), (4, 3), (5, 6), (6, 5), (7, 8), (8, 7), (9, 10), (10, 9), (11, 12), (12, 11)]
    rl = [(1, 3), (3, 1), (2, 4), (4, 2)]
    hka = [(6, 1), (6, 2), (8, 3), (8, 4), (10, 1), (10, 2), (12, 3), (12, 4)]
    expect = np.zeros((12, 12))
    for pairs, w in ((fe, -2.0), (rl, -1.0), (hka, -1.0)):
        for i, j in pairs:
            expect[i - 1, j - 1] = w
    assert np.array_equal(Wt, expect)


def test_feedback_eed6_reads_x14_minus_half_pi():
    a = np.array([[1.5, 1.0, 1.5, 1.5, 3.0, 1.5, 3.0, 1.5]])
    angles = np.array([[1.5, 1.6, 1.7, 1.8]])  # x5, x11, x8, x14
    f = taga_feedback(a, angles, np.zeros((1, 4)), np.array([[1.0, 1.0]]))[0]
    assert f[5] == pytest.approx(3.0 * (1.8 - np.pi / 2))
    assert f[4] == -f[5] and f[6] == -f[7]
    # flexor and extensor of each hip receive opposite angle feedback; contact terms +-a4
    assert f[0] + f[1] == pytest.approx(0.0) and f[0] - f[1] == pytest.approx(2 * (1.5 * (1.5 - np.pi / 2) - 1.0 * (
        1.7 - np.pi / 2) + 1.5 * (1.6 - np.pi / 2) + 1.5))


# ---------------------------------------------------------------- stride metrics
def _sequence(pattern, dt=0.001):
    """Contacts (T, 2) from [(duration s, right, left), ...] repeated; feet move 0.5 m per touchdown."""
    rows = [(r, l) for d, r, l in pattern for _ in range(int(round(d / dt)))]
    c = np.array(rows, bool)
    t = np.arange(len(c)) * dt
    td = np.concatenate([[0], np.cumsum(c[1:, 0] & ~c[:-1, 0])])
    foot = np.stack([td * 1.0, td * 1.0], 1)
    return t, c, foot, np.full(len(t), 1.0)


def test_metrics_walk_synthetic():
    # 1.0 s cycle: right stance 0.6 s, 0.1 s double support twice
    cycle = [(0.1, 1, 1), (0.4, 1, 0), (0.1, 1, 1), (0.4, 0, 1)]
    t, c, x, h = _sequence(cycle * 6)
    m = stride.analyse_strides(t, c, x, h)
    assert m.gait == "walk" and m.strides == 4  # 5 touchdowns after t = 0
    assert m.cycle_duration == pytest.approx(1.0, abs=2e-3)
    assert m.stride_length == pytest.approx(1.0)
    assert m.speed == pytest.approx(1.0, abs=3e-3)
    assert m.double_support == pytest.approx(0.2, abs=0.01) and m.flight == 0.0


def test_metrics_run_synthetic_with_touchdown_bounce():
    # 0.8 s cycle, 0.1 s flight twice; a 3 ms bounce at each right touchdown is removed
    cycle = [(0.003, 1, 0), (0.003, 0, 0), (0.294, 1, 0), (0.1, 0, 0), (0.3, 0, 1), (0.1, 0, 0)]
    t, c, x, h = _sequence(cycle * 6)
    m = stride.analyse_strides(t, c, x, h, min_phase=0.01)
    assert m.gait == "run" and m.strides == 4
    assert m.cycle_duration == pytest.approx(0.8, abs=2e-3)
    assert m.flight == pytest.approx(0.25, abs=0.01) and m.double_support == 0.0
    raw = stride.analyse_strides(t, c, x, h, min_phase=0.0)
    assert raw.strides == 10  # the bounces count as touchdowns without cleaning


def test_metrics_mixed_and_too_short():
    walk = [(0.1, 1, 1), (0.4, 1, 0), (0.1, 1, 1), (0.4, 0, 1)]
    run = [(0.3, 1, 0), (0.1, 0, 0), (0.3, 0, 1), (0.1, 0, 0)]
    t, c, x, h = _sequence(walk * 3 + run * 3)
    assert stride.analyse_strides(t, c, x, h).gait == "mixed"
    t, c, x, h = _sequence(walk)
    assert stride.analyse_strides(t, c, x, h).gait == "none"


# ---------------------------------------------------------------- the paper's claims
@pytest.fixture(scope="module")
def walk_and_run():
    """u0 = 5.5 (walking) and 7.5 (running, the lowest u0 that runs from Appendix E), 20 s."""
    return protocols.steady([5.5, 7.5], seconds=20.0, window=10.0)


def test_claim1_walks_20s_with_double_support_and_no_flight(walk_and_run):
    _, (m, _) = walk_and_run
    assert not m["fell"] and m["gait"] == "walk"
    assert m["strides"] >= 8 and m["strides_with_double_support"] == m["strides"]
    assert m["flight"] == 0.0 and 0.05 < m["double_support"] < 0.3
    assert 1.0 < m["speed"] < 1.6 and 0.9 < m["cycle_duration"] < 1.3  # Fig. 11 range at u0 = 5.5
    assert 0.95 < m["hip_min"] < m["hip_max"] < 1.1


def test_claim2_larger_u0_runs(walk_and_run):
    _, (walk, run) = walk_and_run
    assert not run["fell"] and run["gait"] == "run"
    assert run["strides_with_flight"] == run["strides"] >= 8 and run["double_support"] == 0.0
    assert run["flight"] > 0.1
    assert run["speed"] > walk["speed"] and run["stride_length"] > walk["stride_length"]
    assert run["cycle_duration"] < walk["cycle_duration"]


def test_claim7_isolated_generator_is_slower_than_walking(walk_and_run):
    w, (m, _) = walk_and_run
    entrained = generator.walking_hip_period(w, t_start=10.0)
    assert entrained == pytest.approx(m["cycle_duration"], abs=0.01)  # the generator is entrained to the stride
    isolated = generator.isolated_period(5.5)
    assert np.isfinite(isolated) and isolated > 1.5 * entrained


@pytest.mark.parametrize("target,force,delay", [("right_shank", 200.0, 0.05), ("hip", 288.0, 0.3)])
def test_claim4_push_recovery(target, force, delay):
    _, (r,) = protocols.push(target, force, [delay], before=6.0, after=6.0)
    assert not r["fell"]
    dev = max(abs(L / r["stride_length_before"] - 1) for L, _ in r["strides_after"][:3])
    assert dev > 0.05  # the push did disturb the strides
    assert r["strides_to_recover"] is not None and r["strides_to_recover"] <= 3


def test_a_push_that_fells_every_walker_ends_and_reports_the_fall():
    # an all-down batch stops its clock: the push loop must not wait for a time that never comes
    _, (r,) = protocols.push("hip", 5000.0, [0.0], before=2.0, after=0.5)
    assert r["fell"] and r["t_push"] < r["fell_at"] < r["t_push"] + 0.7 and r["strides_to_recover"] is None


# ---------------------------------------------------------------- CLI
def test_cli_push_on_a_walker_that_falls_first_says_so(capsys):
    import json

    assert main(["taga", "--push", "hip", "--u0", "1.5", "--quiet"]) == 0  # u0 = 1.5 falls within a second
    out, err = capsys.readouterr()
    assert "not given, the walker fell at 0.9" in out and "before the push" in out and err == ""
    assert main(["taga", "--push", "hip", "--u0", "1.5", "--quiet", "--json"]) == 0
    r = json.loads(capsys.readouterr().out)  # strict JSON: no NaN
    assert r["fell"] and r["t_push"] is None and r["stride_length_before"] is None


@pytest.mark.parametrize(
    "argv,needle",
    [
        (["--preset", "nope"], "unknown preset"),
        (["--u0", "-1"], "--u0: must be >= 0, got -1.0"),
        (["--bg", "-1"], "--bg: must be a number >= 0 (or a list, one per simulation), got -1.0"),
        (["--timestep", "0.01"], "--timestep: must be in [1e-05, 0.005] s, got 0.01"),
        (["--slope", "60"], "--slope must be in [-50, 50] %, got 60"),
        (["--slope", "-51"], "--slope must be in [-50, 50] %, got -51"),
    ],
)
def test_cli_bad_arguments(argv, needle, capsys):
    assert main(["taga", *argv]) == 2
    err = capsys.readouterr().err.strip()
    assert needle in err and len(err.splitlines()) == 1


def test_cli_reproduce_runs_the_paper_into_the_folder(tmp_path, monkeypatch):
    """``evobiped taga --reproduce DIR --quick --quiet`` hands the folder and both switches to the reproduction."""
    from evobiped.experiments.taga import taga_reproduce

    calls = []
    monkeypatch.setattr(taga_reproduce, "reproduce_taga", lambda out, quick, quiet, say=None:
                        calls.append((out, quick, quiet)))
    assert main(["taga", "--reproduce", str(tmp_path / "r"), "--quick", "--quiet"]) == 0
    assert main(["taga", "--reproduce", str(tmp_path / "r")]) == 0
    assert calls == [(str(tmp_path / "r"), True, True),
                     (str(tmp_path / "r"), False, False)] and (tmp_path / "r").is_dir()


def test_reproduce_tables_format_cells_as_the_summary_shows_them():
    from evobiped.experiments.taga.taga_reproduce import fmt

    assert fmt([{"a": 1.23456, "b": float("nan"), "c": 0.004}, {"a": None, "b": "walk", "c": 3}], ["a", "b", "c"]) == (
        "| a | b | c |\n|---|---|---|\n| 1.235 | - | 0.004 |\n| - | walk | 3 |\n")


def test_cli_json_and_genome_file_replays_the_same_walk(capsys, tmp_path):
    import json

    from evobiped.files.genome_file import load_genome

    f = tmp_path / "taga.json"
    assert main(["taga", "--u0", "5.5", "--seconds", "4", "--window", "3", "--json", "--save-genome", str(f)]) == 0
    out = json.loads(capsys.readouterr().out)
    (w,) = out["walkers"]
    assert w["u0"] == 5.5 and not w["fell"] and w["strides"] >= 2 and w["flight"] == 0.0
    genome, cfg, _ = load_genome(f)
    r = cfg.build().run(genome)
    walker = walking.TagaWalker(5.5)
    walker.advance(4.0)
    assert r.end_position[0, 0] == walker.body.planar_position(walker.sims)[0, 0]


# ---------------------------------------------------------------- pluggability
def test_every_body_controller_pair_runs_or_is_refused_by_the_contract():
    """Every registered body with every registered controller: a pair whose declarations agree runs and gives
    finite fitness; a pair they refuse is one ConfigError before anything is compiled."""
    from evobiped.bodies import BODIES
    from evobiped.interface.contract import Offer, problem
    from evobiped.controllers import CONTROLLERS
    from evobiped.episode import EpisodeConfig
    from evobiped.core.errors import ConfigError
    from evobiped.interface.mapping import MAPS
    from evobiped.core.options import parse

    rng = np.random.default_rng(0)
    ran = []
    for body, bcls in BODIES.items():
        for ctrl, ccls in CONTROLLERS.items():
            cfg = EpisodeConfig(body=body, controller=ctrl, seconds=0.2)
            why = problem(ccls.needs(parse(ccls.Options, {}, "options")), Offer(bcls.actuators, bcls.sensor_widths))
            if why is None and (ccls.output_kind, bcls.action_kind) not in MAPS:  # the outputs' kind is declared too
                with pytest.raises(ConfigError, match=f"controller '{ctrl}' gives {ccls.output_kind} outputs, which "
                                                      f"body '{body}' cannot take"):
                    cfg.layout()
                continue
            if why is not None:
                with pytest.raises(ConfigError, match=re.escape(f"controller '{ctrl}' (body '{body}', task 'walk') "
                                                                f"{why}")):
                    cfg.layout()
                continue
            ep = cfg.build()
            lay = ep.controller.layout
            g = lay.sample(rng, 2)
            r = ep.run(g)
            assert r.fitness.shape == (2,) and np.isfinite(r.fitness).all(), (body, ctrl)
            ran.append((body, ctrl))
    assert len(ran) >= len(BODIES) * 3  # the papers' three controllers drive both bodies


def test_every_body_offers_the_sensors_it_declares():
    """The declared sensor widths (the controller contract) are the widths of the arrays ``sensors`` returns."""
    from evobiped.bodies import BODIES

    for name, cls in BODIES.items():
        body = cls()
        sims = Sims(body.build_model(), 2)
        body.reset(sims)
        got = {k: v.shape for k, v in body.sensors(sims).items()}
        assert got == {k: (2, w) for k, w in cls.sensor_widths.items()}, name


def test_matsuoka_drives_reil_pd_targets_within_range():
    from evobiped.episode import build_episode

    ep = build_episode(body="reil", controller="matsuoka", seconds=1.0)
    assert ep.controller.feedback == "none" and ep.controller.input_names == ()
    grab = ActionRecorder(row=0)
    ep.run(preset_genome(ep.controller), listener=grab)
    a = np.array(grab.seen)
    low, high = ep.low, ep.high
    assert (a >= low).all() and (a <= high).all()
    assert (a.max(0) - a.min(0) > 0.2 * (high - low)).all()  # every joint is driven through its range


def test_replay_records_the_taga_stick_figure(tmp_path, capsys):
    import rerun as rr

    from evobiped.episode import EpisodeConfig
    from evobiped.files.genome_file import save_genome

    cfg = EpisodeConfig(body="taga", controller="matsuoka", seconds=0.5, controller_options={"u0": 5.5})
    ep = cfg.build()
    g = preset_genome(ep.controller)
    save_genome(tmp_path / "taga.json", g, cfg, fitness=float(ep.run(g).fitness[0]))
    out = tmp_path / "taga.rrd"
    assert main(["replay", str(tmp_path / "taga.json"), "--out", str(out)]) == 0
    assert "equals it bit for bit" in capsys.readouterr().out
    paths = {c.entity_path for c in rr.chunk.RrdReader(out).stream()}
    for link in ("hip", "right_thigh", "right_shank", "left_thigh", "left_shank"):
        assert any(link in p for p in paths), link


def test_a_push_acts_at_the_hip_and_at_a_shank_s_centre():
    """Fig. 7's pushes are MuJoCo's applied forces at a body's centre of mass: the hip's point mass and the
    middle of a uniform shank (checked against the Appendix A kinematics, bent legs); "none" removes them."""
    body = TagaBiped()
    sims = Sims(body.build_model(), 2)
    body.reset(sims)
    sims.qpos[:, 2:] = [0.3, 0.5, -0.2, 0.1]
    sims.forward()
    k, m = body.links(sims), sims.model
    for leg, name in enumerate(("right_shank", "left_shank")):
        centre = 0.5 * (k["knee"][:, leg] + k["ankle"][:, leg])
        assert np.allclose(sims.xipos[:, m.body(name).id][:, [0, 2]], centre, atol=1e-12)
    assert np.allclose(sims.xipos[:, m.body("hip").id][:, [0, 2]], k["hip"], atol=1e-12)
    walking.set_push(sims, np.array([1]), "right_shank", 200.0)
    assert sims.xfrc_applied[1, m.body("right_shank").id, 0] == 200.0 and not sims.xfrc_applied[0].any()
    walking.set_push(sims, np.array([1]), "hip", 288.0)
    assert sims.xfrc_applied[1, m.body("hip").id, 0] == 288.0 and np.count_nonzero(sims.xfrc_applied[1]) == 1
    walking.set_push(sims, np.array([1]), "none", 0.0)
    assert not sims.xfrc_applied.any()
    with pytest.raises(UserError, match="push target"):
        walking.set_push(sims, np.array([0]), "knee", 1.0)
