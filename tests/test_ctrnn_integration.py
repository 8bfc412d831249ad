"""The CTRNN's integration: forward Euler (the paper's, the default) and the exponential substeps (``integration``),
against a fine Runge-Kutta integration of eqs. 2-3 done here."""

import json
from pathlib import Path

import numpy as np
import pytest

from evobiped.controllers import CTRNN

ROOT = Path(__file__).resolve().parents[1]


def sigmoid(x):
    return 1.0 / (1.0 + np.exp(-x))


def reference(W, tau, alpha, seconds, h=1e-4):
    """Every neuron's output at each 0.02 s tick, eqs. 2-3 integrated by classical Runge-Kutta at step ``h``."""
    A, out = np.zeros(len(tau)), []
    f = lambda A: (-A + sigmoid(A - alpha) @ W) / tau  # noqa: E731
    for _ in range(int(round(seconds / 0.02))):
        out.append(sigmoid(A - alpha))
        for _ in range(int(round(0.02 / h))):
            k1 = f(A)
            k2 = f(A + h / 2 * k1)
            k3 = f(A + h / 2 * k2)
            A = A + h / 6 * (k1 + 2 * k2 + 2 * k3 + f(A + h * k3))
    return np.array(out)


def stepped(integration, W, tau, alpha, seconds):
    n = len(tau)
    net = CTRNN(n_outputs=1, n_neurons=n, time_constants=[0.015, 5.0], integration=integration)
    p = net.decode(np.concatenate([np.ravel(W), tau, alpha])[None])
    A, out = net.initial_state(p), []
    for _ in range(int(round(seconds / 0.02))):
        out.append(net.neuron_outputs(p, A)[0])
        A, _ = net.step(p, A, np.zeros((1, 0)))
    return np.array(out)


def test_a_self_inhibited_fast_neuron_rests_where_euler_flips_it_at_25_hz():
    """tau = dt = 0.02 s, w = -10: (dt / tau)(1 - w / 4) = 3.5 > 2.  Euler's output alternates about 0 and 1 every tick
    (25 Hz); the continuous neuron rests at 0.43, and so do the exponential substeps."""
    W, tau, alpha = np.array([[-10.0]]), np.array([0.02]), np.array([-4.0])
    euler = stepped("euler", W, tau, alpha, 0.5)[-10:, 0]
    assert np.all(np.abs(np.diff(euler)) > 0.9)  # a flip every tick: 0 <-> 1 at 25 Hz
    exact = reference(W, tau, alpha, 0.5)[-10:, 0]
    assert np.ptp(exact) < 1e-6 and exact[0] == pytest.approx(0.429, abs=1e-3)
    assert stepped("exponential", W, tau, alpha, 0.5)[-10:, 0] == pytest.approx(exact, abs=1e-6)


@pytest.mark.parametrize("seed", [0, 2])
def test_the_exponential_substeps_follow_a_fine_integration_of_a_random_network(seed):
    """Ten neurons, weights anywhere in [-16, 16], tau in [0.02, 2] s (the from-scratch walker's range), biases in
    [-4, 4]: over 1 s every output stays within 0.1 of the fine integration's; Euler's is 0.2 or more away."""
    rng = np.random.default_rng(seed)
    W, tau, alpha = rng.uniform(-16, 16, (10, 10)), np.exp(rng.uniform(np.log(0.02), np.log(2.0),
                                                                       10)), rng.uniform(-4, 4, 10)
    exact = reference(W, tau, alpha, 1.0)
    assert np.abs(stepped("exponential", W, tau, alpha, 1.0) - exact).max() < 0.1
    assert np.abs(stepped("euler", W, tau, alpha, 1.0) - exact).max() > 0.2


def test_networks_of_different_substeps_in_one_batch_step_as_they_do_alone(rng):
    net = CTRNN(n_outputs=2, n_neurons=3, inputs={"s": 1}, time_constants=[0.02, 2.0], tau_scale="log",
                integration="exponential")
    g = net.layout.sample(rng, 4)
    g[0, net.layout.slices()["weights"]] = 0.0  # one substep for this one, many for the others
    p = net.decode(g)
    assert p["substeps"][0] == 1 and p["substeps"].max() > 1
    inputs = rng.normal(size=(4, 1))
    A, out = net.step(p, net.initial_state(p), inputs)
    for i in range(4):
        pi = net.decode(g[i:i + 1])
        Ai, oi = net.step(pi, net.initial_state(pi), inputs[i:i + 1])
        assert np.array_equal(Ai[0], A[i]) and np.array_equal(oi[0], out[i])


def test_euler_stays_the_default_and_no_stored_walker_names_another_integration():
    """A genome file writes back only the options its table gave: the network walkers shipped before the option name
    no integration, so they replay with Euler, as they were recorded; the walking networks evolved with the exact
    leak step (walker-ctrnn-walk) and the commanded walkers made from them name it."""
    assert CTRNN.Options().integration == "euler"
    files = sorted((ROOT / "docs" / "walkers").glob("*ctrnn*.json"))
    walkers = [f for f in files if "robustness" not in f.name]
    assert walkers
    for f in walkers:
        options = json.loads(f.read_text())["episode"].get("controller_options", {})
        if f.name.startswith(("ctrnn_walk_", "ctrnn_command_", "ctrnn_stride_")):
            assert options["integration"] == "exponential", f.name
        else:
            assert "integration" not in options, f.name
