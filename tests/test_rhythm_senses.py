"""The rhythm generators fed back by any body's senses: Matsuoka's (``feedback = "senses"``, PD targets in rad with
``output = "angle"``, a direct ``reflex``) and G3's (``feedback = "senses"``): each feed against an independent
computation, the push-pull pathways, zero gains as no feedback to the last bit, and the senses changing the walker."""

import numpy as np
import pytest

from evobiped.episode import EpisodeConfig

from .conftest import ActionRecorder

INPUTS = ["joint_angles", "joint_velocities", "foot_contact", "pelvis_tilt", "pelvis_tilt_rate", "since_touchdown"]


def _config(feedback="senses", output="angle", seconds=1.0):
    return EpisodeConfig(body="reil", controller="matsuoka", seconds=seconds,
                         controller_options={"feedback": feedback, "output": output, "u0": 1.0, "dt": 0.01,
                                             "inputs": INPUTS})


def _genome(ctrl, rng, **blocks):
    """The layout's initial means, with named blocks set to ``blocks``' values (scalars or arrays)."""
    parts = []
    for b in ctrl.layout.blocks:
        v = np.full(b.size, b.init_mean) if b.name not in blocks else np.broadcast_to(blocks[b.name], (b.size,))
        parts.append(np.asarray(v, float))
    return np.concatenate(parts)


def test_senses_feed_each_oscillator_push_pull_through_its_gains():
    ep = _config().build()
    c = ep.controller
    assert c.feedback == "senses" and c.normalises_inputs and c.output_kind == "angle"
    k = c.n_inputs
    assert list(c.input_names) == INPUTS and k == sum(c._widths.values()) == 19 and [b.name for b in c.layout.blocks][
        -2:] == ["bias", "sense_gain"]
    rng = np.random.default_rng(3)
    gains = rng.uniform(-1, 1, (2, c.n_osc * k))
    G = np.stack([_genome(c, rng, sense_gain=g) for g in gains])
    params = c.decode(G)
    x = rng.normal(size=(2, k))
    feed = c.feed(params, x)
    for p in range(2):  # independently: oscillator o's flexor (neuron 2o) gets +sum_i K[o, i] x_i, its extensor -
        K = gains[p].reshape(c.n_osc, k)
        for o in range(c.n_osc):
            want = sum(K[o, i] * x[p, i] for i in range(k))
            assert feed[p, 2 * o] == pytest.approx(want, abs=1e-12)
            assert feed[p, 2 * o + 1] == pytest.approx(-want, abs=1e-12)


def test_zero_gains_are_no_feedback_to_the_last_bit_and_gains_change_the_walk():
    rng = np.random.default_rng(0)
    with_senses, without = _config(seconds=1.5).build(), _config("none", seconds=1.5).build()
    g = _genome(with_senses.controller, rng, sense_gain=0.0, p_e=0.3, p_f=0.3)
    plain = np.concatenate([g[:without.controller.layout.size]])  # the same genes before the gains
    a, b = with_senses.run(g[None]), without.run(plain[None])
    assert np.array_equal(a.end_time, b.end_time) and np.array_equal(a.fitness, b.fitness)
    assert np.array_equal(a.end_position, b.end_position)
    gains = rng.uniform(-1, 1, with_senses.controller.n_osc * with_senses.controller.n_inputs)
    c = with_senses.run(_genome(with_senses.controller, rng, sense_gain=gains, p_e=0.3, p_f=0.3)[None])
    assert not np.array_equal(c.end_position, a.end_position)


def test_angle_output_is_the_pd_target_in_rad_about_the_posture_bias():
    ep = _config().build()
    c = ep.controller
    rng = np.random.default_rng(1)
    bias = np.array([0.1, -0.05, 0.4, -0.2, 0.05, 0.3])
    params = c.decode(_genome(c, rng, bias=bias, p_e=0.7, p_f=0.2)[None])
    y = np.abs(rng.normal(size=(1, c.n)))
    out = c.torques(params, y)
    assert np.allclose(out[0], 0.7 * y[0, 1::2] - 0.2 * y[0, 0::2] + bias, atol=1e-14)
    still, grab = _genome(c, rng, bias=bias, p_e=0.0, p_f=0.0), ActionRecorder(row=0)
    ep.run(still[None], listener=grab)
    assert np.allclose(grab.seen[0], np.clip(bias, ep.low, ep.high))  # no rhythm: the targets are the posture


def test_senses_need_declared_scales_and_signed_output_is_unchanged():
    signed = _config(output="signed").build().controller
    assert "bias" not in [b.name for b in signed.layout.blocks] and signed.output_kind == "signed"
    assert _config("none", "signed").build().controller.normalises_inputs is False


def test_reflex_adds_the_senses_to_each_target_and_needs_senses_and_angles():
    from evobiped.core.errors import ConfigError

    cfg = EpisodeConfig(body="reil", controller="matsuoka", seconds=1.0,
                        controller_options={"feedback": "senses", "output": "angle", "reflex": True, "dt": 0.01,
                                            "inputs": INPUTS})
    c = cfg.build().controller
    rng = np.random.default_rng(2)
    R = rng.uniform(-1, 1, c.n_osc * c.n_inputs)
    params = c.decode(_genome(c, rng, reflex_gain=R, p_e=0.0, p_f=0.0, bias=0.1)[None])
    x = rng.normal(size=(1, c.n_inputs))
    _, out = c.step(params, c.initial_state(params), x)
    assert np.allclose(out[0], 0.1 + R.reshape(c.n_osc, c.n_inputs) @ x[0], atol=1e-12)
    with pytest.raises(ConfigError, match="reflex needs"):
        EpisodeConfig(body="reil", controller="matsuoka",
                      controller_options={"feedback": "none", "output": "angle", "reflex": True}).build()


def _g3(feedback="senses", seconds=1.0):
    opts = {"feedback": feedback, "go": 0.1} | ({"inputs": INPUTS} if feedback == "senses" else {})
    return EpisodeConfig(body="reil", controller="g3", seconds=seconds, controller_options=opts)


def test_g3_senses_reach_each_channels_input_and_zero_gains_are_the_go_signal_alone():
    from evobiped.controllers.g3_network import rk4_step

    ep = _g3().build()
    c = ep.controller
    assert c.normalises_inputs and c.n_inputs == 19 and c.layout.blocks[-1].name == "sense_gain"
    rng = np.random.default_rng(4)
    K = rng.uniform(-1, 1, c.n * c.n_inputs)
    params = c.decode(_genome(c, rng, sense_gain=K)[None])
    x = rng.normal(size=(1, c.n_inputs))
    state = {"x": np.full((1, c.n), 0.1), "y": np.zeros((1, c.n)), "k": 0}
    got, _ = c.step(params, state, x)
    xx, yy = state["x"], state["y"]
    feed = K.reshape(c.n, c.n_inputs) @ x[0]
    for s in range(c.substeps):  # independently: I = [GO + K x]^+ at each RK4 substep
        I = np.maximum(c.go_at(s - c.lag_steps)[None, :] + feed[None, :], 0.0)
        xx, yy = rk4_step(c.cells, xx, yy, I, params["D"], c.h)
    assert np.allclose(got["x"], xx, rtol=0, atol=1e-12) and np.allclose(got["y"], yy, rtol=0, atol=1e-12)
    assert not np.allclose(got["x"], c.step(c.decode(_genome(c, rng, sense_gain=0.0)[None]), state, x)[0]["x"])
    plain = _g3("none", seconds=1.5).build()
    g = _genome(c, rng, sense_gain=0.0)
    a, b = _g3(seconds=1.5).build().run(g[None]), plain.run(g[None, :plain.controller.layout.size])
    assert np.array_equal(a.end_position, b.end_position) and np.array_equal(a.fitness, b.fitness)


def test_exponential_integration_solves_each_leak_exactly_and_stays_stable_where_euler_does_not():
    """A lone neuron pair without connections, adaptation or feedback relaxes to u0 as u0 + (u_init - u0) e^(-t/tau):
    the exponential step gives that to rounding at any control period, Euler only for h << tau (and diverges past
    h = 2 tau); with a rhythm, at a period much shorter than tau, both give the same oscillation."""
    from evobiped.controllers.matsuoka import Matsuoka

    tau, h = 0.02, 0.05  # h > 2 tau: forward Euler's factor 1 - h/tau = -1.5
    genes = {"tau": {"low": 0.01, "high": 1.0, "init_mean": tau}, "beta": {"low": 0.0, "high": 10.0, "init_mean": 0.0},
             "w_fe": {"low": -10.0, "high": 0.0, "init_mean": 0.0},
             "w_rl": {"low": -10.0, "high": 0.0, "init_mean": 0.0},
             "w_hka": {"low": -10.0, "high": 0.0, "init_mean": 0.0}}
    runs = {}
    for integration in ("exponential", "euler"):
        c = Matsuoka(n_outputs=2, u0=1.0, feedback="none", initial_u=3.0, dt=h, integration=integration)
        c.override_genes(genes)
        c = c.bound(h)
        p = c.decode(c.layout.init_mean[None])
        s = c.initial_state(p)
        u = []
        for _ in range(8):
            s, _ = c.step(p, s, np.zeros((1, 0)))
            u.append(s["u"][0, 0])
        runs[integration] = np.array(u)
    exact = 1.0 + (3.0 - 1.0) * np.exp(-h * np.arange(1, 9) / tau)
    assert np.allclose(runs["exponential"], exact, rtol=0, atol=1e-12)
    assert abs(runs["euler"][-1] - 1.0) > 10  # |1 - h/tau|^8 = 25.6: Euler's oscillating divergence
    periods = {}
    for integration in ("exponential", "euler"):  # the two-neuron rhythm at h = tau / 20
        c = Matsuoka(n_outputs=2, u0=1.0, feedback="none", initial_u=0.5, dt=0.0025, integration=integration)
        c.override_genes({"tau": {"low": 0.01, "high": 1.0, "init_mean": 0.05}})
        c = c.bound(0.0025)
        p = c.decode(c.layout.init_mean[None])
        s, out = c.initial_state(p), []
        for _ in range(4000):
            s, o = c.step(p, s, np.zeros((1, 0)))
            out.append(o[0, 0])
        o = np.array(out[1000:])
        up = np.flatnonzero((o[1:] > 0) & (o[:-1] <= 0))
        periods[integration] = np.diff(up).mean() * 0.0025
    assert periods["euler"] > 0.2 and periods["exponential"] == pytest.approx(periods["euler"], rel=0.02)


def test_g3_angle_output_is_the_pd_target_in_rad_about_the_standing_pose():
    ep = EpisodeConfig(body="reil", controller="g3", seconds=1.0,
                       controller_options={"feedback": "senses", "go": 0.1, "output": "angle",
                                           "inputs": INPUTS}).build()
    c = ep.controller
    assert c.output_kind == "angle" and {"low": -1.0, "high": 1.0} == {
        k: getattr(next(b for b in c.layout.blocks if b.name == "offset"), k) for k in ("low", "high")}
    rng = np.random.default_rng(5)
    offset = np.array([0.3, -0.1, -0.6, 0.2, 0.05, -0.9])
    params = c.decode(_genome(c, rng, offset=offset, gain=1.5, sense_gain=0.0)[None])
    x = np.full((1, c.n), 0.9)  # offset + gain x: 1.65 and more, beyond [0, 1]: not clipped
    assert np.allclose(c.outputs_of(params, x)[0], offset + 1.5 * 0.9, rtol=0, atol=1e-14)
    still, grab = _genome(c, rng, offset=offset, gain=0.0, sense_gain=0.0), ActionRecorder(row=0)
    ep.run(still[None], listener=grab)
    assert np.allclose(grab.seen[0], np.clip(offset, ep.low, ep.high))  # no rhythm: the targets are the offsets
