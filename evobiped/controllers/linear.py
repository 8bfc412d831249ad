"""A linear policy: joint targets = bias + W x over the normalised senses (beyond the papers).

    y = b + W^T x,       x = (reading - centre) / scale    (k inputs, n outputs)

With every gene at zero the targets are zero: the body's standing posture
(straight legs for the Reil body).  ``output = "angle"`` (default) sends y to a
position body as PD targets in rad, clipped to each joint's range;
``output = "signed"`` sends it as torques (N m, clipped) or, on a position
body, squashed into the range (:mod:`evobiped.interface.mapping`), so the policy drives
any body.

The inputs are always normalised: by the body's declared standing values and
scales, or by the running normaliser a run keeps (``input_norm``).  The
linear policy is the simplest controller that evolution strategies turn into a
walker from scratch in the mirrored stance frame (``frame = "stance"``; Mania,
Guy & Recht 2018 showed linear policies walk MuJoCo's humanoid).

Genome: n biases, then k * n weights, weight (i, j) from input i to output j at
gene n + i * n + j.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from ..interface.contract import Needs
from ..interface.genome import GeneBlock, GenomeLayout
from ..core.options import option
from .base import Controller, ControllerOptions

OUTPUT_KINDS = {"angle": "angle", "signed": "signed"}


@dataclass(frozen=True, kw_only=True)
class LinearOptions(ControllerOptions):
    """Options of the linear controller."""

    dt: float = option(0.02, "control period", unit="s", low=1e-4, high=1.0)
    output: str = option("angle", "`angle`: PD targets in rad (zero = standing); `signed`: torques in N m or squashed "
                                  "targets", choices=tuple(OUTPUT_KINDS))
    weight_range: float = option(10.0, "bound of every weight and bias gene, +-", above=0)
    init_sigma: float = option(0.0, "initial spread of the genes (0: every policy starts standing)", low=0)
    mutation_sigma: float = option(0.1, "the GA's mutation sigma of every gene", above=0)


class Linear(Controller):
    """``y = b + W^T x``: no state, every output from every (normalised) input."""

    name: ClassVar[str] = "linear"
    docs_note: ClassVar[str] = (
        "Joint targets = bias + W · normalised senses: every gene zero is the standing posture. The simplest policy "
        "that\nevolution strategies turn into a walker from scratch ([the route from scratch]"
        "(#the-route-from-scratch-evolution-strategies)).")
    output_kind: ClassVar[str] = "angle"
    normalises_inputs = True

    Options: ClassVar[type] = LinearOptions

    @classmethod
    def needs(cls, options: LinearOptions) -> Needs:
        """Any body; reads every sensor the body and task offer (or the ``inputs`` option's), normalised."""
        return Needs(all_sensors=True, normalised=True)

    def __init__(self, options: LinearOptions | None = None, *, n_outputs: int, inputs: dict[str, int] | None = None,
                 actuators=None, **given):
        o = self.options = self.own_options(options, given)
        self.output_kind = OUTPUT_KINDS[o.output]
        self.n_outputs = int(n_outputs)
        inputs = dict(inputs or {})
        self.input_names = tuple(inputs)
        self.n_inputs = int(sum(inputs.values()))
        self.dt = float(o.dt)
        r, s, m = float(o.weight_range), float(o.init_sigma), float(o.mutation_sigma)
        common = dict(low=-r, high=r, init_mean=0.0, init_sigma=s, mutation_sigma=m)
        self._layout = GenomeLayout((GeneBlock(name="biases", size=self.n_outputs, **common),
                                     GeneBlock(name="weights", size=self.n_inputs * self.n_outputs, **common)))

    @property
    def layout(self) -> GenomeLayout:
        return self._layout

    def decode(self, genomes: np.ndarray) -> dict[str, np.ndarray]:
        p = super().decode(genomes)
        P = p["biases"].shape[0]
        return {"b": p["biases"], "W": p["weights"].reshape(P, self.n_inputs, self.n_outputs)}

    def initial_state(self, params):
        return None

    def step(self, params, state, inputs):
        # per-row sums in a fixed order (row p never depends on P)
        return state, params["b"] + (inputs[:, :, None] * params["W"]).sum(axis=1)

    def neuron_outputs(self, params, state):
        return np.zeros((params["b"].shape[0], 0))
