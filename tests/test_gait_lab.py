"""The gait lab against independent calculations: contacts as MuJoCo's contact list has them, slip as the Jacobian
gives the contact point's velocity (a sliding body slips at its speed, a rolling one not at all), duty factors, flight
and steps of a constructed stance schedule, and the walk task's gait terms equal to the report's."""

import dataclasses

import mujoco
import numpy as np
import pytest

from evobiped.analysis.gait_report import FootRecorder, failed_criteria, gait_report
from evobiped.core.errors import ConfigError, UserError
from evobiped.core.options import given
from evobiped.episode import EpisodeConfig
from evobiped.files.genome_file import load_genome
from evobiped.physics.gait_lab import measure_one, stance_episodes
from evobiped.tasks.walk import LAB_TERMS, LAB_TERMS_TICK

from .conftest import WALKERS


def _standing(v=(0.0, 0.0, 0.0), w=(0.0, 0.0, 0.0)):
    """The Reil body in its initial pose, feet on the floor, its free joint moving at ``v`` (m/s) and ``w`` (rad/s)."""
    ep = EpisodeConfig(body="reil", controller=None, task="walk", seconds=1.0, control_dt=0.02).build()
    sims = ep.sims(1)
    ep.body.reset(sims)
    sims.qpos[0, 2] -= 0.002  # 2 mm into the floor: both feet in contact
    sims.qvel[0, :3], sims.qvel[0, 3:6] = v, w
    sims.forward()
    return ep, sims


def test_contacts_are_mujocos_contact_list_and_slip_the_contact_points_velocity():
    g, cfg, _ = load_genome(WALKERS / "ctrnn_distilled_seed5.json")
    ep = cfg.nominal().build()
    st = ep.start(g[None], seconds=6.0)
    m = st.sims.model
    floor, feet = m.geom("floor").id, [m.geom("left_foot").id, m.geom("right_foot").id]
    seen = set()
    for _ in range(300):
        ep.advance(st, ticks=1)
        s, d = ep.body.feet(st.sims), st.sims.batch.get_data(0)
        listed = [any({c.geom1, c.geom2} == {floor, f} for c in d.contact[: d.ncon]) for f in feet]
        assert list(s.contact[0]) == listed
        seen.add(tuple(listed))
        for k, f in enumerate(feet):
            p = d.geom_xpos[f] - [0, 0, m.geom_size[f, 0]]
            jacp = np.zeros((3, m.nv))
            mujoco.mj_jac(m, d, jacp, None, p, m.geom_bodyid[f])
            assert s.slip[0, k] == pytest.approx(np.hypot(*(jacp @ d.qvel)[:2]), abs=1e-9)
    assert {(True, False), (False, True), (True, True)} <= seen  # single and double support both met


def test_a_sliding_body_slips_at_its_speed_and_a_rolling_foot_does_not_slip():
    _, sims = _standing(v=(0.3, 0.4, 0.0))
    ep, _ = _standing()
    s = ep.body.feet(sims)
    assert s.contact.all() and s.slip[0] == pytest.approx([0.5, 0.5], abs=1e-12)
    # a rigid rotation about the left foot's lowest point p: v(x) = w x (x - p); the left foot rolls, the right one
    # (0.5 m to its right) is dragged sideways... by the rotation about the vertical, at w_z * 0.5 m/s
    ep, sims = _standing()
    p = sims.geom_xpos[0, sims.model.geom("left_foot").id] - [0, 0, 0.08]
    w = np.array([0.0, 2.0, 0.5])
    v = np.cross(w, sims.xpos[0, sims.model.body("pelvis").id] - p)
    ep, sims = _standing(v=v, w=w)
    s = ep.body.feet(sims)
    centre_speed = np.hypot(*np.cross(w, [0, 0, 0.08])[:2])
    assert centre_speed > 0.1 and s.slip[0, 0] == pytest.approx(0.0, abs=1e-12)
    assert s.slip[0, 1] == pytest.approx(0.5 * 0.5, rel=1e-3)


def test_a_known_stance_schedule_gives_its_duty_factors_flight_and_steps():
    dt, T = 0.01, 400  # 4 s; a stride of 1 s: left stands [0, 0.6), right [0.5, 1.1): duty 0.6, double support 0.2
    t = np.arange(T) * dt
    phase = t % 1.0
    left = phase < 0.6
    right = (phase >= 0.5) | (phase < 0.1)
    contact = np.stack([left, right], axis=1)
    contact[250:252, 0] = False  # a 20 ms lift inside a stance is flight...
    contact[70:73, 0] = True  # ...and a 30 ms tap in a swing is no stance (no longer than 40 ms)
    sample = {"contact": contact, "slip": np.full((T, 2), 0.01), "height": np.where(contact, 0.0, 0.05),
              "knee": np.zeros((T, 2)), "power": np.full((T, 6), 1.0)}
    m = measure_one(sample, dt, forward=2.0, mass=2.0, leg_length=1.0, feet=("left", "right"))
    left_stance = 0.6 - 0.02 / 4 - 0.0  # one 20 ms lift in 4 s
    assert m["duty_left"] == pytest.approx(left_stance, abs=1e-9)
    assert m["duty_right"] == pytest.approx(0.6, abs=1e-9)
    assert m["double_support"] == pytest.approx(0.2 - 0.02 / 4, abs=1e-9)
    assert m["airborne"] == 0.0  # the right foot stands during the left's lift
    # left: 4 stances + 1 split by the lift; right: the first stance (0-0.1 s) and 4 more (the last cut at 4 s)
    assert len(stance_episodes(contact[:, 0], dt)) == 5 and len(stance_episodes(contact[:, 1], dt)) == 5
    assert m["steps_per_s"] == pytest.approx(10 / 4) and m["step_length"] == pytest.approx(0.2)
    assert m["slip"] == pytest.approx(0.01) and m["slip_share"] == pytest.approx(0.02)
    assert m["power"] == pytest.approx(3.0) and m["positive_work"] == pytest.approx(12.0)
    assert m["cost_of_transport"] == pytest.approx(3.0 / (9.81 * 0.5)) and m["froude"] == pytest.approx(0.25 / 9.81)
    assert m["clearance"] == pytest.approx(0.05)
    kicked = {**sample, "height": sample["height"].copy()}
    kicked["height"][130, 1] = 1.0  # one swing's foot kicked a metre high (as a falling walker can)
    k = measure_one(kicked, dt, forward=2.0, mass=2.0, leg_length=1.0, feet=("left", "right"))
    assert k["clearance"] > 0.15 and k["lift"] == pytest.approx(0.05)  # the lift a fitness pays is capped per swing


def test_the_walk_tasks_gait_terms_are_the_reports_measures():
    g, cfg, _ = load_genome(WALKERS / "simbicon_cma_seed5.json")
    opts = dict(given(cfg.task_options), gait_terms=True, gait_sampling="physics_step")
    run_cfg = dataclasses.replace(cfg.nominal(), task_options=opts, seconds=8.0)
    terms = {k: float(v[0]) for k, v in run_cfg.build().run(g[None]).terms.items()}
    report = gait_report(cfg, g, seconds=8.0)
    for k in LAB_TERMS:
        assert terms[k] == pytest.approx(report[k], rel=1e-12), k
    assert report["up"] and 0.5 < report["duty_left"] < 0.6 and report["steps_per_s"] > 5


def test_control_tick_sampling_reads_the_last_physics_step_of_each_tick():
    """The sampling the earlier walkers were evolved with: their terms are the measures of every fourth sample of the
    report's series (the last physics step of each 20 ms tick), debounced one way, and lack the tail measures."""
    g, cfg, _ = load_genome(WALKERS / "simbicon_cma_seed5.json")
    opts = dict(given(cfg.task_options), gait_terms=True, gait_sampling="control_tick")
    ep = dataclasses.replace(cfg.nominal(), task_options=opts, seconds=6.0).build()
    recorder = FootRecorder()
    result = ep.run(g[None], listener=recorder)
    assert ep.substeps == 4 and "slide_per_m" not in result.terms and "slip_p90" in LAB_TERMS
    series = {k: v[ep.substeps - 1::ep.substeps] for k, v in recorder.series().items()}
    forward = float(result.terms["forward"][0])
    mass, leg = ep.body.gait_constants(ep.model)
    tick = measure_one(series, ep.control_dt, forward=forward, mass=mass, leg_length=leg, feet=("left", "right"))
    for k in LAB_TERMS_TICK:
        assert result.terms[k][0] == tick[k], k


def test_positive_work_is_raw_mujocos_joint_work_at_every_physics_step():
    """An independent calculation: the same controls stepped in one raw MjData, the actuators' positive work as
    qfrc_actuator times each hinge's displacement over every 5 ms physics step (semi-implicit Euler: the exact work
    of the step), against the gait lab's power series; and the last-step sample alone misses a tenth of it or more."""
    g, cfg, _ = load_genome(WALKERS / "ctrnn_walk_preset_seed1.json")
    ep = cfg.nominal().build()
    st = ep.start(g[None], seconds=4.0)
    m = ep.model
    d = mujoco.MjData(m)
    state = np.empty(mujoco.mj_stateSize(m, mujoco.mjtState.mjSTATE_FULLPHYSICS))
    mujoco.mj_getState(m, st.sims.batch.get_data(0), state, mujoco.mjtState.mjSTATE_FULLPHYSICS)
    mujoco.mj_setState(m, d, state, mujoco.mjtState.mjSTATE_FULLPHYSICS)
    recorder = FootRecorder()
    recorder.start(ep, st.sims)
    qadr, dadr = m.jnt_qposadr[m.actuator_trnid[:, 0]], m.jnt_dofadr[m.actuator_trnid[:, 0]]
    raw = []
    for _ in range(200):
        ep.advance(st, ticks=1, listener=recorder)
        d.ctrl[:] = st.sims.ctrl[0]
        for _ in range(ep.substeps):
            q0 = d.qpos[qadr].copy()
            mujoco.mj_step(m, d)
            raw.append(d.qfrc_actuator[dadr] * (d.qpos[qadr] - q0) / m.opt.timestep)
    assert np.array_equal(d.qpos, st.sims.qpos[0])  # the same motion, to the last bit
    lab = recorder.series()["power"]
    assert lab.shape == (800, 6) and lab == pytest.approx(np.array(raw), abs=1e-6)
    every, last = np.maximum(lab, 0).sum(), np.maximum(lab[3::4], 0).sum() * 4
    assert abs(last - every) > 0.02 * every  # one step in four is not the work


def test_the_stance_debounce_merges_bounces_and_drops_taps():
    dt, T = 0.005, 800  # 4 s of 5 ms samples; one stance [0, 0.6) s a second
    contact = (np.arange(T) * dt % 1.0) < 0.6
    contact[20:24] = False  # a 20 ms bounce inside the first stance
    contact[150:156] = True  # a 30 ms tap in the first swing
    one_way, both = stance_episodes(contact, dt), stance_episodes(contact, dt, min_gap=0.04)
    assert len(one_way) == 5 and len(both) == 4 and both[0] == (0, 120)
    contact[20:30] = False  # a 50 ms gap is a swing, not a bounce
    assert len(stance_episodes(contact, dt, min_gap=0.04)) == 5


def test_the_tail_of_the_slip_and_the_stride_against_hand_calculations():
    dt, T = 0.01, 400
    left = (np.arange(T) * dt % 1.0) < 0.6
    contact = np.stack([left, np.roll(left, 50)], axis=1)
    slip = np.where(np.arange(T)[:, None] % 10 == 0, 0.2, 0.01) * np.ones((T, 2))  # one sample in ten slides fast
    sample = {"contact": contact, "slip": slip, "height": np.where(contact, 0.0, 0.05), "knee": np.zeros((T, 2)),
              "power": np.zeros((T, 6))}
    m = measure_one(sample, dt, forward=2.0, mass=1.0, leg_length=1.0, feet=("left", "right"))
    stance_slips = slip[contact]
    assert m["slip"] == 0.01 and m["slip_p90"] == pytest.approx(np.percentile(stance_slips, 90))
    assert m["slide_per_m"] == pytest.approx(stance_slips.sum() * dt / 2.0)  # slid metres per metre forward
    steps = m["steps_per_s"] * 4.0
    fr = 0.5 ** 2 / 9.81
    assert m["step_leg"] == pytest.approx(2.0 / steps) and m["step_similar"] == pytest.approx((2.0 / steps) / (
        1.15 * fr ** 0.3))
    torque = np.tile([1.0, -2.0, 0.0, 3.0, 0.0, 0.0], (T, 1))
    m = measure_one({**sample, "torque": torque}, dt, forward=2.0, mass=1.0, leg_length=1.0, feet=("left", "right"))
    assert m["torque_cost"] == pytest.approx(14.0)  # 1 + 4 + 9 N^2 m^2 at every sample, per kg
    report = gait_report(*reversed(load_genome(WALKERS / "ctrnn_walk_preset_seed1.json")[:2]), seconds=5.0)
    assert report["shuffle"] and report["step_similar"] < 1 / 3  # 13 cm steps where about 45 cm are predicted


def test_a_skipping_walker_fails_the_walking_criteria_and_says_which():
    g, cfg, _ = load_genome(WALKERS / "ctrnn_es_seed5.json")
    report = gait_report(cfg, g, seconds=10.0)
    assert report["up"] and report["speed"] > 0.8
    assert {"duty_min", "airborne", "duty_asymmetry"} <= set(report["failed"]) and not report["walks"]
    assert failed_criteria({**report, "duty_min": 0.55, "airborne": 0.0, "duty_asymmetry": 0.01, "slip_share": 0.04,
                                      "slide_per_m": 0.08}) == []


def test_gait_terms_refuse_a_body_without_feet_and_bad_weights(monkeypatch):
    from evobiped.bodies import BODIES
    from evobiped.bodies.base import Body
    from evobiped.bodies.reil import ReilBiped

    class Footless(ReilBiped):  # the Reil body as a body that declares no feet
        name = "footless"
        feet, gait_constants = Body.feet, Body.gait_constants

    monkeypatch.setitem(BODIES, "footless", Footless)
    cfg = EpisodeConfig(body="footless", task="walk", task_options={"gait_terms": True}, seconds=1.0)
    ep = cfg.build()
    with pytest.raises(ConfigError, match="declares no feet"):
        ep.run(ep.controller.layout.centre[None])
    with pytest.raises(UserError, match="declares no feet"):
        gait_report(cfg, ep.controller.layout.centre)
    with pytest.raises(ConfigError, match="finite"):
        EpisodeConfig(task_options={"fitness": "weighted", "weights": {"airborne": float("nan")}})
    with pytest.raises(ConfigError, match="names no term"):
        EpisodeConfig(task_options={"fitness": "weighted", "weights": {"airbone": -1.0}})
    with pytest.raises(ConfigError, match="slide_per_m measured only under gait_sampling = 'physics_step'"):
        EpisodeConfig(task_options={"fitness": "weighted", "weights": {"slide_per_m": -1.0}})
    with pytest.raises(ConfigError, match="gait_sampling"):
        EpisodeConfig(task_options={"gait_terms": True, "gait_sampling": "every_tick"})
    EpisodeConfig(task_options={"fitness": "weighted", "weights": {"slide_per_m": -1.0},
                                "gait_sampling": "physics_step"})
    g, cfg, _ = load_genome(WALKERS / "ctrnn_es_seed5.json")
    for bad in (float("inf"), 0.0, -1.0):
        with pytest.raises(UserError, match="--seconds"):
            gait_report(cfg, g, seconds=bad)


def test_a_walk_outranks_a_faster_mover_when_candidates_are_tried_for_walking():
    from evobiped.analysis.selection import best_candidate

    skipper = {"fell": False, "end_time": 20.0, "distance": 50.0, "heading_deg": 1.0, "up_long": True, "walks": False}
    walker = {**skipper, "distance": 11.0, "walks": True}
    assert best_candidate([skipper, walker]) == 1
    assert best_candidate([{k: v for k, v in r.items() if k != "walks"} for r in (skipper, walker)]) == 0


def test_tagas_walker_on_its_spring_damper_ground_agrees_with_the_experiments_stride_analysis():
    """The gait lab on the Taga body (feet: the ankles on the Appendix A ground) against the Taga experiment's own,
    independent stride analysis (per-stride from contact onsets and foot positions) of the Appendix D walker."""
    from evobiped.experiments.taga.parameters import preset_genome
    from evobiped.experiments.taga.protocols import steady
    from evobiped.experiments.taga.walking import walker_config

    cfg = walker_config(5.5)
    lab = gait_report(cfg, preset_genome(cfg.parts()[1], "taga"), seconds=20.0)
    _, (strides,) = steady(5.5, seconds=20.0, window=10.0)
    assert lab["up"] and strides["gait"] == "walk"
    assert lab["speed"] == pytest.approx(strides["speed"], rel=0.01)
    assert lab["steps_per_s"] == pytest.approx(2 / strides["cycle_duration"], rel=0.03)
    assert lab["step_length"] == pytest.approx(strides["stride_length"] / 2, rel=0.03)
    assert lab["double_support"] == pytest.approx(strides["double_support"], abs=0.01)
    assert lab["airborne"] <= 0.002 and strides["flight"] == 0.0
    assert 0.5 < lab["duty_left"] < 0.6 and lab["duty_asymmetry"] < 0.02 and lab["knee_swing"] > 0.8
