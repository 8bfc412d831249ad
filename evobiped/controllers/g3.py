"""The G3 GO Gait Generator as a body controller (Pribe, Grossberg & Cohen 1997).

One G3 channel (excitatory x_k, slow inhibitory y_k; :mod:`evobiped.controllers.g3_network`) per
driven joint, ``n_outputs`` channels in the body's actuator order, so the same
class drives any body.  Evolvable (the genome):

* ``self_inhibition`` D_kk (N) and ``coupling`` D_kj, k != j (N(N-1), row-major
  without the diagonal): the inhibition matrix of eq. (1);
* ``gain`` and ``offset`` (N each): the output mapping
  o_k = clip(offset_k + gain_k x_k, 0, 1) ("unit" output: a PD target
  low + o (high - low) for the Reil body, or a torque for torque bodies), or with ``output = "angle"``
  o_k = offset_k + gain_k x_k, a PD target in rad about the standing pose (offset in [-1, 1] rad).

With ``feedback = "senses"`` the body feeds back into it: the controller's inputs x ``(k,)`` (the senses it is
wired to, normalised, in the stance frame where ``frame`` says so) reach channel k's excitatory input through
evolved gains, I_k = [GO_k + (K x)_k]^+ held over each control period (``sense_gain``: K ``(N, k)`` row-major),
so touch-downs and the trunk's tilt can reset and shape the rhythm as Taga's pathways do his.  With ``reflex``
(and an ``angle`` output) they also reach the targets directly, o += reflex_scale R x (``reflex_gain``: R ``(N, k)``),
a posture reflex beside the rhythm; with ``symmetric`` the first leg's genes serve both legs
(:mod:`evobiped.controllers.bilateral`); in the stance frame each leg's channels stay on its leg (:meth:`reframe`).

Fixed (options): the cell constants A-G2 of a preset (default ``fig4``); the GO
signal ``go``, either a level or a schedule ``[[t_s, level], ...]`` (seconds from
the episode start; the level is 0 before the first entry: :func:`evobiped.core.schedule.timed_levels`, the parser
the matsuoka controller's ``u0`` shares), so a user can speed
a walker up or switch its gait during an episode by changing one number; the
per-channel GO lag ``lag`` (channel k receives every GO change k*lag model
time units late, to break symmetry as the paper's cordlag/sidelag do, rounded
to the internal step); and the time scale.

Time: the network's equations are dimensionless.  ``time_scale`` is the number
of model time units per second of simulated time (default 10: the Fig. 4 walk,
period 10.0 units at I = 0.1, steps once per 1.0 s).  Each control period
``dt`` (s) advances the network by dt * time_scale units in RK4 steps of at most
``max_step`` units (0.05: the Fig. 4 period is within 0.02 % of its dt -> 0 value).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from ..interface.contract import Needs
from ..core.errors import ConfigError
from .g3_network import CELLS, rk4_step
from ..interface.genome import GeneBlock, GenomeLayout
from ..core.options import option
from ..core.schedule import level_at, timed_levels
from .base import Controller, ControllerOptions

SELF = dict(low=0.0, high=1.5, init_mean=0.9, init_sigma=0.1, mutation_sigma=0.1)
COUPLING = dict(low=0.0, high=1.5, init_mean=0.15, init_sigma=0.1, mutation_sigma=0.05)
GAIN = dict(low=-2.0, high=2.0, init_mean=0.0, init_sigma=1.0, mutation_sigma=0.3)
OFFSET = dict(low=0.0, high=1.0, init_mean=0.5, init_sigma=0.2, mutation_sigma=0.1)
#: the offset of an ``angle`` output: rad about the standing pose
ANGLE_OFFSET = dict(low=-1.0, high=1.0, init_mean=0.0, init_sigma=0.05, mutation_sigma=0.05)
SENSE_GAIN = dict(low=-1.0, high=1.0, init_mean=0.0, init_sigma=0.05, mutation_sigma=0.05)
REFLEX_GAIN = dict(low=-2.0, high=2.0, init_mean=0.0, init_sigma=0.1, mutation_sigma=0.1)


@dataclass(frozen=True, kw_only=True)
class G3Options(ControllerOptions):
    """Options of the g3 controller."""

    dt: float = option(0.02, "control period", unit="s", above=0)
    go: float = option(0.1, "the GO signal: a level, or a schedule [[t, level], ...] (t in s from the episode start)",
                       check=timed_levels, span="level >= 0, or [[t_s, level], ...]")
    lag: float = option(0.05, "GO lag of each channel behind the previous one", unit="model time", low=0)
    time_scale: float = option(10.0, "model time units per second of simulated time", unit="1/s", above=0)
    max_step: float = option(0.05, "largest RK4 step", unit="model time", above=0)
    preset: str = option("fig4", "cell constants A-G2 of this published parameter set", choices=tuple(CELLS))
    feedback: str = option("none", "`none`: the GO signal alone drives it; `senses`: the body's normalised senses "
                           "also reach each channel's input through evolved gains", choices=("none", "senses"))
    output: str = option("unit", "what offset + gain x is to the body: `unit` (clipped to [0, 1] across the joint's "
                         "range, or a torque), `angle` (a PD target in rad: 0 is the standing pose)",
                         choices=("unit", "angle"))
    reflex: bool = option(False, "with `senses` feedback and `angle` output: the senses also reach each joint's "
                          "target directly through evolved gains R (a posture reflex beside the rhythm)")
    reflex_scale: float = option(1.0, "the reflex's gains times this (rad of target per unit of gene and of "
                                 "normalised sense)", above=0)
    symmetric: bool = option(False, "one set of genes for both legs: the second leg's channels mirror the first's "
                             "(inhibitions, output mapping, and gains reading the mirrored senses)")


class G3Controller(Controller):
    """``n_outputs`` G3 channels, one per actuator; D and the output mapping evolve."""

    docs_note: ClassVar[str] = (
        "Pribe, Grossberg & Cohen's GO Gait Generator driving a body, one channel per joint; the paper's quadruped "
        "network is `evobiped g3`'s ([g3.md](g3.md)). `--preset walker-g3-walk` evolves it with the body's senses in "
        "the stance frame ([rhythm_walkers.md](rhythm_walkers.md)).")

    name: ClassVar[str] = "g3"
    output_kind: ClassVar[str] = "unit"

    Options: ClassVar[type] = G3Options

    @classmethod
    def needs(cls, options: G3Options) -> Needs:
        """Any body; no sensors (the GO signal is an option), or with ``feedback = "senses"`` the task's and the
        ``inputs`` option's, normalised."""
        if options.feedback == "senses":
            return Needs(task_sensors=True, normalised=True)
        return Needs(deaf=True)

    def __init__(self, options: G3Options | None = None, *, n_outputs: int, inputs: dict[str, int] | None = None,
                 actuators=None, **given):
        o = self.options = self.own_options(options, given)
        dt, go, lag, time_scale, max_step, preset = o.dt, o.go, o.lag, o.time_scale, o.max_step, o.preset
        inputs = dict(inputs or {})
        self.feedback = o.feedback
        if inputs and self.feedback != "senses":
            raise ConfigError(f"g3: takes no sensor inputs (got {sorted(inputs)}) without feedback = \"senses\"; "
                              "its GO signal is the 'go' option")
        self.normalises_inputs = self.feedback == "senses"
        self.output_kind = o.output
        if n_outputs < 1:
            raise ConfigError("g3: needs at least one output channel")
        self.n_outputs = self.n = int(n_outputs)
        self.input_names = tuple(inputs)
        self.n_inputs = int(sum(inputs.values()))
        self.dt, self.time_scale, self.lag = float(dt), float(time_scale), float(lag)
        self.go_times, self.go_levels = timed_levels(go)
        self.cells = CELLS[preset]
        span = self.dt * self.time_scale  # model units per control period
        self.substeps = int(np.ceil(span / max_step - 1e-9))
        self.h = span / self.substeps
        # channel k sees the GO signal lag_k units late: a whole number of internal steps
        self.lag_steps = np.round(np.arange(self.n) * self.lag / self.h).astype(int)
        n = self.n
        #: the mirror spreading the first leg's genes over both (``symmetric``; set by the episode's wiring)
        self.bilateral = None
        self.symmetric = bool(o.symmetric)
        units = n // 2 if self.symmetric else n  # channels with genes of their own
        self._layout = GenomeLayout(
            (
                GeneBlock(name="self_inhibition", size=units, **SELF),
                GeneBlock(name="coupling", size=units * (n - 1), **COUPLING),
                GeneBlock(name="gain", size=units, **GAIN),
                GeneBlock(name="offset", size=units, **(ANGLE_OFFSET if o.output == "angle" else OFFSET)),
            )
            + ((GeneBlock(name="sense_gain", size=units * self.n_inputs, **SENSE_GAIN),) if self.feedback == "senses"
               else ())
        )
        self.reflex = bool(o.reflex)
        if self.reflex:
            if self.feedback != "senses" or self.output_kind != "angle":
                raise ConfigError("g3: reflex needs feedback = \"senses\" and output = \"angle\"")
            self._layout = GenomeLayout(self._layout.blocks + (
                GeneBlock(name="reflex_gain", size=units * self.n_inputs, **REFLEX_GAIN),))

    @property
    def layout(self) -> GenomeLayout:
        return self._layout

    def decode(self, genomes: np.ndarray) -> dict[str, np.ndarray]:
        p = super().decode(genomes)
        P, n = p["gain"].shape[0], self.n
        if not self.symmetric:
            D = np.zeros((P, n, n))
            off = ~np.eye(n, dtype=bool)
            D[:, off] = p["coupling"]
            D[:, np.arange(n), np.arange(n)] = p["self_inhibition"]
            out = {"D": D, "gain": p["gain"], "offset": p["offset"]}
            if self.feedback == "senses":
                out["K"] = p["sense_gain"].reshape(P, n, self.n_inputs)
            if self.reflex:
                out["R"] = p["reflex_gain"].reshape(P, n, self.n_inputs)
            return out
        sym = self.bilateral
        if sym is None:
            raise ConfigError("g3: symmetric needs the body's mirror (build it through an episode)")
        half = n // 2
        rows = np.zeros((P, half, n))  # what reaches each first-leg channel from every channel
        off = np.ones((half, n), bool)
        off[np.arange(half), sym.first] = False
        rows[:, off] = p["coupling"]
        rows[:, np.arange(half), sym.first] = p["self_inhibition"]
        out = {"D": sym.couplings(rows), "gain": sym.units(p["gain"]), "offset": sym.units(p["offset"])}
        if self.feedback == "senses":
            out["K"] = sym.gains(p["sense_gain"].reshape(P, half, self.n_inputs))
        if self.reflex:
            out["R"] = sym.gains(p["reflex_gain"].reshape(P, half, self.n_inputs))
        return out

    def initial_state(self, params: dict[str, np.ndarray]) -> dict:
        """x, y ``(P, N)`` zero (the paper's resting start) and the internal step count k."""
        P = params["gain"].shape[0]
        state = {"x": np.zeros((P, self.n)), "y": np.zeros((P, self.n)), "k": 0}
        if self.frame is not None:  # the rows whose second leg stood at the last tick (reframe)
            state["flip"] = np.zeros(P, bool)
        return state

    def reframe(self, state, flip):
        """Each leg's channels stay on its leg: where the stance leg changed, the legs' channels swap places."""
        return self.frame.follow(state, flip, {"x": 1, "y": 1})

    def go_at(self, k: np.ndarray) -> np.ndarray:
        """GO level at internal steps ``k`` (any shape): the schedule's level at t = k h / time_scale s."""
        return level_at(self.go_times, self.go_levels, np.asarray(k) * self.h / self.time_scale)

    def outputs_of(self, params: dict[str, np.ndarray], x: np.ndarray) -> np.ndarray:
        """o = clip(offset + gain x, 0, 1), or offset + gain x (rad) with an ``angle`` output, ``(P, N)``."""
        o = params["offset"] + params["gain"] * x
        return o if self.output_kind == "angle" else np.clip(o, 0.0, 1.0)

    def step(self, params, state, inputs):
        x, y, k = state["x"], state["y"], state["k"]
        out = self.outputs_of(params, x)
        if self.reflex:
            out = out + self.options.reflex_scale * np.einsum("pnk,pk->pn", params["R"], inputs)
        feed = np.einsum("pnk,pk->pn", params["K"], inputs) if self.feedback == "senses" else None
        for s in range(self.substeps):
            I = self.go_at(k + s - self.lag_steps)[None, :]  # (1, N); 0 before it arrives
            if feed is not None:  # an excitatory input: not below 0
                I = np.maximum(I + feed, 0.0)
            x, y = rk4_step(self.cells, x, y, I, params["D"], self.h)
        return {**state, "x": x, "y": y, "k": k + self.substeps}, out

    def neuron_outputs(self, params, state):
        """x (the motor channels) then y, ``(P, 2N)``."""
        return np.concatenate([state["x"], state["y"]], axis=1)
