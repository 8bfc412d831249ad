"""A biped from an MJCF file and its declaration (``--body mjcf:PATH``): the derived body against the hand-written
Reil body (the same model declared reads the same senses and walks the same episode to the last bit), the box
biped's senses, mirror, feet and constants against the simulation, and bad declarations refused one line each."""

import shutil

import numpy as np
import pytest

from evobiped.bodies import ReilBiped, body_class
from evobiped.core.errors import ConfigError
from evobiped.episode import EpisodeConfig
from evobiped.physics.models import model_path
from evobiped.physics.sim import Sims

from .conftest import cli

REIL_DECLARATION = """\
pelvis = "pelvis"
joints = ["hip_pitch", "hip_roll", "knee"]
knee = "knee"
fall_height = 0.5
[legs.left]
actuators = ["left_hip_pitch", "left_hip_roll", "left_knee"]
foot = "left_foot"
[legs.right]
actuators = ["right_hip_pitch", "right_hip_roll", "right_knee"]
foot = "right_foot"
"""
SENSES = ["joint_angles", "joint_velocities", "pelvis_tilt", "pelvis_tilt_rate", "com_from_feet", "com_velocity"]


@pytest.fixture()
def declared_reil(tmp_path):
    """``mjcf:`` name of the Reil model declared beside a copy of it."""
    shutil.copy(model_path("reil_biped"), tmp_path / "reil_biped.xml")
    (tmp_path / "reil_biped.toml").write_text(REIL_DECLARATION)
    return f"mjcf:{tmp_path / 'reil_biped.xml'}"


def _walked(ep, seed=3):
    """A walked, asymmetric state of one row (not the symmetric reset): joints, rates and the pelvis disturbed."""
    state = ep.start(np.zeros((1, ep.controller.layout.size)) + ep.controller.layout.init_mean)
    rng = np.random.default_rng(seed)
    sims = state.sims
    sims.qpos[:, 7:] += rng.normal(0, 0.2, sims.qpos[:, 7:].shape)
    sims.qvel[:] = rng.normal(0, 0.5, sims.qvel.shape)
    sims.qpos[0, 2] -= 0.1
    quat = np.array([1.0, 0.08, -0.05, 0.3])
    sims.qpos[0, 3:7] = quat / np.linalg.norm(quat)
    sims.forward()
    return sims


def test_the_reil_model_declared_reads_the_hand_written_bodys_senses_and_walks_its_episode_bit_for_bit(declared_reil):
    cls = body_class(declared_reil)
    assert cls.actuators == ReilBiped.actuators and cls.action_kind == "position"
    assert all(np.array_equal(a, b) for a, b in zip(cls().action_bounds(), ReilBiped().action_bounds()))
    assert cls.mirror == ReilBiped.mirror and cls.actuator_mirror == ReilBiped.actuator_mirror
    assert set(cls.sensor_widths) == set(ReilBiped.sensor_widths)
    hand = EpisodeConfig(body="reil", controller="ctrnn", seconds=1.0).build()
    made = EpisodeConfig(body=declared_reil, controller="ctrnn", seconds=1.0).build()
    a, b = hand.body.sensors(_walked(hand)), made.body.sensors(_walked(made))
    for name in SENSES:
        assert np.array_equal(a[name], b[name]), name
    fa, fb = hand.body.feet(_walked(hand)), made.body.feet(_walked(made))
    for field in ("slip", "height", "knee", "power", "torque"):
        assert np.allclose(getattr(fa, field), getattr(fb, field), rtol=0, atol=1e-12), field
    assert hand.body.gait_constants(hand.model) == pytest.approx(made.body.gait_constants(made.model), abs=1e-12)
    opts = {"inputs": SENSES, "n_neurons": 8, "dt": 0.02}  # the senses a genome reads, raw
    hand = EpisodeConfig(body="reil", controller="ctrnn", seconds=3.0, controller_options=opts).build()
    made = EpisodeConfig(body=declared_reil, controller="ctrnn", seconds=3.0, controller_options=opts,
                         body_options={"timestep": 0.005}).build()  # the Reil body's step (its model file's: 2 ms)
    G = np.random.default_rng(0).uniform(hand.controller.layout.low, hand.controller.layout.high,
                                         (4, hand.controller.layout.size))
    ra, rb = hand.run(G), made.run(G)
    assert np.array_equal(ra.fitness, rb.fitness) and np.array_equal(ra.end_position, rb.end_position)
    assert np.array_equal(ra.end_time, rb.end_time)


def test_the_box_bipeds_declaration_gives_its_actuators_senses_feet_and_constants():
    cls = body_class("mjcf:box_biped")
    body = cls()
    m = body.build_model()
    assert [a.name for a in cls.actuators] == [m.actuator(i).name for i in range(m.nu)]
    low, high = body.action_bounds()
    assert np.array_equal(low, m.actuator_ctrlrange[:, 0]) and np.array_equal(high, m.actuator_ctrlrange[:, 1])
    mass, leg = body.gait_constants(m)
    assert mass == pytest.approx(8.0 + 2 * (1.5 + 1.2 + 0.4)) and leg == pytest.approx(0.4 + 0.4 + 0.035 + 0.025)
    sims = Sims(m, 1)
    body.reset(sims)
    s = body.sensors(sims)
    assert np.array_equal(s["foot_contact"], [[1.0, 1.0]]) and np.allclose(s["pelvis_tilt"], 0)
    assert np.allclose(s["com_from_feet"], [cls.sensor_norms["com_from_feet"][0]])
    feet = body.feet(sims)
    assert np.allclose(feet.height, 0.0, atol=1e-9) and feet.contact.all()  # flat soles on the floor at rest
    sims.qpos[0, 2] += 0.05  # lifted: no contact, soles 5 cm up
    sims.forward()
    assert not body.contacts(sims).any() and np.allclose(body.feet(sims).height, 0.05)
    assert not body.fallen(sims, np.arange(1)).any()
    sims.qpos[0, 2] -= 0.6  # the centre of mass below 55 % of its standing height
    sims.forward()
    assert body.fallen(sims, np.arange(1)).all()


def test_the_box_biped_declares_its_mirror_truly():
    """A mirrored state reads the mirror of every sense the derived mirror declares."""
    ep = EpisodeConfig(body="mjcf:box_biped", controller="ctrnn", seconds=1.0).build()
    sims = _walked(ep)
    m = ep.model
    pair = Sims(m, 2)
    pair.qpos[:], pair.qvel[:] = sims.qpos[0], sims.qvel[0]
    q, v = pair.qpos[1].copy(), pair.qvel[1].copy()
    q[1], v[1] = -q[1], -v[1]
    w, x, y, z = q[3:7]
    q[3:7] = (w, -x, y, -z)
    v[3], v[5] = -v[3], -v[5]
    for role in ("hip_pitch", "hip_roll", "knee", "ankle"):
        a, b = m.joint(f"left_{role}"), m.joint(f"right_{role}")
        q[a.qposadr[0]], q[b.qposadr[0]] = q[b.qposadr[0]], q[a.qposadr[0]]
        v[a.dofadr[0]], v[b.dofadr[0]] = v[b.dofadr[0]], v[a.dofadr[0]]
    pair.qpos[1], pair.qvel[1] = q, v
    pair.forward()
    got = ep.body.sensors(pair)
    for name, (perm, sign) in ep.body.mirror.items():
        if name in ("stance_leg", "since_touchdown", "stance_side"):
            continue
        assert np.allclose(got[name][1], got[name][0][list(perm)] * np.array(sign), atol=1e-9), name


@pytest.mark.parametrize("edit, words", [
    (lambda t: t.replace('pelvis = "pelvis"\n', ""), "pelvis is missing"),
    (lambda t: t.replace('"left_knee"]', '"left_kne"]'), "the model has no actuator 'left_kne'"),
    (lambda t: t.replace('foot = "right_foot"', 'foot = "right_shank"'), None),
    (lambda t: t.replace('"left_hip_roll", "left_knee"]', '"left_hip_roll"]'), "legs.left.actuators must name 3"),
    (lambda t: 'colour = "red"\n' + t, "unknown key 'colour'"),
    (lambda t: t + 'colour = "red"\n', "legs.right must hold actuators and foot only"),
    (lambda t: t.replace('pelvis = "pelvis"', 'pelvis = "left_thigh"'), "has no free joint"),
    (lambda t: 'forward = "z"\n' + t, "forward (z) and up (z) must be different axes"),
])
def test_a_bad_declaration_is_refused_one_line_per_problem(tmp_path, edit, words):
    shutil.copy(model_path("reil_biped"), tmp_path / "b.xml")
    (tmp_path / "b.toml").write_text(edit(REIL_DECLARATION))
    if words is None:  # a capsule shank is a foot the gait lab can read: accepted
        body_class(f"mjcf:{tmp_path / 'b.xml'}")
        return
    with pytest.raises(ConfigError) as exc:
        body_class(f"mjcf:{tmp_path / 'b.xml'}")
    assert words in str(exc.value) and str(exc.value).startswith("body declaration ")


def test_the_cli_runs_a_declared_body_and_refuses_a_bad_one_in_one_line_per_problem(tmp_path, capsys):
    assert cli("episode", "--body", "mjcf:box_biped", "--seconds", "0.5", "--seed", "0") == 0
    shutil.copy(model_path("reil_biped"), tmp_path / "b.xml")
    (tmp_path / "b.toml").write_text(REIL_DECLARATION.replace('"left_knee"]',
                                                              '"left_kne"]').replace('pelvis = "pelvis"\n', ""))
    capsys.readouterr()
    assert cli("episode", "--body", f"mjcf:{tmp_path / 'b.xml'}", "--seconds", "0.5") == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and "pelvis is missing" in err
    assert cli("episode", "--body", f"mjcf:{tmp_path / 'none.xml'}", "--seconds", "0.5") == 2
    err = capsys.readouterr().err
    assert "no declaration" in err and "Traceback" not in err and len(err.strip().splitlines()) == 1


def test_every_sense_of_a_declared_body_is_described():
    cls = body_class("mjcf:box_biped")
    assert set(cls.sensor_text) == set(cls.sensor_widths) and cls.environment is None
    assert "left knee, left ankle, right hip_pitch" in cls.sensor_text["joint_angles"]
