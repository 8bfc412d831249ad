"""A SIMBICON-style balance controller (beyond the papers), for 6-DOF bipeds with point feet.

Yin, Loken & van de Panne 2007, "SIMBICON: simple biped locomotion control",
adapted to the Reil body (2-DOF hips, knees, sphere feet, no torso, PD target
actuators).  Reil & Husbands' CTRNN has no senses, so its walkers must be
stabilised by the body alone; this controller shows what feedback does on the
same body.  It is a finite-state machine with two states per step:

* **Phase.**  One leg stands, the other swings.  The swing starts "early" for
  ``step_time`` s, then stays "late" until its foot touches the ground (or
  3 ``step_time`` passes); then the legs swap roles.  The left leg stands first.
* **Swing hip, in the world frame** (rad, the leg's angle from the vertical):
  forward  ``hip_early | hip_late + cd d_fwd + cv v_fwd``,
  outward  ``roll_offset + cd_lateral d_out + cv_lateral v_out``,
  where d is the centre of mass minus the stance foot (m) and v the
  centre-of-mass velocity (m/s), forward and toward the swing side: the foot
  is placed where the body is going (SIMBICON's balance feedback).  The pelvis
  tilt is added so that these are world angles, whatever the pelvis does.
* **Knees**: swing ``knee_early | knee_late``, stance ``stance_knee`` (rad).
* **Stance hip** keeps the pelvis level:
  target = current angle + ``pelvis_gain`` tilt + ``pelvis_damping`` tilt rate
  (signed so as to turn the pelvis back), in pitch and in roll.

Hearing (beyond SIMBICON, for the steering task).  When the task offers the
sound signal s (``sound``, + for a source on the left; see
:mod:`evobiped.tasks.steer`), two more genes bias the swing targets by s:
``sound_forward`` lengthens the right leg's steps and shortens the left's
(``- side sound_forward s`` on the forward swing target, side = +1 for the
left leg), which turns a walker without hip yaw towards the left for s > 0
when the gene is positive; ``sound_lateral`` moves every swing foot sideways
(``+ sound_lateral s`` to the left).  Both start at 0 (deaf) and evolve
like the rest; evolution picks their signs.  s grows towards +-1 as the
walker nears the source (at 10 m |s| <= 0.05, at 0.5 m up to 0.8), and so do
these biases: the option ``sound_limit`` clips the s they act on to
+-sound_limit (default 1: unclipped), which keeps the direction heard and cuts
off the growth that fells a walker on arrival (docs/steering.md).

Outputs are joint target angles (rad) in the body's actuator order, clipped to
the body's ranges.  Genome: the 13 numbers above (15 with hearing), each its
own gene block (bounds, initial Gaussian, mutation sigma in :data:`GENES` and
:data:`SOUND_GENES`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from ..interface.contract import Actuator, Needs, index
from ..core.errors import ConfigError
from ..interface.genome import GeneBlock, GenomeLayout
from ..core.options import option
from .base import Controller, ControllerOptions

#: body sensors read by name, with the widths their meaning fixes: joint angles in action order (one per
#: actuator, however many the body has), foot contacts (left, right), pelvis pitch and roll and their rates,
#: the centre of mass from each foot (forward, left) and its velocity (forward, left)
SENSORS = {
    "joint_angles": None,
    "foot_contact": 2,
    "pelvis_tilt": 2,
    "pelvis_tilt_rate": 2,
    "com_from_feet": 4,
    "com_velocity": 2,
}
#: name: (low, high); the initial Gaussian is centred with sigma = range / 4, mutation sigma = range / 10
RANGES = {
    "step_time": (0.15, 0.5),  # s
    "hip_early": (0.0, 1.0),  # rad, forward
    "hip_late": (-0.5, 0.4),
    "knee_early": (-1.4, -0.3),
    "knee_late": (-0.6, 0.0),
    "stance_knee": (-0.4, 0.0),
    "cd": (-1.0, 2.0),  # rad/m
    "cv": (-1.0, 2.0),  # rad/(m/s)
    "roll_offset": (-0.3, 0.3),  # rad, outward
    "cd_lateral": (-1.0, 2.0),
    "cv_lateral": (-1.0, 2.0),
    "pelvis_gain": (0.0, 1.2),  # rad/rad
    "pelvis_damping": (0.0, 0.16),  # rad/(rad/s)
}
GENES = tuple(
    GeneBlock(name=k, size=1, low=lo, high=hi, init_mean=0.5 * (lo + hi), init_sigma=(hi - lo) / 4,
              mutation_sigma=(hi - lo) / 10)
    for k, (lo, hi) in RANGES.items()
)
#: hearing (when the task offers the ``sound`` sensor s in [-1, 1], + source on the left):
#: name: (low, high), initial mean 0 (deaf), sigma = range / 4, mutation sigma = range / 10
SOUND_RANGES = {
    # rad per unit s, added to the right swing hip's forward target, taken from the left's
    "sound_forward": (-0.4, 0.4),
    "sound_lateral": (-0.3, 0.3),  # rad per unit s, moves each swing foot to the left (+) or right (-)
}
SOUND_GENES = tuple(
    GeneBlock(name=k, size=1, low=lo, high=hi, init_mean=0.0, init_sigma=(hi - lo) / 4, mutation_sigma=(hi - lo) / 10)
    for k, (lo, hi) in SOUND_RANGES.items()
)
#: the joints of each leg, found by role in the body's actuators
JOINTS = ("hip_pitch", "hip_roll", "knee")


@dataclass(frozen=True, kw_only=True)
class SimbiconOptions(ControllerOptions):
    """Options of the simbicon controller."""

    dt: float = option(0.02, "control period", unit="s", above=0)
    sound_limit: float = option(1.0, "the hearing genes act on the ear signal s clipped to +-sound_limit (1: as "
                                "heard, s is in [-1, 1]); near a source |s| grows towards 1", above=0, high=1)


class Simbicon(Controller):
    """Two-state-per-step balance controller; see the module docstring."""

    name: ClassVar[str] = "simbicon"
    output_kind: ClassVar[str] = "angle"
    Options: ClassVar[type] = SimbiconOptions

    @classmethod
    def needs(cls, options: SimbiconOptions) -> Needs:
        """Two legs of hip pitch, hip roll and knee; the balance sensors; the task's (``sound``: hearing)."""
        return Needs(sensors=SENSORS, task_sensors=True, joints=JOINTS)

    def __init__(self, options: SimbiconOptions | None = None, *, n_outputs: int, inputs: dict[str, int] | None = None,
                 actuators: tuple[Actuator, ...] = (), **given):
        self.options = self.own_options(options, given)
        inputs = dict(inputs or {})
        self.n_outputs = len(actuators)
        self.dt = float(self.options.dt)
        self.sound_limit = float(self.options.sound_limit)
        # actuator columns per leg (left = 0, right = 1)
        self._pitch, self._roll, self._knee = (np.array([index(actuators, leg, j) for leg in ("left", "right")])
                                               for j in JOINTS)
        self.input_names = tuple(inputs)
        start = np.cumsum([0, *inputs.values()])
        self._at = {k: slice(start[i], start[i + 1]) for i, k in enumerate(inputs)}
        if "sound" in inputs and inputs["sound"] != 1:
            raise ConfigError(f"simbicon: the sound input is one signal s, got width {inputs['sound']}")
        self.hears = "sound" in inputs
        self._layout = GenomeLayout(GENES + SOUND_GENES if self.hears else GENES)

    @property
    def layout(self) -> GenomeLayout:
        return self._layout

    def initial_state(self, params):
        P = len(params["step_time"])
        # stance leg (0 left, 1 right), time in the swing (s), last targets (rad)
        return {"stance": np.zeros(P, int), "t": np.zeros(P), "out": np.zeros((P, self.n_outputs))}

    def neuron_outputs(self, params, state):
        """The 6 targets (rad), then the stance leg (0 left, 1 right) and the time in the swing (s)."""
        return np.column_stack([state["out"], state["stance"], state["t"]])

    def step(self, params, state, inputs):
        g = {k: v[:, 0] for k, v in params.items()}
        x = {k: inputs[:, s] for k, s in self._at.items()}
        P = len(inputs)
        rows = np.arange(P)
        t = state["t"] + self.dt
        stance = state["stance"]
        swing = 1 - stance
        landed = x["foot_contact"][rows, swing] > 0
        switch = ((t > g["step_time"]) & landed) | (t > 3 * g["step_time"])
        stance = np.where(switch, swing, stance)
        t = np.where(switch, 0.0, t)
        swing = 1 - stance
        early = t < g["step_time"]
        out_sw = np.where(swing == 0, 1.0, -1.0)  # + left: the swing side, outward
        pitch, roll = x["pelvis_tilt"].T
        pitch_rate, roll_rate = x["pelvis_tilt_rate"].T
        d = x["com_from_feet"].reshape(P, 2, 2)[rows, stance]  # (P, 2): forward, left
        v = x["com_velocity"]
        q = x["joint_angles"]

        fwd = np.where(early, g["hip_early"], g["hip_late"]) + g["cd"] * d[:, 0] + g["cv"] * v[:, 0]
        out = g["roll_offset"] + out_sw * (g["cd_lateral"] * d[:, 1] + g["cv_lateral"] * v[:, 1])
        if self.hears:  # longer right steps and shorter left ones for a source on the left, feet set towards it
            sound = x["sound"][:, 0]
            if self.sound_limit < 1.0:  # the direction heard, its growth near the source cut off
                sound = np.clip(sound, -self.sound_limit, self.sound_limit)
            fwd = fwd - out_sw * g["sound_forward"] * sound
            out = out + out_sw * g["sound_lateral"] * sound
        target = np.empty((P, self.n_outputs))
        PITCH, ROLL, KNEE = self._pitch, self._roll, self._knee
        # a nose-down pelvis swings the legs back, a left-up pelvis swings them left
        target[rows, PITCH[swing]] = fwd + pitch
        target[rows, ROLL[swing]] = out - out_sw * roll
        target[rows, KNEE[swing]] = np.where(early, g["knee_early"], g["knee_late"])
        target[rows, KNEE[stance]] = g["stance_knee"]
        turn_pitch = g["pelvis_gain"] * pitch + g["pelvis_damping"] * pitch_rate
        turn_roll = g["pelvis_gain"] * roll + g["pelvis_damping"] * roll_rate
        target[rows, PITCH[stance]] = q[rows, PITCH[stance]] - turn_pitch
        target[rows, ROLL[stance]] = q[rows, ROLL[stance]] - out_sw * turn_roll
        return {"stance": stance, "t": t, "out": target}, target
