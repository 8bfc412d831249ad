"""The compiled Reil & Husbands biped against Tables I-II and Sect. II-A."""

import mujoco
import numpy as np
import pytest

from evobiped.bodies import ReilBiped
from evobiped.bodies.reil import ACTUATORS, TABLE_II
from evobiped.physics.models import model_path


@pytest.fixture(scope="module")
def model():
    return ReilBiped().build_model()


def test_masses_table_I(model):
    m = lambda b: model.body(b).mass[0]  # noqa: E731
    assert m("pelvis") == pytest.approx(1.0)
    for side in ("left", "right"):
        assert m(f"{side}_thigh") == pytest.approx(0.6)
        assert m(f"{side}_shank") == pytest.approx(0.6)  # the sphere foot is part of the lower leg
    assert model.body_subtreemass[model.body("pelvis").id] == pytest.approx(3.4)


def test_segment_lengths_and_foot(model):
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    pelvis = model.geom("pelvis")
    # pelvis capsule: half-length 0.25 along y -> 0.5 m between the hip joints
    assert 2 * pelvis.size[1] == pytest.approx(0.5)
    for side in ("left", "right"):
        hip = data.xanchor[model.joint(f"{side}_hip_pitch").id]
        knee = data.xanchor[model.joint(f"{side}_knee").id]
        foot = data.geom_xpos[model.geom(f"{side}_foot").id]
        assert np.linalg.norm(knee - hip) == pytest.approx(0.5)
        assert np.linalg.norm(foot - knee) == pytest.approx(0.5)
        g = model.geom(f"{side}_foot")
        assert g.type[0] == mujoco.mjtGeom.mjGEOM_SPHERE and g.size[0] == pytest.approx(0.08)
    left = data.xanchor[model.joint("left_hip_pitch").id]
    right = data.xanchor[model.joint("right_hip_pitch").id]
    assert np.linalg.norm(left - right) == pytest.approx(0.5)
    # standing upright, feet exactly touching the floor
    assert data.geom_xpos[model.geom("left_foot").id][2] == pytest.approx(0.08)


def test_six_actuated_dof_on_free_root(model):
    types = [model.jnt_type[j] for j in range(model.njnt)]
    assert types.count(mujoco.mjtJoint.mjJNT_FREE) == 1
    assert types.count(mujoco.mjtJoint.mjJNT_HINGE) == 6
    assert model.nu == 6 and model.nv == 12
    names = {model.joint(j).name for j in range(model.njnt)}
    assert names >= set(ACTUATORS)


def test_target_ranges_table_II(model):
    lo, hi = ReilBiped().action_bounds()
    for i, a in enumerate(ACTUATORS):
        want = TABLE_II[a.split("_", 1)[1]]
        assert tuple(model.actuator_ctrlrange[i]) == pytest.approx(want)
        assert (lo[i], hi[i]) == pytest.approx(want)
        assert model.actuator(a).trntype[0] == mujoco.mjtTrn.mjTRN_JOINT
    assert TABLE_II == {"knee": (-1.4, 0.0), "hip_roll": (-0.8, 0.8), "hip_pitch": (-1.3, 1.6)}


def test_pd_law_eq1(model):
    """The actuator force is k_s (theta_d - theta) - k_d dtheta/dt with the body's gains."""
    body = ReilBiped(kp=50, kv=2)
    m = body.build_model()
    d = mujoco.MjData(m)
    i = m.actuator("left_knee").id
    j = m.joint("left_knee")
    d.qpos[j.qposadr[0]] = -0.3
    d.qvel[j.dofadr[0]] = 0.7
    d.ctrl[i] = -1.0
    mujoco.mj_forward(m, d)
    assert d.actuator_force[i] == pytest.approx(50 * (-1.0 - -0.3) - 2 * 0.7)


def test_sign_conventions(model):
    """hip_pitch > 0 swings the leg forward (+x), hip_roll > 0 outward, knee < 0 backward."""
    d = mujoco.MjData(model)

    def foot_after(joint, angle, side):
        mujoco.mj_resetData(model, d)
        d.qpos[model.joint(f"{side}_{joint}").qposadr[0]] = angle
        mujoco.mj_kinematics(model, d)
        return d.geom_xpos[model.geom(f"{side}_foot").id]

    for side, out in (("left", 1), ("right", -1)):
        assert foot_after("hip_pitch", 0.5, side)[0] > 0.3
        assert foot_after("knee", -0.5, side)[0] < -0.1
        assert out * foot_after("hip_roll", 0.5, side)[1] > 0.25 + 0.3


def test_model_file_is_found():
    assert model_path("reil_biped").is_file()


def test_karma_inertia_reading():
    """inertia="karma": 0.4 kg m^2 per MathEngine body; the knee's joint-space inertia matches
    the hand calculation I_shank + m_shank d^2 + armature, ~100 times the geoms' value."""
    m = ReilBiped(inertia="karma").build_model()
    g = ReilBiped().build_model()
    assert np.allclose(m.body_inertia[m.body("pelvis").id], 0.4)
    for b in ("left_thigh", "right_thigh", "left_shank", "right_shank"):
        assert np.allclose(m.body_inertia[m.body(b).id], 1.2)
    assert np.array_equal(m.body_mass, g.body_mass) and np.array_equal(m.body_ipos, g.body_ipos)
    shank = m.body("left_shank").id
    d = np.linalg.norm(m.body_ipos[shank])  # knee to the shank's centre of mass, m
    for model, I in ((m, 1.2), (g, g.body_inertia[shank][0])):
        data = mujoco.MjData(model)
        mujoco.mj_forward(model, data)
        M = np.zeros((model.nv, model.nv))
        mujoco.mj_fullM(model, data, M)
        dof = model.joint("left_knee").dofadr[0]
        assert M[dof, dof] == pytest.approx(I + 0.6 * d**2 + model.dof_armature[dof], rel=1e-9)
    assert m.body_inertia[shank][0] > 60 * g.body_inertia[shank][0]


def test_unknown_inertia_reading_is_refused():
    from evobiped.core.errors import ConfigError

    with pytest.raises(ConfigError, match="inertia: must be one of geoms, karma, got 'ode'"):
        ReilBiped(inertia="ode")
