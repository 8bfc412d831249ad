"""An open-loop phase oscillator: joint targets as a function of time alone (no sensors).

Reil & Husbands' CTRNNs have no sensory input, so their walkers are open-loop
rhythms that the body's own dynamics must stabilise.  This controller searches
such rhythms directly (``scripts/open_loop_probe.py``); a genome it finds is
an ordinary genome of the ``open-loop`` controller and replays with
``evobiped replay``.  With t the time since the episode started (s) and
w = 2 pi f t, the ``form`` option picks one of two families:

* ``sine`` (9 genes, a body with two legs of hip pitch, hip roll and knee):
  each joint's target (rad) a sinusoid at the common frequency f, the right
  leg half a period behind the left:
  hip pitch ``hip_offset + hip_amplitude sin(w + s)``,
  knee ``min(0, knee_offset + knee_amplitude sin(w + s + knee_phase))``,
  hip roll ``roll_offset + roll_amplitude sin(w + s + roll_phase)``,
  s = 0 for the left leg and pi for the right.  Outputs are angles, clipped
  to the joint ranges by the episode.
* ``fourier`` (1 + 5 n genes, any body of n actuators, no symmetry imposed):
  each actuator's own offset and first two harmonics, in half-ranges from
  the middle of its range, u = offset + sin1 sin(w) + cos1 cos(w) + sin2
  sin(2w) + cos2 cos(2w); the unit output clip((1 + u) / 2, 0, 1) spans the
  actuator's range (mid + half u, clipped to it).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from ..interface.contract import Actuator, Needs, index
from ..interface.genome import GeneBlock, GenomeLayout
from ..core.options import option
from .base import Controller, ControllerOptions

#: the sine form's genes: name -> (low, high); units Hz, rad, rad, rad, rad, rad (phase), rad, rad, rad (phase)
SINE_RANGES = {
    "frequency": (0.3, 2.5),
    "hip_amplitude": (0.0, 0.8),
    "hip_offset": (-0.3, 0.5),
    "knee_amplitude": (0.0, 0.8),
    "knee_offset": (-0.8, 0.0),
    "knee_phase": (-np.pi, np.pi),
    "roll_amplitude": (0.0, 0.4),
    "roll_offset": (-0.3, 0.3),
    "roll_phase": (-np.pi, np.pi),
}
#: the fourier form's common frequency range (Hz)
FOURIER_HZ = (0.3, 2.5)
#: the fourier form's coefficients per actuator, in half-ranges
FOURIER_TERMS = ("offset", "sin1", "cos1", "sin2", "cos2")
#: the joints of each leg the sine form drives, found by role in the body's actuators
JOINTS = ("hip_pitch", "hip_roll", "knee")
#: form -> output kind (see evobiped.interface.mapping)
FORMS = {"sine": "angle", "fourier": "unit"}


def _block(name: str, size: int, low: float, high: float, init_mean: float, init_sigma: float) -> GeneBlock:
    return GeneBlock(name=name, size=size, low=low, high=high, init_mean=init_mean, init_sigma=init_sigma,
                     mutation_sigma=(high - low) / 10)


@dataclass(frozen=True, kw_only=True)
class OpenLoopOptions(ControllerOptions):
    """Options of the open-loop controller."""

    form: str = option("sine", "`sine`: 9 genes, legs in antiphase (two legs of hip pitch, hip roll, knee); "
                       "`fourier`: an offset and two harmonics per actuator (any body)", choices=tuple(FORMS))
    dt: float = option(0.02, "control period", unit="s", above=0)


class OpenLoop(Controller):
    """Targets as a function of time only; see the module docstring."""

    name: ClassVar[str] = "open-loop"
    docs_note: ClassVar[str] = ("Joint targets as a function of time alone, no sensors (what "
                                "`scripts/open_loop_probe.py` searches;\nevobiped/controllers/open_loop.py gives the "
                                "two forms' formulas).")
    output_kind: ClassVar[str] = "angle"
    Options: ClassVar[type] = OpenLoopOptions

    @classmethod
    def needs(cls, options: OpenLoopOptions) -> Needs:
        """No sensors; the sine form needs two legs of hip pitch, hip roll and knee."""
        return Needs(deaf=True, joints=JOINTS if options.form == "sine" else None)

    def __init__(self, options: OpenLoopOptions | None = None, *, n_outputs: int, inputs: dict[str, int] | None = None,
                 actuators: tuple[Actuator, ...] = (), **given):
        self.options = self.own_options(options, given)
        self.form, self.dt, self.input_names = self.options.form, float(self.options.dt), ()
        self.n_outputs = n = int(n_outputs)
        self.output_kind = FORMS[self.form]
        if self.form == "sine":
            # actuator columns per joint, (left, right)
            self._cols = {j: [index(actuators, leg, j) for leg in ("left", "right")] for j in JOINTS}
            blocks = tuple(_block(k, 1, lo, hi, 0.5 * (lo + hi), (hi - lo) / 4) for k, (lo, hi) in SINE_RANGES.items())
        else:
            lo, hi = FOURIER_HZ
            blocks = (_block("frequency", 1, lo, hi, 0.5 * (lo + hi), (hi - lo) / 4),
                      *(_block(k, n, -1.0, 1.0, 0.0, 0.2) for k in FOURIER_TERMS))
        self._layout = GenomeLayout(blocks)

    @property
    def layout(self) -> GenomeLayout:
        return self._layout

    def initial_state(self, params):
        """The time since the start (s), ``(P,)``."""
        return np.zeros(len(params["frequency"]))

    def neuron_outputs(self, params, state):
        """The targets at time ``state`` ``(P, n_outputs)``: angles (rad, sine form) or unit outputs (fourier form)."""
        w = 2 * np.pi * params["frequency"][:, 0] * state  # (P,) rad
        if self.form == "fourier":
            g, w = params, w[:, None]
            u = g["offset"] + g["sin1"] * np.sin(w) + g["cos1"] * np.cos(w) + g["sin2"] * np.sin(2 * w) + g[
                "cos2"] * np.cos(2 * w)
            return np.clip(0.5 + 0.5 * u, 0.0, 1.0)
        g = {k: v[:, 0] for k, v in params.items()}
        out = np.empty((len(state), self.n_outputs))
        for leg, s in enumerate((0.0, np.pi)):
            out[:, self._cols["hip_pitch"][leg]] = g["hip_offset"] + g["hip_amplitude"] * np.sin(w + s)
            out[:, self._cols["knee"][leg]] = np.minimum(0.0, g["knee_offset"]
                                                         + g["knee_amplitude"] * np.sin(w + s + g["knee_phase"]))
            out[:,
                self._cols["hip_roll"][leg]] = g["roll_offset"] + g["roll_amplitude"] * np.sin(w + s + g["roll_phase"])
        return out

    def step(self, params, state, inputs):
        return state + self.dt, self.neuron_outputs(params, state)
