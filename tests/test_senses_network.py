"""A CTRNN fit for senses (the ctrnn controller's options beyond the paper) and control latency, against
calculations done here: outputs after the Euler step, ln-tau genes, centre-crossing biases, the full-range motor
map, normalised inputs as the body declares them, the input-weight block, actions applied k ticks late."""

import dataclasses

import numpy as np
import pytest

from evobiped.bodies import ReilBiped
from evobiped.controllers import CTRNN
from evobiped.episode import EpisodeConfig
from evobiped.core.errors import ConfigError
from evobiped.interface.mapping import to_action

from .test_ctrnn import genome

SENSES = ["joint_angles", "joint_velocities", "foot_contact", "pelvis_tilt", "pelvis_tilt_rate", "com_from_feet",
          "com_velocity"]


def test_outputs_after_the_update_let_a_sense_reach_a_motor_in_the_same_tick():
    """One neuron, input weight v: before (the paper's order) O = sigma(A(t) - alpha), after O = sigma(A(t+dt) -
    alpha)."""
    x = np.array([[2.0]])
    outs = {}
    for order in ("before", "after"):
        net = CTRNN(n_outputs=1, n_neurons=1, inputs={"s": 1}, outputs=order, time_constants=[0.05, 1.0])
        p = net.decode(genome(net, [0.0], [0.1], [0.0], V=[[3.0]]))
        A, outs[order] = net.step(p, np.zeros((1, 1)), x)
        assert A[0, 0] == pytest.approx(0.02 / 0.1 * 3.0 * 2.0)  # tau dA/dt = -A + v x from A = 0
    assert outs["before"][0, 0] == 0.5  # A(0) = 0: the input has not arrived
    assert outs["after"][0, 0] == pytest.approx(1 / (1 + np.exp(-1.2)))


def test_log_time_constants_and_centre_crossing_biases():
    net = CTRNN(n_outputs=2, n_neurons=2, time_constants=[0.02, 5.0], tau_scale="log", centre_crossing=True)
    s = net.layout.slices()["time_constants"]
    assert net.layout.low[s].tolist() == pytest.approx([np.log(0.02)] * 2) and net.layout.high[
        s].tolist() == pytest.approx([np.log(5.0)] * 2)
    assert np.exp(net.layout.init_mean[s][0]) == pytest.approx(np.sqrt(0.02 * 5.0))  # geometric mean, 0.32 s
    W = [[1.0, -2.0], [3.0, 4.0]]  # w_ij from i to j
    p = net.decode(genome(net, W, [np.log(0.1), np.log(2.0)], [0.5, -0.5]))
    assert p["tau"][0].tolist() == pytest.approx([0.1, 2.0])
    assert p["alpha"][0].tolist() == pytest.approx([0.5 + 0.5 * (1.0 + 3.0), -0.5 + 0.5 * (-2.0 + 4.0)])
    # dt / 2 < low still holds in ln tau
    with pytest.raises(ConfigError, match="time_constants"):
        CTRNN(n_outputs=1, time_constants=[0.005, 5.0], tau_scale="log")


def test_the_full_motor_map_stands_at_one_half_and_reaches_every_joint_s_whole_range():
    low, high = ReilBiped().action_bounds()  # Table II: hip pitch [-1.3, 1.6], roll [-0.8, 0.8], knee [-1.4, 0]
    net = CTRNN(n_outputs=6, motor="full")
    o = np.array([[0.0] * 6, [0.5] * 6, [1.0] * 6])
    t = to_action(net.output_kind, low, high, "position", o)
    assert t[0].tolist() == pytest.approx(low.tolist()) and t[2].tolist() == pytest.approx(high.tolist())
    assert t[1].tolist() == [0.0] * 6
    assert to_action("centred", low, high, "position", o)[0, 2] == pytest.approx(-0.7)  # what `centred` cannot pass


def test_the_input_weight_block_has_its_own_range_and_sigma():
    net = CTRNN(n_outputs=6, n_neurons=20, inputs={"a": 3}, input_weights=[-25.0, 25.0], input_sigma=0.5)
    s = net.layout.slices()["input_weights"]
    assert net.layout.size == 20 * 20 + 40 + 60
    assert set(net.layout.low[s]) == {-25.0} and set(net.layout.init_sigma[s]) == {0.5} and set(
        net.layout.mutation_sigma[s]) == {0.5}
    assert set(net.layout.high[: 400]) == {16.0}  # the recurrent weights keep the paper's range


def test_normalised_inputs_are_the_body_s_declared_standing_values_and_scales():
    """At the reset pose (standing straight, both feet down) every normalised reading is near 0 but the
    contacts (+1): the constant biases raw readings would be are gone."""
    cfg = EpisodeConfig(seconds=0.2, controller_options=dict(inputs=SENSES, normalise_inputs=True, motor="full"))
    ep = cfg.build()
    g = np.zeros(ep.controller.layout.size)
    g[ep.controller.layout.slices()["time_constants"]] = 1.0
    state = ep.start(g)  # every output 0.5: targets 0, standing straight
    ep.advance(state, ticks=5)  # the feet have touched down
    x = ep._inputs(state, 1)[0][0]
    raw = np.concatenate([ep.body.sensors(state.sims)[n][0] for n in SENSES])
    centre, scale = ep.controller.input_norm
    assert x.tolist() == pytest.approx(((raw - centre) / scale).tolist())
    contacts = slice(12, 14)
    assert x[contacts].tolist() == [1.0, 1.0]
    assert np.abs(np.delete(x, np.r_[contacts])).max() < 0.5, x
    assert raw[14 + 4 + 1] == pytest.approx(-0.25, abs=0.01)  # the raw lateral offset of the left foot


def test_normalising_a_sensor_with_no_declared_scale_is_one_line():
    from evobiped.bodies import BODIES, TagaBiped

    class Undeclared(TagaBiped):
        name = "undeclared"
        sensor_norms = {}

    BODIES["undeclared"] = Undeclared
    try:
        with pytest.raises(ConfigError, match="normalises its inputs, but no standing value and scale is declared for "
                                              "link_angles"):
            EpisodeConfig(body="undeclared", controller_options=dict(normalise_inputs=True,
                                                                     inputs=["link_angles"])).build()
    finally:
        del BODIES["undeclared"]


@pytest.mark.parametrize("bad", [-1, 1.5, 101, True])
def test_a_bad_latency_is_one_line(bad):
    with pytest.raises(ConfigError, match="episode.controller_options.latency"):
        EpisodeConfig(controller_options=dict(latency=bad))


def test_latency_applies_each_action_k_ticks_late():
    """An open-loop controller's actions depend on time alone: with latency k the body gets the action computed
    k ticks before (the first one held until then)."""
    cfg = EpisodeConfig(controller="open-loop", seconds=0.5)
    genome = cfg.layout().init_mean + 0.1

    def applied(k):
        actions = []

        class Watch:
            def start(self, episode, sims): ...
            def tick(self, t, sims, ids, neurons, action, task_state): actions.append(action[0].copy())
            def end(self, result): ...

        c = dataclasses.replace(cfg, controller_options={"latency": k})
        c.build().run(genome, listener=Watch())
        return np.array(actions)

    a0, a2 = applied(0), applied(2)
    assert np.array_equal(a2[2:], a0[:-2]) and np.array_equal(a2[:3], a0[[0, 0, 0]])
    assert not np.array_equal(a2, a0)
