"""A small open-loop controller, written as a new controller is: this one file, plus one registration line.

Each actuator i follows o_i(t) = 1/2 + 1/2 a_i sin(2 pi f_i t + phi_i), a unit output (a PD target across
the joint's range, or a torque across the body's bounds), with t the time since the episode started (s).
Genome: the amplitudes a (n), the frequencies f (n, Hz), the phases phi (n, rad), n = the body's actuators.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from evobiped.interface.contract import Needs
from evobiped.controllers.base import Controller, ControllerOptions
from evobiped.interface.genome import GeneBlock, GenomeLayout
from evobiped.core.options import option


@dataclass(frozen=True, kw_only=True)
class SineOptions(ControllerOptions):
    """Options of the sine controller."""

    dt: float = option(0.02, "control period", unit="s", above=0)


class Sine(Controller):
    """An open-loop sine per actuator; any body, no sensors."""

    name: ClassVar[str] = "sine"
    output_kind: ClassVar[str] = "unit"
    Options: ClassVar[type] = SineOptions

    @classmethod
    def needs(cls, options: SineOptions) -> Needs:
        return Needs()

    def __init__(self, options: SineOptions | None = None, *, n_outputs: int, inputs: dict[str, int] | None = None,
                 actuators=None, **given):
        self.options = self.own_options(options, given)
        self.n_outputs, self.dt, self.input_names = int(n_outputs), float(self.options.dt), ()
        n = self.n_outputs
        self._layout = GenomeLayout((
            GeneBlock(name="amplitude", size=n, low=0.0, high=1.0, init_mean=0.3, init_sigma=0.2, mutation_sigma=0.1),
            GeneBlock(name="frequency", size=n, low=0.2, high=3.0, init_mean=1.0, init_sigma=0.5, mutation_sigma=0.2),
            GeneBlock(name="phase", size=n, low=0.0, high=2 * np.pi, init_mean=np.pi, init_sigma=1.0,
                      mutation_sigma=0.5),
        ))

    @property
    def layout(self) -> GenomeLayout:
        return self._layout

    def initial_state(self, params):
        """The time since the start (s), ``(P,)``."""
        return np.zeros(len(params["amplitude"]))

    def neuron_outputs(self, params, state):
        return 0.5 + 0.5 * params["amplitude"] * np.sin(2 * np.pi * params["frequency"] * state[:, None]
                                                        + params["phase"])

    def step(self, params, state, inputs):
        return state + self.dt, self.neuron_outputs(params, state)
