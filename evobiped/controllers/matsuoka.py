"""Matsuoka's neural rhythm generator as used by Taga, Yamaguchi & Shimizu 1991 (eqs. 5-6).

    tau_i  du_i/dt = -u_i + sum_j w_ij y_j - beta v_i + u_0 + Feed_i
    tau'_i dv_i/dt = -v_i + y_i,          y_i = max(0, u_i)

One unit oscillator (a flexor and an extensor neuron) per actuated joint, in
the body's actuator order; joint torque (or signed output) ``p_e y_e - p_f y_f``.
w_ij is the weight *from* neuron j *to* neuron i.  The body's actuators are two
legs of equal length (first half one leg, second half the other), the first
joint of each leg its hip.  Connections (Appendix D, Fig. 3):

* w_fe between the flexor and the extensor of every oscillator;
* w_rl between the two hips, flexor-flexor and extensor-extensor;
* w_hka from both neurons of a leg's hip to the extensor of every other joint of
  that leg (Taga: knee and ankle extensors).

Feedback: on a body with the sensors ``link_angles``, ``link_velocities`` and
``ground_contact`` (the Taga biped) the Appendix C pathways Feed_1..Feed_12
(with F_eed6 = a_5 (x_14 - pi/2) h(F_g4): the printed ``a_5(x_14 pi/2)`` is a
transcription slip), otherwise Feed = 0.  ``feedback = "senses"`` feeds any body's senses instead: the
controller's inputs x ``(k,)`` (the senses it is wired to, normalised, in the stance frame where ``frame``
says so) through an evolvable gain matrix K ``(n_osc, k)``, push-pull as Appendix C's pathways are: oscillator
o's flexor receives +(K x)_o and its extensor -(K x)_o.  With foot contacts, the time since touch-down and
the pelvis' tilt among the inputs these are the paper's kinds of pathway (touch-down resetting the hips'
phase, posture terms) with their gains and signs evolved.  Forward Euler at the control period
(the physics step by default: tau = 0.025 s over dt = 0.5 ms), or with ``integration = "exponential"`` each leak
solved exactly over the period, the other inputs held (stable for any tau; for control periods of 10-20 ms).  The
initial state is u = v = 0 (``initial_u`` > 0 starts the first leg's flexors and the
second leg's extensors there, e.g. for the isolated generator, which from an
exactly symmetric state settles to its fixed point instead of oscillating).

Genome blocks (Taga's Appendix D values: :mod:`evobiped.experiments.taga.parameters`): per-oscillator
``tau``, ``tau_adapt``, ``p_e``, ``p_f``; scalars ``beta``, ``w_fe``, ``w_rl``,
``w_hka``; with Taga's feedback, ``feedback`` = a_1..a_8; with the senses', ``sense_gain`` = K row-major
(oscillator by input); with ``output = "angle"``, ``bias`` (rad, per oscillator): the posture it swings about; with
``reflex``, ``reflex_gain`` R (oscillator by input): the target gains reflex_scale R x.  ``symmetric``: the first
leg's genes serve both legs (:mod:`evobiped.controllers.bilateral`); in the stance frame each leg's oscillator stays
on its leg (:meth:`reframe`).  The
tonic input u_0 is a structure option (the experiments' control parameter, Taga's speed command), not a gene: a level,
or a schedule ``[[t_s, level], ...]`` (seconds from the episode start, :func:`evobiped.core.schedule.timed_levels`; 0
before its first step), so one episode can walk a walker through several speeds.  A level is the decoded
``params["u0"]`` ``(P, 1)`` (an experiment may set it per walker, as :class:`~evobiped.experiments.taga.walking.
TagaWalker` does); a schedule's level at each tick's start time k * period (the state's tick count ``k``) replaces it.
"""

from __future__ import annotations

import copy

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from ..interface.contract import Actuator, Needs, Offer, index, legs, problem
from ..core.errors import ConfigError
from ..interface.genome import GeneBlock, GenomeLayout
from ..core.options import option
from ..core.schedule import level_at, timed_levels
from .base import Controller, ControllerOptions

#: sensors the Appendix C feedback needs (provided by the Taga body), with their widths
FEEDBACK_SENSORS = {"link_angles": 4, "link_velocities": 4, "ground_contact": 2}
#: the joints of each of Taga's legs, the order of his oscillators within a leg
TAGA_JOINTS = ("hip", "knee", "ankle")
#: gene ranges and GA distributions
BLOCKS = {
    "tau": dict(low=0.005, high=1.0, init_mean=0.05, init_sigma=0.02, mutation_sigma=0.02),
    "tau_adapt": dict(low=0.02, high=5.0, init_mean=0.4, init_sigma=0.2, mutation_sigma=0.2),
    "p_e": dict(low=0.0, high=200.0, init_mean=50.0, init_sigma=30.0, mutation_sigma=20.0),
    "p_f": dict(low=0.0, high=200.0, init_mean=50.0, init_sigma=30.0, mutation_sigma=20.0),
    "beta": dict(low=0.0, high=10.0, init_mean=2.5, init_sigma=1.0, mutation_sigma=0.5),
    "w_fe": dict(low=-10.0, high=0.0, init_mean=-2.0, init_sigma=1.0, mutation_sigma=0.5),
    "w_rl": dict(low=-10.0, high=0.0, init_mean=-1.0, init_sigma=0.5, mutation_sigma=0.5),
    "w_hka": dict(low=-10.0, high=0.0, init_mean=-1.0, init_sigma=0.5, mutation_sigma=0.5),
    "feedback": dict(low=0.0, high=10.0, init_mean=2.0, init_sigma=1.0, mutation_sigma=0.5),
    "bias": dict(low=-1.0, high=1.0, init_mean=0.0, init_sigma=0.05, mutation_sigma=0.05),
    "sense_gain": dict(low=-2.0, high=2.0, init_mean=0.0, init_sigma=0.1, mutation_sigma=0.1),
}


def taga_feedback(a: np.ndarray, angles: np.ndarray, rates: np.ndarray, contact: np.ndarray) -> np.ndarray:
    """Appendix C: Feed_1..Feed_12 ``(P, 12)`` in Taga's neuron numbering.

    ``a`` (P, 8) = a_1..a_8; ``angles``/``rates`` (P, 4) = x5, x11, x8, x14 and
    their rates (right thigh, right shank, left thigh, left shank); ``contact``
    (P, 2) = h(F_g2), h(F_g4).
    """
    h = np.pi / 2
    x5, x11, x8, x14 = (angles[:, i] for i in range(4))
    dx11, dx14 = rates[:, 1], rates[:, 3]
    cr, cl = contact[:, 0], contact[:, 1]
    a1, a2, a3, a4, a5, a6, a7, a8 = (a[:, i] for i in range(8))
    f = np.empty((angles.shape[0], 12))
    f[:, 0] = a1 * (x5 - h) - a2 * (x8 - h) + a3 * (x11 - h) * cr + a4 * cl
    f[:, 1] = a1 * (h - x5) - a2 * (h - x8) + a3 * (h - x11) * cr - a4 * cl
    f[:, 2] = a1 * (x8 - h) - a2 * (x5 - h) + a3 * (x14 - h) * cl + a4 * cr
    f[:, 3] = a1 * (h - x8) - a2 * (h - x5) + a3 * (h - x14) * cl - a4 * cr
    f[:, 4] = a5 * (h - x14) * cl
    f[:, 5] = a5 * (x14 - h) * cl  # the printed "a5(x14 pi/2)" read as a5(x14 - pi/2)
    f[:, 6] = a5 * (h - x11) * cr
    f[:, 7] = a5 * (x11 - h) * cr
    f[:, 8] = a6 * (h - x11) * cr + a7 * (h - x14) * cl - a8 * dx11 * cr
    f[:, 9] = a6 * (x11 - h) * cr + a7 * (x14 - h) * cl + a8 * dx11 * cr
    f[:, 10] = a6 * (h - x14) * cl + a7 * (h - x11) * cr - a8 * dx14 * cl
    f[:, 11] = a6 * (x14 - h) * cl + a7 * (x11 - h) * cr + a8 * dx14 * cl
    return f


@dataclass(frozen=True, kw_only=True)
class MatsuokaOptions(ControllerOptions):
    """Options of the matsuoka controller."""

    u0: float | list = option(5.5, "tonic input u_0 (the experiments' speed control): a level, or a schedule "
                              "[[t, level], ...] (t in s from the episode start)", check=timed_levels,
                              span="level >= 0, or [[t_s, level], ...]")
    feedback: str = option("auto", "Appendix C feedback: `taga` (required), `none`, `auto` (where the body has Taga's "
                           "legs and sensors), or `senses`: any body's normalised senses through evolved gains",
                           choices=("auto", "taga", "senses", "none"))
    output: str = option("signed", "what p_e y_e - p_f y_f is to the body: `signed` (a torque, or a PD target "
                         "centred on the joint's range), `angle` (a PD target in rad: 0 is the standing pose)",
                         choices=("signed", "angle"))
    reflex: bool = option(False, "with `senses` feedback and `angle` output: the senses also reach each joint's "
                          "target directly through evolved gains R (a posture reflex beside the rhythm)")
    reflex_scale: float = option(1.0, "the reflex's gains times this (their genes stay O(1) while the reflex is "
                                 "gentle: an evolution strategy's sigma is in gene units)", above=0)
    initial_u: float = option(0.0, "initial u of the first leg's flexors and the second leg's extensors")
    dt: float | None = option(None, "control period (none: the physics step)", unit="s", above=0)
    symmetric: bool = option(False, "one set of genes for both legs: the second leg's oscillators mirror the "
                             "first's (time constants, amplitudes, posture, and gains reading the mirrored senses)")
    integration: str = option("euler", "`euler`: forward Euler at the control period (Taga's); `exponential`: each "
                              "leak solved exactly over the period with the other inputs held (stable for any "
                              "time constant)", choices=("euler", "exponential"))


class Matsuoka(Controller):
    """Matsuoka oscillators, one per actuator; Taga's rhythm generator on the Taga body."""

    docs_note: ClassVar[str] = (
        "Taga's rhythm generator; on the Taga body with his Appendix C pathways ([taga.md](taga.md)). On any body "
        "`feedback = \"senses\"` feeds the body's normalised senses into the oscillators; with `frame = \"stance\"` "
        "each leg's oscillator stays on its leg while the genes it follows are the stance or the swing leg's: "
        "`--preset walker-matsuoka-walk` walks the Reil body from scratch ([rhythm_walkers.md](rhythm_walkers.md)).")

    name: ClassVar[str] = "matsuoka"
    output_kind: ClassVar[str] = "signed"
    Options: ClassVar[type] = MatsuokaOptions

    @classmethod
    def needs(cls, options: MatsuokaOptions) -> Needs:
        """Two legs with the same joints; Taga's feedback where the body has his legs and sensors."""
        taga = Needs(sensors=FEEDBACK_SENSORS, joints=TAGA_JOINTS)
        if options.feedback == "taga":
            return Needs(sensors=FEEDBACK_SENSORS, joints=TAGA_JOINTS, paired_legs=True)
        if options.feedback == "senses":
            return Needs(task_sensors=True, paired_legs=True, normalised=True)
        return Needs(paired_legs=True, optional=taga if options.feedback == "auto" else None)

    def __init__(self, options: MatsuokaOptions | None = None, *, n_outputs: int, inputs: dict[str, int] | None = None,
                 actuators: tuple[Actuator, ...] | None = None, **given):
        o = self.options = self.own_options(options, given)
        inputs = dict(inputs or {})
        # the episode checked needs(): two legs, and Taga's legs and sensors where the feedback is "taga"; "auto"
        # takes the feedback where the wiring gave its sensors
        taga_body = actuators is not None and problem(Needs(joints=TAGA_JOINTS), Offer(actuators, {})) is None
        has = taga_body and all(s in inputs for s in FEEDBACK_SENSORS)
        self.feedback = ("taga" if (o.feedback == "taga" or (o.feedback == "auto" and has))
                         else "senses" if o.feedback == "senses" else "none")
        self.normalises_inputs = self.feedback == "senses"
        self.output_kind = o.output
        u0, initial_u, dt = o.u0, o.initial_u, o.dt
        self.n_outputs = self.n_osc = int(n_outputs)
        self.n = 2 * self.n_osc
        #: u_0's schedule: step times (K,) s and levels (K,); ``u0_constant``: one level from t = 0 (``params["u0"]``)
        self.u0_times, self.u0_levels = timed_levels(u0)
        self.u0_constant = len(self.u0_times) == 1 and self.u0_times[0] == 0.0
        self.u0, self.initial_u = float(level_at(self.u0_times, self.u0_levels, 0.0)), float(initial_u)
        self.input_names = tuple(inputs)
        self._widths = dict(inputs)
        self.dt = None if dt is None else float(dt)
        self.period = self.dt
        n_osc = self.n_osc
        #: the mirror spreading the first leg's genes over both (``symmetric``; set by the episode's wiring)
        self.bilateral = None
        self.symmetric = bool(o.symmetric)
        units = n_osc // 2 if self.symmetric else n_osc  # oscillators with genes of their own
        blocks = [GeneBlock(name=b, size=units, **BLOCKS[b]) for b in ("tau", "tau_adapt", "p_e", "p_f")]
        blocks += [GeneBlock(name=b, size=1, **BLOCKS[b]) for b in ("beta", "w_fe", "w_rl", "w_hka")]
        self.n_inputs = int(sum(inputs.values()))
        if self.output_kind == "angle":  # each joint's posture: the target (rad) its oscillator swings about
            blocks.append(GeneBlock(name="bias", size=units, **BLOCKS["bias"]))
        if self.feedback == "taga":
            blocks.append(GeneBlock(name="feedback", size=8, **BLOCKS["feedback"]))
        elif self.feedback == "senses":
            blocks.append(GeneBlock(name="sense_gain", size=units * self.n_inputs, **BLOCKS["sense_gain"]))
        self.reflex = bool(o.reflex)
        if self.reflex:
            if self.feedback != "senses" or self.output_kind != "angle":
                raise ConfigError("matsuoka: reflex needs feedback = \"senses\" and output = \"angle\"")
            blocks.append(GeneBlock(name="reflex_gain", size=units * self.n_inputs, **BLOCKS["sense_gain"]))
        self._layout = GenomeLayout(tuple(blocks))
        # Taga's neuron k (0-based) sits at internal index _taga_order[k]: his oscillators are the
        # hips, the knees, the ankles, the first leg's before the second's
        taga_osc = [index(actuators, leg, j) for j in TAGA_JOINTS for leg in legs(actuators)] if taga_body else []
        self._taga_order = np.array([2 * o + s for o in taga_osc for s in (0, 1)], int)

    # ------------------------------------------------------------ genome
    @property
    def layout(self) -> GenomeLayout:
        return self._layout

    def roles(self) -> np.ndarray:
        """Joint role of each oscillator within its leg: 0 hip, 1 knee, 2 ankle, ..."""
        return np.arange(self.n_osc) % (self.n_osc // 2)

    def bound(self, dt: float) -> "Matsuoka":
        """A copy integrating with Euler steps of ``dt`` s (the physics step when ``dt`` is None)."""
        other = copy.copy(self)
        other.period = float(dt)
        return other

    def decode(self, genomes: np.ndarray) -> dict[str, np.ndarray]:
        g = super().decode(genomes)
        P, n = g["beta"].shape[0], self.n
        if self.symmetric:  # the first leg's genes for both legs
            if self.bilateral is None:
                raise ConfigError("matsuoka: symmetric needs the body's mirror (build it through an episode)")
            sym = self.bilateral
            for b in ("tau", "tau_adapt", "p_e", "p_f", "bias"):
                if b in g:
                    g[b] = sym.units(g[b])
            for b in ("sense_gain", "reflex_gain"):
                if b in g:
                    g[b] = sym.gains(g[b].reshape(P, self.n_osc // 2, self.n_inputs)).reshape(P, -1)
        rep = lambda x: np.repeat(x, 2, axis=1)  # noqa: E731  per-oscillator -> per-neuron
        W = np.zeros((P, n, n))
        f, e = 2 * np.arange(self.n_osc), 2 * np.arange(self.n_osc) + 1
        W[:, f, e] = W[:, e, f] = g["w_fe"]
        half = self.n_osc // 2
        hips = (0, half)
        W[:, 2 * hips[0], 2 * hips[1]] = W[:, 2 * hips[1], 2 * hips[0]] = g["w_rl"][:, 0]
        W[:, 2 * hips[0] + 1, 2 * hips[1] + 1] = W[:, 2 * hips[1] + 1, 2 * hips[0] + 1] = g["w_rl"][:, 0]
        for hip in hips:
            for o in range(hip + 1, hip + half):
                W[:, 2 * o + 1, 2 * hip] = W[:, 2 * o + 1, 2 * hip + 1] = g["w_hka"][:, 0]
        out = dict(W=W, tau=rep(g["tau"]), tau_adapt=rep(g["tau_adapt"]), beta=g["beta"], p_e=g["p_e"], p_f=g["p_f"],
                   bias=g["bias"] if "bias" in g else np.zeros((P, self.n_osc)))
        out["u0"] = np.full((P, 1), self.u0)  # u_0 at 0 s; a schedule's level is read at each tick instead
        out["a"] = g["feedback"] if self.feedback == "taga" else np.zeros((P, 8))
        if self.feedback == "senses":
            out["K"] = g["sense_gain"].reshape(P, self.n_osc, self.n_inputs)
        if self.reflex:
            out["R"] = g["reflex_gain"].reshape(P, self.n_osc, self.n_inputs)
        return out

    # ------------------------------------------------------------ dynamics
    def initial_state(self, params: dict[str, np.ndarray]) -> dict:
        """u, v ``(P, n)`` (see the module for u's start) and the tick count k (0)."""
        P = params["W"].shape[0]
        u = np.zeros((P, self.n))
        half = self.n_osc // 2  # first leg's flexors and second leg's extensors ahead
        u[:, 0 : 2 * half : 2] = self.initial_u
        u[:, 2 * half + 1 :: 2] = self.initial_u
        state = {"u": u, "v": np.zeros((P, self.n)), "k": 0}
        if self.frame is not None:  # the rows whose second leg stood at the last tick (reframe)
            state["flip"] = np.zeros(P, bool)
        return state

    def reframe(self, state, flip):
        """Each leg's oscillator stays on its leg: where the stance leg changed, the legs' oscillators swap places."""
        return self.frame.follow(state, flip, {"u": 2, "v": 2})

    def u0_at(self, params: dict[str, np.ndarray], k: int) -> np.ndarray | float:
        """u_0 at tick ``k``: ``params["u0"]`` ``(P, 1)`` for a constant one, else the schedule's level at k * period
        s."""
        return params["u0"] if self.u0_constant else float(level_at(self.u0_times, self.u0_levels, k * self.period))

    def feed(self, params: dict[str, np.ndarray], inputs: np.ndarray) -> np.ndarray:
        """Feed_i ``(P, n)`` in internal neuron order (0 without feedback)."""
        P = inputs.shape[0]
        out = np.zeros((P, self.n))
        if self.feedback == "senses":  # push-pull: +K x to each flexor, -K x to its extensor
            f = np.einsum("pok,pk->po", params["K"], inputs)
            out[:, 0::2], out[:, 1::2] = f, -f
            return out
        if self.feedback != "taga":
            return out
        cols, start = {}, 0
        for name, w in self._widths.items():
            cols[name] = inputs[:, start : start + w]
            start += w
        f = taga_feedback(params["a"], cols["link_angles"], cols["link_velocities"], cols["ground_contact"])
        out[:, self._taga_order] = f
        return out

    def torques(self, params: dict[str, np.ndarray], y: np.ndarray) -> np.ndarray:
        """``p_e y_e - p_f y_f`` (plus the posture ``bias`` with ``output = "angle"``) per oscillator ``(P, n_osc)``."""
        out = params["p_e"] * y[:, 1::2] - params["p_f"] * y[:, 0::2]
        return out + params["bias"] if self.output_kind == "angle" else out

    def step(self, params, state, inputs):
        if self.period is None:
            raise ConfigError("matsuoka: the control period is unknown (step the controller bound(dt) returns, or give "
                              "dt)")
        u, v, k = state["u"], state["v"], state["k"]
        y = np.maximum(u, 0.0)
        out = self.torques(params, y)
        if self.reflex:
            out = out + self.options.reflex_scale * np.einsum("pok,pk->po", params["R"], inputs)
        net = (params["W"] * y[:, None, :]).sum(axis=2)
        du = (-u + net - params["beta"] * v + self.u0_at(params, k) + self.feed(params, inputs)) / params["tau"]
        dv = (-v + y) / params["tau_adapt"]
        h = self.period
        if self.options.integration == "exponential":  # x' = (x_inf - x)/tau over h: x_inf + (x - x_inf) e^-h/tau
            ku, kv = np.exp(-h / params["tau"]), np.exp(-h / params["tau_adapt"])
            u_inf, v_inf = u + params["tau"] * du, v + params["tau_adapt"] * dv
            return {**state, "u": u_inf + (u - u_inf) * ku, "v": v_inf + (v - v_inf) * kv, "k": k + 1}, out
        return {**state, "u": u + h * du, "v": v + h * dv, "k": k + 1}, out

    def neuron_outputs(self, params, state):
        return np.maximum(state["u"], 0.0)
