"""The SIMBICON-style balance controller and the Reil body's balance sensors."""

import mujoco
from types import SimpleNamespace

import numpy as np
import pytest

from evobiped.bodies import ReilBiped, TagaBiped
from evobiped.interface.contract import Offer, problem
from evobiped.controllers.simbicon import RANGES, SENSORS, Simbicon
from evobiped.episode import Episode, EpisodeConfig, build_episode
from evobiped.core.errors import ConfigError
from evobiped.physics.sim import Sims
from evobiped.tasks import WalkTask

#: the Reil body's sensors wired to simbicon's inputs, as the episode wires them
WIRED = {n: ReilBiped.sensor_widths[n] for n in SENSORS}


def _sims(body, qpos=None, qvel=None):
    sims = Sims(body.build_model(), 1)
    body.reset(sims)
    if qpos is not None:
        sims.qpos[0] = qpos
    if qvel is not None:
        sims.qvel[0] = qvel
    sims.forward()
    return sims


def _quat(axis, angle):
    q = np.zeros(4)
    mujoco.mju_axisAngle2Quat(q, np.asarray(axis, float), angle)
    return q


def _mul(a, b):
    q = np.zeros(4)
    mujoco.mju_mulQuat(q, a, b)
    return q


def test_pelvis_tilt_and_rates_in_the_heading_frame():
    """Yaw 90 degrees (facing +y), then pitch 0.2 nose down and roll 0.1 left side up."""
    body = ReilBiped()
    m = body.build_model()
    q0 = m.qpos0.copy()
    q0[2] = 2.0
    # intrinsic: yaw about z, then pitch about the body's y (nose down), then roll about its x
    q0[3:7] = _mul(_mul(_quat([0, 0, 1], np.pi / 2), _quat([0, 1, 0], 0.2)), _quat([1, 0, 0], 0.1))
    v = np.zeros(m.nv)
    v[3:6] = [0.3, -0.5, 0.0]  # free joint: angular velocity in the body frame (roll rate, pitch rate)
    s = body.sensors(_sims(body, q0, v))
    np.testing.assert_allclose(body.heading(_sims(body, q0))[0], [0, 1], atol=1e-12)
    # independently: the pelvis's x and y axes rotated by the quaternion; pitch from x, roll from y
    axes = [np.zeros(3), np.zeros(3)]
    mujoco.mju_rotVecQuat(axes[0], np.array([1.0, 0, 0]), q0[3:7])
    mujoco.mju_rotVecQuat(axes[1], np.array([0, 1.0, 0]), q0[3:7])
    assert -np.arcsin(axes[0][2]) == pytest.approx(0.2)
    np.testing.assert_allclose(s["pelvis_tilt"][0], [0.2, np.arcsin(axes[1][2])], atol=1e-12)
    assert s["pelvis_tilt"][0, 1] == pytest.approx(0.1, abs=0.005)
    # the body's y axis differs from the heading's left axis by the 0.1 rad roll: rates to first order
    np.testing.assert_allclose(s["pelvis_tilt_rate"][0], [-0.5, 0.3], atol=0.06)


def test_com_from_feet_and_velocity_against_the_model():
    """Facing -x (yaw 180 degrees), translating at (1, 2) m/s in the world: forward -1, left -2."""
    body = ReilBiped()
    m = body.build_model()
    q0 = m.qpos0.copy()
    q0[3:7] = _quat([0, 0, 1], np.pi)
    v = np.zeros(m.nv)
    v[:3] = [1.0, 2.0, 0.0]
    sims = _sims(body, q0, v)
    s = body.sensors(sims)
    np.testing.assert_allclose(s["com_velocity"][0], [-1.0, -2.0], atol=1e-9)
    # standing straight: the centre of mass lies midway between the feet, 0.25 m from each
    d = mujoco.MjData(m)
    d.qpos[:] = q0
    mujoco.mj_forward(m, d)
    com = d.subtree_com[m.body("pelvis").id]
    assert com[0] == pytest.approx(d.site_xpos[m.site("left_foot").id][0])
    # facing -x, the left foot lies at -y: the centre of mass is to its right (left = -0.25)
    np.testing.assert_allclose(s["com_from_feet"][0], [0.0, -0.25, 0.0, 0.25], atol=1e-9)


def test_an_upside_down_walker_has_fallen_even_with_its_centre_of_mass_high():
    body = ReilBiped()
    m = body.build_model()
    q0 = m.qpos0.copy()
    q0[2] = 3.0
    ids = np.array([0])
    assert not body.fallen(_sims(body, q0), ids)[0]
    q0[3:7] = _quat([1, 0, 0], 1.6)  # on its side and a little past
    assert body.fallen(_sims(body, q0), ids)[0]
    q0[3:7] = _quat([1, 0, 0], 1.5)
    assert not body.fallen(_sims(body, q0), ids)[0]
    strict = ReilBiped(fall_tilt=1.0)
    assert strict.fallen(_sims(strict, q0), ids)[0]


def _genome(ctrl, **values):
    lay = ctrl.layout
    g = lay.init_mean.copy()
    for k, v in values.items():
        g[lay.slices()[k]] = v
    return g


def _inputs(ctrl, **x):
    out = np.zeros((1, sum(WIRED.values())))
    for k, v in x.items():
        out[0, ctrl._at[k]] = v
    return out


def test_swing_and_stance_targets_by_hand():
    """Left stance, early swing: every target from the module docstring's formulas."""
    ctrl = Simbicon(n_outputs=6, inputs=WIRED, actuators=ReilBiped.actuators)
    g = _genome(ctrl, step_time=0.3, hip_early=0.5, knee_early=-1.0, stance_knee=-0.1, cd=0.4, cv=0.2,
                roll_offset=0.05, cd_lateral=0.5, cv_lateral=0.3, pelvis_gain=0.6, pelvis_damping=0.1)
    params = ctrl.decode(g)
    q = np.array([0.1, 0.02, -0.05, -0.2, 0.03, -0.3])
    x = _inputs(ctrl, joint_angles=q, foot_contact=[1, 1], pelvis_tilt=[0.05, -0.04], pelvis_tilt_rate=[0.2, 0.1],
                com_from_feet=[0.1, -0.2, 0.0, 0.3], com_velocity=[0.5, -0.1])
    state, out = ctrl.step(params, ctrl.initial_state(params), x)
    assert state["stance"][0] == 0 and state["t"][0] == pytest.approx(0.02)  # no switch before step_time
    d_fwd, d_left = 0.1, -0.2  # centre of mass from the left (stance) foot
    want = np.empty(6)
    want[3] = 0.5 + 0.4 * d_fwd + 0.2 * 0.5 + 0.05  # right swing hip: world angle + pelvis pitch
    out_right = -1.0  # the right leg's outward direction is -left
    want[4] = 0.05 + out_right * (0.5 * d_left + 0.3 * -0.1) - out_right * -0.04
    want[5] = -1.0
    want[2] = -0.1
    want[0] = 0.1 - (0.6 * 0.05 + 0.1 * 0.2)
    want[1] = 0.02 + (0.6 * -0.04 + 0.1 * 0.1)
    np.testing.assert_allclose(out[0], want, atol=1e-12)


def test_the_legs_swap_when_the_swing_foot_lands_after_step_time():
    ctrl = Simbicon(n_outputs=6, inputs=WIRED, actuators=ReilBiped.actuators)
    params = ctrl.decode(_genome(ctrl, step_time=0.3))
    st = ctrl.initial_state(params)
    touching = _inputs(ctrl, foot_contact=[1, 1])
    airborne = _inputs(ctrl, foot_contact=[1, 0])
    for _ in range(15):  # 0.3 s: not yet past step_time
        st, _ = ctrl.step(params, st, touching)
    assert st["stance"][0] == 0
    st, _ = ctrl.step(params, st, airborne)  # past step_time, but the swing foot is up
    assert st["stance"][0] == 0
    st, _ = ctrl.step(params, st, touching)
    assert st["stance"][0] == 1 and st["t"][0] == 0.0
    for _ in range(45):  # 3 step_time with the (now left) swing foot never landing: forced swap
        st, _ = ctrl.step(params, st, airborne)
    assert st["stance"][0] == 0


def test_the_stance_hip_turns_a_tilted_pelvis_back():
    """In zero gravity with the left foot standing, the stance hip's new target accelerates the pelvis against its
    tilt."""
    ep = build_episode(body="reil", controller="simbicon", seconds=1.0)
    body, ctrl = ep.body, ep.controller
    m = ep.model
    m.opt.gravity[:] = 0
    params = ctrl.decode(_genome(ctrl, pelvis_gain=0.8, pelvis_damping=0.0))
    for axis, k in (([0, 1, 0], 0), ([1, 0, 0], 1)):  # pitch nose down, roll left side up
        q0 = m.qpos0.copy()
        q0[2] = 2.0
        q0[3:7] = _quat(axis, 0.1)
        sims = _sims(body, q0)
        x, _ = ep._inputs(SimpleNamespace(sims=sims, task={}, senses=None, norm=None), 1)
        _, out = ctrl.step(params, ctrl.initial_state(params), x)
        sims.ctrl[0] = np.clip(out[0], ep.low, ep.high)
        sims.ctrl[0, 2:] = sims.qpos[0, body._qadr[2:]]  # hold the knees and the swing leg: only the stance hip acts
        sims.forward()
        d = mujoco.MjData(m)
        d.qpos[:], d.ctrl[:] = sims.qpos[0], sims.ctrl[0]
        mujoco.mj_forward(m, d)
        # the tilt grows along +axis; the pelvis must accelerate about -axis
        assert d.qacc[3 + (1 if k == 0 else 0)] < -1.0


def test_bad_pairings_are_one_clear_error():
    with pytest.raises(ConfigError, match="'simbicon' .body 'taga', task 'walk'. needs a left and a right leg with the "
                                          "joints hip_pitch, hip_roll, knee, the body has right: hip, knee, ankle; "
                                          "left: hip, knee, ankle"):
        EpisodeConfig(body="taga", controller="simbicon").layout()
    with pytest.raises(ConfigError, match="gives angle outputs, which body 'taga' cannot take as torques"):
        Episode(TagaBiped(), Simbicon(n_outputs=6, inputs=WIRED, actuators=ReilBiped.actuators), WalkTask(),
                seconds=1.0)
    with pytest.raises(ConfigError, match="needs the sensors foot_contact, pelvis_tilt, .*; its inputs leave them out"):
        EpisodeConfig(controller="simbicon", controller_options={"inputs": ["joint_angles"]}).layout()
    # the episode checks the contract (once): a body whose centre-of-mass velocity is 1 wide is refused
    offer = Offer(ReilBiped.actuators, {**ReilBiped.sensor_widths, "com_velocity": 1})
    assert problem(Simbicon.needs(Simbicon.Options()), offer) == "needs the sensors com_velocity (2 wide, offered 1)"
    assert problem(Simbicon.needs(Simbicon.Options()), Offer(ReilBiped.actuators, ReilBiped.sensor_widths)) is None


def test_simbicon_finds_its_joints_by_role_not_by_column():
    """The same walker with the body's actuators declared in another order: the same targets, permuted."""
    from evobiped.interface.contract import index

    mirrored = ReilBiped.actuators[3:] + ReilBiped.actuators[:3]  # right leg first
    a = Simbicon(n_outputs=6, inputs=WIRED, actuators=ReilBiped.actuators)
    b = Simbicon(n_outputs=6, inputs=WIRED, actuators=mirrored)
    g = _genome(a, step_time=0.3, hip_early=0.5, cd=0.4, pelvis_gain=0.6)
    q = np.array([0.1, 0.02, -0.05, -0.2, 0.03, -0.3])
    x = dict(foot_contact=[1, 1], pelvis_tilt=[0.05, -0.04], com_from_feet=[0.1, -0.2, 0.0, 0.3],
             com_velocity=[0.5, -0.1])
    pa, pb = a.decode(g), b.decode(g)
    _, out_a = a.step(pa, a.initial_state(pa), _inputs(a, joint_angles=q, **x))
    _, out_b = b.step(pb, b.initial_state(pb), _inputs(b, joint_angles=np.r_[q[3:], q[:3]], **x))
    for act in ReilBiped.actuators:
        assert out_a[0, index(ReilBiped.actuators, act.leg, act.joint)] == out_b[0, index(mirrored, act.leg, act.joint)]
    assert out_a[0, 3] != out_a[0, 0]  # the legs' targets differ: a permutation is visible


def test_genes_and_layout():
    ctrl = Simbicon(n_outputs=6, inputs=WIRED, actuators=ReilBiped.actuators)
    assert ctrl.layout.size == len(RANGES) == 13
    assert np.all(ctrl.layout.low < ctrl.layout.init_mean) and np.all(ctrl.layout.init_mean < ctrl.layout.high)


def test_the_evolved_walker_in_docs_walks_50_s_and_10_m():
    """The best of `evobiped evolve --controller simbicon --seed 1` (docs/walkers): no fall in 50 s, >= 10 m
    with steps: the feet take turns on the ground."""
    from pathlib import Path

    from evobiped.files.genome_file import load_genome

    genome, cfg, meta = load_genome(Path(__file__).parents[1] / "docs" / "walkers" / "simbicon_seed1.json")
    ep = cfg.build()
    contacts = []

    class Feet:
        def start(self, episode, sims):
            self.body = episode.body

        def tick(self, t, sims, ids, neurons, action, task_state):
            contacts.append(self.body.sensors(sims)["foot_contact"][0].copy())

        def end(self, result): ...

    r = ep.run(genome, listener=Feet())
    assert not r.fell[0] and not r.unstable[0] and r.end_time[0] == 50.0
    assert r.fitness[0] >= 10.0
    assert r.fitness[0] == pytest.approx(meta["fitness"], rel=0.05)
    c = np.array(contacts)
    single = (c.sum(axis=1) == 1)
    swaps = np.count_nonzero(np.diff(np.argmax(c[single], axis=1)))
    assert swaps > 50  # more than 50 changes of the standing foot in 50 s


def test_com_velocity_equals_mujocos_subtree_velocity_in_motion():
    """A walker mid-stride (spinning, legs swinging): the sensor against mj_subtreeVel, rotated into the heading
    frame."""
    body = ReilBiped()
    m = body.build_model()
    rng = np.random.default_rng(5)
    q0 = m.qpos0.copy()
    q0[3:7] = _quat([0.3, 0.2, 1.0], 0.8)
    v = rng.normal(0, 1.0, m.nv)
    s = body.sensors(_sims(body, q0, v))
    d = mujoco.MjData(m)
    d.qpos[:], d.qvel[:] = q0, v
    mujoco.mj_forward(m, d)
    mujoco.mj_subtreeVel(m, d)
    want = d.subtree_linvel[m.body("pelvis").id, :2]
    fwd = body.heading(_sims(body, q0))[0]
    left = np.array([-fwd[1], fwd[0]])
    np.testing.assert_allclose(s["com_velocity"][0], [want @ fwd, want @ left], atol=1e-10)


def test_hearing_biases_the_swing_targets_by_the_sound_signal():
    """With the sound input: two more genes; s shifts the forward swing target by -side sound_forward s
    and the outward one by side sound_lateral s (side +1 for the left leg); deaf genes change nothing."""
    heard = {"sound": 1, **WIRED}
    ctrl = Simbicon(n_outputs=6, inputs=heard, actuators=ReilBiped.actuators)
    assert ctrl.layout.size == 15 and ctrl.layout.init_mean[-2:].tolist() == [0.0, 0.0]
    deaf = Simbicon(n_outputs=6, inputs=WIRED, actuators=ReilBiped.actuators)
    base = dict(step_time=0.3, hip_early=0.5, knee_early=-1.0, stance_knee=-0.1, cd=0.4, cv=0.2, roll_offset=0.05)
    x = np.zeros((1, 1 + sum(WIRED.values())))
    x[0, ctrl._at["foot_contact"]] = [1, 1]
    x[0, ctrl._at["com_from_feet"]] = [0.1, -0.2, 0.0, 0.3]
    _, quiet = deaf.step(deaf.decode(_genome(deaf, **base)), deaf.initial_state(deaf.decode(_genome(deaf, **base))),
                         x[:, 1:])
    for sound_forward, sound_lateral in [(0.0, 0.0), (0.3, 0.0), (0.0, 0.2), (-0.1, 0.25)]:
        params = ctrl.decode(_genome(ctrl, **base, sound_forward=sound_forward, sound_lateral=sound_lateral))
        x[0, 0] = 0.5  # the source on the left
        _, out = ctrl.step(params, ctrl.initial_state(params), x)
        want = quiet[0].copy()
        want[3] += sound_forward * 0.5  # the right leg swings (left stance): side -1, a longer step
        want[4] -= sound_lateral * 0.5  # its outward direction is right: the foot moves left
        np.testing.assert_allclose(out[0], want, atol=1e-12)


@pytest.mark.parametrize("s, heard", [(0.5, 0.1), (-0.8, -0.1), (0.06, 0.06), (-0.1, -0.1)])
def test_the_sound_limit_clips_what_the_hearing_genes_act_on(s, heard):
    """sound_limit = 0.1: the targets of a walker hearing s are those it sets for s clipped to +-0.1, i.e.
    the forward target shifted by sound_forward * heard (right leg swinging), the outward one by -sound_lateral *
    heard."""
    heard_inputs = {"sound": 1, **WIRED}
    ctrl = Simbicon(n_outputs=6, inputs=heard_inputs, actuators=ReilBiped.actuators)
    clipped = Simbicon(n_outputs=6, inputs=heard_inputs, actuators=ReilBiped.actuators, sound_limit=0.1)
    params = ctrl.decode(_genome(ctrl, step_time=0.3, hip_early=0.5, knee_early=-1.0, cd=0.4, sound_forward=0.3,
                                 sound_lateral=0.2))
    x = np.zeros((1, 1 + sum(WIRED.values())))
    x[0, ctrl._at["foot_contact"]] = [1, 1]
    x[0, 0] = 0.0
    _, quiet = ctrl.step(params, ctrl.initial_state(params), x)
    x[0, 0] = s
    _, out = clipped.step(params, clipped.initial_state(params), x)
    want = quiet[0].copy()
    want[3] += 0.3 * heard
    want[4] -= 0.2 * heard
    np.testing.assert_allclose(out[0], want, atol=1e-12)


def test_a_deaf_walker_steers_exactly_as_it_walks():
    """The balance controller on the steering task with deaf genes: every presentation walks the walk task's path."""
    import dataclasses
    from pathlib import Path

    from evobiped.files.genome_file import load_genome

    genome, cfg, _ = load_genome(Path(__file__).parents[1] / "docs" / "walkers" / "simbicon_seed1.json")
    walk = cfg.build().run(genome, seconds=4.0)
    steer = dataclasses.replace(cfg, task="steer", task_options={}).build()
    assert steer.controller.hears and steer.controller.layout.size == 15
    rows = steer.run(np.concatenate([genome, [0.0, 0.0]]), seconds=4.0).rows
    assert np.array_equal(rows.end_position, np.repeat(walk.end_position, 2, axis=0))
    assert np.array_equal(rows.end_time, np.repeat(walk.end_time, 2))
