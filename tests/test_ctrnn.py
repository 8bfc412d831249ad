"""The CTRNN (eqs. 2-3) against calculations done independently here."""

import numpy as np
import pytest

from evobiped.controllers import CTRNN
from evobiped.core.errors import ConfigError, GenomeError


def genome(net, W, tau, alpha, V=None):
    parts = [np.asarray(W, float).ravel(), tau, alpha]
    if V is not None:
        parts.append(np.asarray(V, float).ravel())
    return np.concatenate([np.atleast_1d(np.asarray(p, float)) for p in parts])


def test_layout_fig4_and_bounds():
    net = CTRNN(n_outputs=6)
    lay = net.layout
    assert lay.size == 120
    s = lay.slices()
    assert (s["weights"], s["time_constants"], s["biases"]) == (slice(0, 100), slice(100, 110), slice(110, 120))
    assert lay.low[:100].tolist() == [-16] * 100 and lay.high[:100].tolist() == [16] * 100
    assert lay.low[100:110].tolist() == [0.5] * 10 and lay.high[100:110].tolist() == [5] * 10
    assert lay.low[110:].tolist() == [-4] * 10 and lay.high[110:].tolist() == [4] * 10
    # Table III
    assert lay.init_sigma[0] == 8 and lay.init_mean[100] == 2.75 and lay.init_sigma[100] == 1.5
    assert lay.init_sigma[110] == 3 and lay.init_mean[110] == 0
    # an external input adds its own weights after the biases (Fig. 10)
    assert CTRNN(n_outputs=6, inputs={"sound": 1}).layout.size == 130


def test_single_neuron_decay():
    """With w = 0 a perturbed activation decays as (1 - dt/tau)^k (forward Euler of -A/tau)."""
    net = CTRNN(n_outputs=1, n_neurons=1)
    p = net.decode(genome(net, [0.0], [2.0], [0.0]))
    A = np.array([[1.0]])
    for _ in range(50):
        A, _ = net.step(p, A, np.zeros((1, 0)))
    assert A[0, 0] == pytest.approx((1 - 0.02 / 2.0) ** 50, rel=1e-12)
    # Euler error vs the exact exponential: k (dt/tau)^2 / 2 = 0.25 %
    assert A[0, 0] == pytest.approx(np.exp(-50 * 0.02 / 2.0), rel=3e-3)


def test_two_neurons_by_hand():
    """Two coupled neurons stepped with explicit loops equal the vectorised step."""
    W = np.array([[0.5, -3.0], [2.0, 1.5]])  # W[i, j]: from i to j
    tau = np.array([0.7, 1.9])
    alpha = np.array([0.3, -1.2])
    net = CTRNN(n_outputs=2, n_neurons=2)
    p = net.decode(genome(net, W, tau, alpha))
    A = np.zeros((1, 2))
    a = [0.0, 0.0]
    for _ in range(100):
        o = [1.0 / (1.0 + np.exp(alpha[j] - a[j])) for j in range(2)]
        a = [a[j] + 0.02 / tau[j] * (-a[j] + sum(W[i][j] * o[i] for i in range(2))) for j in range(2)]
        A, out = net.step(p, A, np.zeros((1, 0)))
        assert out[0] == pytest.approx(o, rel=1e-12)
    assert A[0] == pytest.approx(a, rel=1e-12)


def test_weight_direction_and_inputs():
    """Gene i*n + j is the weight from i to j; input weights feed every neuron (Fig. 10)."""
    net = CTRNN(n_outputs=1, n_neurons=3, inputs={"s": 1})
    W = np.zeros((3, 3))
    W[0, 2] = 4.0  # only 0 -> 2
    p = net.decode(genome(net, W, [1, 1, 1], [0, 0, 0], V=[[0.0, 2.0, 0.0]]))
    A, _ = net.step(p, np.zeros((1, 3)), np.array([[0.5]]))
    # neuron 0 gets nothing, neuron 1 gets the input 2 * 0.5, neuron 2 gets 4 * sigma(0)
    assert A[0] == pytest.approx([0.0, 0.02 * 1.0, 0.02 * 4 * 0.5])


def test_batch_rows_are_independent(rng):
    net = CTRNN(n_outputs=6)
    lay = net.layout
    g = lay.sample(rng, 9)
    p_all, p_one = net.decode(g), net.decode(g[4:5])
    A_all, A_one = np.zeros((9, 10)), np.zeros((1, 10))
    for _ in range(200):
        A_all, o_all = net.step(p_all, A_all, np.zeros((9, 0)))
        A_one, o_one = net.step(p_one, A_one, np.zeros((1, 0)))
    assert np.array_equal(A_all[4], A_one[0]) and np.array_equal(o_all[4], o_one[0])


@pytest.mark.parametrize(
    "change, words",
    [
        (lambda g: g[:-1], "119 genes"),
        (lambda g: np.where(np.arange(120) == 5, np.nan, g), "not finite"),
        (lambda g: np.where(np.arange(120) == 105, 7.0, g), "outside [0.5, 5]"),
        (lambda g: np.where(np.arange(120) == 0, -17.0, g), "weights[0]"),
    ],
)
def test_malformed_genome(change, words):
    net = CTRNN(n_outputs=6)
    good = net.layout.init_mean.copy()
    with pytest.raises(GenomeError, match=words.replace("[", r"\[").replace("]", r"\]")):
        net.decode(change(good))


def test_configurable_time_constants():
    """A faster range keeps Table III's proportions; a fast neuron follows its input within about tau."""
    net = CTRNN(n_outputs=1, n_neurons=1, inputs={"s": 1}, time_constants=[0.04, 1.0])
    lay = net.layout
    tau = lay.slices()["time_constants"]
    assert (lay.low[tau][0], lay.high[tau][0], lay.init_mean[tau][0]) == (0.04, 1.0, 0.52)
    assert lay.init_sigma[tau][0] == pytest.approx(0.32) == lay.mutation_sigma[tau][0]
    g = lay.init_mean.copy()
    g[lay.slices()["weights"]], g[tau], g[lay.slices()["biases"]], g[lay.slices()[
        "input_weights"]] = 0.0, 0.04, 0.0, 1.0
    p = net.decode(g[None])
    A = net.initial_state(p)
    for _ in range(5):  # 0.1 s = 2.5 tau of a unit step: 1 - (1 - 0.02/0.04)^5
        A, _ = net.step(p, A, np.ones((1, 1)))
    assert A[0, 0] == pytest.approx(1 - 0.5**5)


@pytest.mark.parametrize("bad", [[0.01, 5.0], [2.0, 1.0], [0.5], "fast", [0.5, float("nan")]])
def test_time_constants_that_euler_cannot_integrate_are_refused(bad):
    with pytest.raises(ConfigError, match="time_constants"):
        CTRNN(n_outputs=6, time_constants=bad)


@pytest.mark.parametrize("P", [1, 2, 16, 33, 65])
@pytest.mark.parametrize("k,n", [(1, 1), (27, 1), (5, 2), (27, 6), (27, 10), (10, 10), (40, 20)])
def test_row_dot_is_the_plain_products_and_sum_bit_for_bit(P, k, n):
    """The network's sums (einsum for speed) equal ``(x[:, :, None] * M).sum(axis=1)`` to the last bit, and row p of
    a batch equals the same row alone: shipped walkers replay exactly and results never depend on the batch size."""
    from evobiped.controllers.ctrnn import row_dot

    rng = np.random.default_rng(P * 1000 + k * 10 + n)
    x = rng.normal(size=(P, k)) * rng.choice([1e-3, 1.0, 1e3], size=(P, k))
    M = rng.normal(size=(P, k, n)) * 5.0
    plain = (x[:, :, None] * M).sum(axis=1)
    fast = row_dot(x, M)
    assert np.array_equal(fast, plain)
    assert np.array_equal(row_dot(x[-1:], M[-1:]), fast[-1:])
    wide = np.concatenate([x, x], axis=1)[:, :k]  # a non-contiguous slice, as the inputs are
    assert np.array_equal(row_dot(wide, M), plain)
