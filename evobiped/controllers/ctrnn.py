"""Continuous-time recurrent neural network (Reil & Husbands 2002, eqs. 2-3).

    tau_j dA_j/dt = -A_j + sum_i w_ij O_i (+ sum_k v_kj s_k)      (2)
    O_j = 1 / (1 + exp(alpha_j - A_j))                             (3)

Integration (``integration``).  ``"euler"`` (the paper's, the default, what
every stored genome was evolved and replays with): one forward Euler step per
control period dt = 0.02 s.  Its guard, tau > dt / 2, covers the leak only: a
neuron with self-weight w is stable only for (dt / tau)(1 - w / 4) < 2, so at
tau = dt = 0.02 s a neuron with w <= -8 flips 0 <-> 1 at 25 Hz where the
continuous network rests.  ``"exponential"`` (beyond the paper; for new
configs): each control period is k equal substeps h = dt / k, each the exact
step of the leak with the neurons' summed input held, A <- net + (A - net)
exp(-h / tau); k is chosen per network from its own genes, the smallest with h
rho <= 1, rho = max_j (1 + sum_i |w_ij| / 4) / tau_j (a bound on the Jacobian's
eigenvalues, sigma' <= 1/4), so no substep overshoots, whatever the gene
ranges (41 substeps at most for 10 neurons of |w| <= 16 at tau = dt).  All
activations are 0 at t = 0.  At each tick the motor outputs are O(t) = sigma(A(t)
- alpha); A then advances to t + dt.  Neurons 1..n_outputs are the motor
neurons, in the body's actuator order.

Motor map (``motor``).  ``"range"`` (the paper's, default): a motor output o in
[0, 1] is the PD target low + o (high - low) in the joint's Table II range, so
o = 0.5 is mid-range (a 0.7 rad crouch for the knee).  ``"centred"`` (beyond
the paper): target = (o - 0.5)(high - low) clipped to the range, so a network
at rest (o = 0.5) stands straight; the slope is the same.

Time constants (``time_constants``, s): the paper's [0.5, 5] by default.  A
sensed network (``inputs``) that must balance may need faster neurons: a
neuron answers its inputs within about tau, and a biped on point feet falls in
about a second; any [low, high] with low > dt / 2 can be configured.

Genome (Fig. 4): n*n weights, then n time constants, then n biases (120 values
for n = 10), then, if the controller has external inputs, k*n input weights.
Weight w_ij (from neuron i to neuron j) is gene i*n + j.

A network fit for senses (options beyond the paper; the paper's genome and
order stay the default):

- ``normalise_inputs``: each sensor reaches the network as (reading - its
  standing value) / its scale, as the body (and task) declare beside each
  sensor, so that a standing body gives inputs near 0, not constant biases;
- ``input_weights`` / ``input_sigma``: the input weights' own range and initial
  sigma (default: the recurrent weights' [-16, 16], sigma 8);
- ``tau_scale = "log"``: the time-constant genes are ln tau, so a search that
  starts mid-range starts at the geometric mean of ``time_constants`` (0.32 s
  for [0.02, 5]) rather than the arithmetic (2.5 s); ``time_constants`` may go
  down to the control period;
- ``outputs = "after"``: the motor outputs are read after the Euler step,
  O(t + dt), so a sense reaches a motor within the same tick (the paper reads
  them before: one tick of latency on every sense-to-motor path);
- ``centre_crossing``: biases alpha_j = gene + 1/2 sum_i w_ij (Mathayomchan &
  Beer 2002), so a network whose bias genes are 0 sits in the sensitive middle
  of its sigmoids instead of saturating;
- ``motor = "full"``: target = clip((o - 1/2) * 2 max(|low|, |high|), low, high):
  o = 0.5 stands straight, as with ``centred``, and the whole Table II range is
  reachable (``centred`` reaches only -0.7 rad at the knee);
- ``direct``: a linear path from the inputs to the motor outputs beside the
  network, o_j = O_j + g (c_j + sum_k D_kj s_k) (genes ``direct_biases`` c,
  n_outputs, and ``direct_weights`` D, k * n_outputs, after the input weights;
  range and sigma those of the input weights; g = ``direct_scale``), so the
  network contains the linear policy (with its neurons at rest, O = 1/2) and can
  grow past it.  With ``motor = "full"`` a unit of o is 2 max(|low|, |high|) rad
  (3.2 rad at the Reil hip): g = 0.3 makes a direct gene about a radian of
  target, as a linear policy's genes are, so a search step means the same in both.
"""

from __future__ import annotations

import copy
import functools
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from ..interface.contract import Needs
from ..core.errors import ConfigError, signals_deferred
from ..interface.genome import GeneBlock, GenomeLayout
from ..core.options import option
from .base import Controller, ControllerOptions

#: Table III (init mean, init sigma, mutation sigma) and the ranges of Sect. II-C1
WEIGHT = dict(low=-16.0, high=16.0, init_mean=0.0, init_sigma=8.0, mutation_sigma=8.0)
TAU = dict(low=0.5, high=5.0, init_mean=2.75, init_sigma=1.5, mutation_sigma=1.5)
BIAS = dict(low=-4.0, high=4.0, init_mean=0.0, init_sigma=3.0, mutation_sigma=3.0)


#: motor map name -> output kind (see evobiped.interface.mapping)
MOTOR_MAPS = {"range": "unit", "centred": "centred", "full": "centred_full"}


def sigmoid(x: np.ndarray) -> np.ndarray:
    with np.errstate(over="ignore"):  # exp(-x) = inf for x < -709 gives exactly 0, as it should: not a warning
        return 1.0 / (1.0 + np.exp(-x))


def _outputs_quiet(A: np.ndarray, alpha: np.ndarray) -> np.ndarray:
    """sigma(A - alpha) for a caller already inside ``np.errstate(over="ignore")`` (one context per tick, not per
    call): exp(alpha - A) is exp(-(A - alpha)) to the last bit (a difference negates exactly), one NumPy call less."""
    return 1.0 / (1.0 + np.exp(alpha - A))


def row_dot(x: np.ndarray, M: np.ndarray) -> np.ndarray:
    """``out[p, j] = sum_i x[p, i] M[p, i, j]``: ``x`` ``(P, k)``, ``M`` ``(P, k, n)`` -> ``(P, n)``, summed over i in
    order, so row p never depends on P and the result is bit for bit ``(x[:, :, None] * M).sum(axis=1)``: einsum's
    loop over a contiguous output axis of two or more columns adds in that order (at a sixth of the cost); a single
    column it would add in another order, so that case takes the plain products and sum."""
    if M.shape[2] >= 2:
        return np.einsum("pi,pij->pj", x, M)
    return (x[:, :, None] * M).sum(axis=1)


def _pair(v) -> None:
    if not (isinstance(v, (list, tuple)) and len(v) == 2
            and all(isinstance(x, (int, float)) and not isinstance(x, bool) and np.isfinite(x) for x in v)):
        raise ConfigError(f"must be [low, high] in s, got {v!r}")


def _range(v, what: str) -> None:
    if v is None:
        return
    ok = isinstance(v, (list, tuple)) and len(v) == 2
    ok = ok and all(isinstance(x, (int, float)) and not isinstance(x, bool) and np.isfinite(x) for x in v)
    if not ok or not v[0] < v[1]:
        raise ConfigError(f"{what} must be [low, high] with low < high, got {v!r}")


@dataclass(frozen=True, kw_only=True)
class CTRNNOptions(ControllerOptions):
    """Options of the ctrnn controller."""

    n_neurons: int = option(10, "neurons; the first drive the body's actuators", low=1, high=1000, integer=True)
    dt: float = option(0.02, "control period (forward Euler step)", unit="s", low=1e-4, high=1.0)
    motor: str = option("range", "motor map: `range` (the paper's: o in [0, 1] spans the joint's range) or `centred` "
                        "(o = 0.5 stands straight)", choices=tuple(MOTOR_MAPS))
    time_constants: tuple = option((TAU["low"], TAU["high"]), "range of the time-constant genes, [low, high] with low "
                                                              "> dt / 2",
                                   unit="s", check=_pair, span="0 < dt / 2 < low < high")
    tau_scale: str = option("linear", "time-constant genes: tau itself (`linear`, the paper's) or ln tau (`log`)",
                            choices=("linear", "log"))
    outputs: str = option("before", "motor outputs read `before` the Euler step (the paper's: one tick of latency) "
                          "or `after` it", choices=("before", "after"))
    normalise_inputs: bool = option(False, "feed (reading - standing value) / scale, as the body declares, not raw "
                                           "readings")
    input_weights: tuple | None = option(None, "range of the input-weight genes, [low, high] (default: the weights' "
                                               "[-16, 16])",
                                         check=lambda v: _range(v, "input weights"), span="low < high")
    input_sigma: float | None = option(None,
                                       "initial and mutation sigma of the input weights (default: the weights' 8)",
                                       above=0)
    centre_crossing: bool = option(False, "biases alpha_j = gene + sum_i w_ij / 2: a network of zero bias genes sits "
                                          "mid-sigmoid")
    direct: bool = option(False, "a linear path from the inputs to the motor outputs beside the network (o = O + g (c "
                                 "+ D s))")
    direct_scale: float = option(1.0, "g: the direct path's gain, in motor output per unit of its genes", above=0)
    integration: str = option("euler", "`euler`: one forward Euler step per control period (the paper's; unstable for "
                              "strong self-inhibition at tau near dt); `exponential`: substeps of the exact leak step, "
                              "as many as each network's weights and time constants need to be stable",
                              choices=("euler", "exponential"))

    def __post_init__(self):
        _tau_block(self.time_constants, self.dt, self.tau_scale)


class CTRNN(Controller):
    """Fully connected CTRNN of ``n_neurons``; the first ``n_outputs`` drive the body."""

    name: ClassVar[str] = "ctrnn"
    output_kind: ClassVar[str] = "unit"

    Options: ClassVar[type] = CTRNNOptions

    @classmethod
    def needs(cls, options: CTRNNOptions) -> Needs:
        """Any body of at most ``n_neurons`` actuators; reads the task's sensors (or the ``inputs`` option's),
        normalised if ``normalise_inputs``."""
        return Needs(task_sensors=True, max_actuators=options.n_neurons, normalised=options.normalise_inputs)

    def __init__(self, options: CTRNNOptions | None = None, *, n_outputs: int, inputs: dict[str, int] | None = None,
                 actuators=None, **given):
        o = self.options = self.own_options(options, given)
        n_neurons, dt, motor, time_constants = o.n_neurons, o.dt, o.motor, o.time_constants
        inputs = dict(inputs or {})
        self.output_kind = MOTOR_MAPS[motor]
        tau = _tau_block(time_constants, dt, o.tau_scale)
        self.log_tau = o.tau_scale == "log"
        self.outputs_after = o.outputs == "after"
        self.centre_crossing = bool(o.centre_crossing)
        self.normalises_inputs = bool(o.normalise_inputs)
        self.n = int(n_neurons)
        self.n_outputs = int(n_outputs)
        self.input_names = tuple(inputs)
        self.n_inputs = int(sum(inputs.values()))
        self.dt = float(dt)
        self.exponential = o.integration == "exponential"
        n, k = self.n, self.n_inputs
        blocks = [
            GeneBlock(name="weights", size=n * n, **WEIGHT),
            GeneBlock(name="time_constants", size=n, **tau, decays=False),  # no neutral tau: weight decay leaves it
            GeneBlock(name="biases", size=n, **BIAS),
        ]
        if k:
            lo, hi = o.input_weights if o.input_weights is not None else (WEIGHT["low"], WEIGHT["high"])
            sigma = o.input_sigma if o.input_sigma is not None else WEIGHT["init_sigma"]
            blocks.append(GeneBlock(name="input_weights", size=k * n, low=float(lo), high=float(hi),
                                    init_mean=0.5 * (lo + hi), init_sigma=float(sigma), mutation_sigma=float(sigma)))
        self.direct, self.direct_scale = bool(o.direct), float(o.direct_scale)
        if self.direct:
            lo, hi = o.input_weights if o.input_weights is not None else (WEIGHT["low"], WEIGHT["high"])
            sigma = o.input_sigma if o.input_sigma is not None else WEIGHT["init_sigma"]
            same = dict(low=float(lo), high=float(hi), init_mean=0.5 * (lo + hi), init_sigma=float(sigma),
                        mutation_sigma=float(sigma))
            blocks += [GeneBlock(name="direct_biases", size=n_outputs, **same),
                       GeneBlock(name="direct_weights", size=k * n_outputs, **same)]
        self._layout = GenomeLayout(tuple(blocks))

    @property
    def layout(self) -> GenomeLayout:
        return self._layout

    def decode(self, genomes: np.ndarray) -> dict[str, np.ndarray]:
        p = super().decode(genomes)
        P, n = p["biases"].shape[0], self.n
        W = p["weights"].reshape(P, n, n)
        tau = np.exp(p["time_constants"]) if self.log_tau else p["time_constants"]
        alpha = p["biases"] + 0.5 * W.sum(axis=1) if self.centre_crossing else p["biases"]
        out = {"W": W, "tau": tau, "alpha": alpha}
        if self.exponential:  # substeps per network: h rho <= 1, rho = max_j (1 + sum_i |w_ij| / 4) / tau_j
            rho = ((1 + 0.25 * np.abs(W).sum(axis=1)) / tau).max(axis=1)
            out["substeps"] = np.maximum(np.ceil(self.dt * rho - 1e-9), 1).astype(int)
        out["V"] = p["input_weights"].reshape(P, self.n_inputs, n) if self.n_inputs else np.zeros((P, 0, n))
        if self.direct:
            g = self.direct_scale
            out["c"], out["D"] = g * p["direct_biases"], g * p["direct_weights"].reshape(
                P, self.n_inputs, self.n_outputs)
        return out

    def initial_state(self, params: dict[str, np.ndarray]) -> np.ndarray:
        return np.zeros_like(params["alpha"])

    def outputs_of(self, params: dict[str, np.ndarray], A: np.ndarray) -> np.ndarray:
        """O = sigma(A - alpha), ``(P, n)``."""
        return sigmoid(A - params["alpha"])

    def compiled(self):
        with signals_deferred():  # its compiled step loads from numba's cache: a Ctrl-C waits until it has
            from . import ctrnn_kernel

        other = copy.copy(self)
        other.step = functools.partial(ctrnn_kernel.step, other)
        return other

    def step(self, params, state, inputs):
        with np.errstate(over="ignore"):
            alpha, W = params["alpha"], params["W"]
            external = row_dot(inputs, params["V"]) if self.n_inputs else None
            if self.exponential:
                A = self._exponential(params, state, external)
                O = _outputs_quiet(A if self.outputs_after else state, alpha)
            else:
                O = _outputs_quiet(state, alpha)
                net = row_dot(O, W)
                if external is not None:
                    net = net + external
                A = state + (self.dt / params["tau"]) * (net - state)
                if self.outputs_after:
                    O = _outputs_quiet(A, alpha)
        if self.direct:
            return A, O[:, : self.n_outputs] + params["c"] + row_dot(inputs, params["D"])
        return A, O[:, : self.n_outputs]

    def _exponential(self, params, A, external):
        """A after one control period of ``substeps`` exact leak steps each (``external``: the inputs' sum, held over
        the period); a network that needs fewer substeps than another in the batch stops early (rows stay
        independent)."""
        k, alpha, W = params["substeps"], params["alpha"], params["W"]
        decay = np.exp(-(self.dt / k)[:, None] / params["tau"])
        every = int(k.min())  # substeps every row takes: no row to hold back
        for i in range(int(k.max())):
            net = row_dot(_outputs_quiet(A, alpha), W)
            net = net if external is None else net + external
            stepped = net + (A - net) * decay
            A = stepped if i < every else np.where((i < k)[:, None], stepped, A)
        return A

    def neuron_outputs(self, params, state):
        return self.outputs_of(params, state)


def _tau_block(time_constants, dt: float, scale: str = "linear") -> dict:
    """The time-constant gene block for a ``[low, high]`` range (s): Table III's for the paper's
    [0.5, 5]; otherwise initial mean mid-range, initial and mutation sigma a third of the range
    (Table III's proportions); with ``scale = "log"`` the same in ln tau.  ``low`` must keep forward
    Euler stable at ``dt`` (low > dt / 2)."""
    ok = isinstance(time_constants, (list, tuple)) and len(time_constants) == 2
    ok = ok and all(isinstance(v, (int, float)) and not isinstance(v, bool) and np.isfinite(v) for v in time_constants)
    if not ok or not dt / 2 < time_constants[0] < time_constants[1]:
        raise ConfigError(f"time_constants must be [low, high] s with {dt / 2:g} < low < high "
                          f"(forward Euler at dt = {dt:g} s), got {time_constants!r}")
    low, high = float(time_constants[0]), float(time_constants[1])
    if scale == "log":
        low, high = float(np.log(low)), float(np.log(high))
    elif (low, high) == (TAU["low"], TAU["high"]):
        return TAU
    third = (high - low) / 3
    return dict(low=low, high=high, init_mean=0.5 * (low + high), init_sigma=third, mutation_sigma=third)
