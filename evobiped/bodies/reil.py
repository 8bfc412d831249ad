"""The 3D 6-DOF biped of Reil & Husbands 2002 (``models/reil_biped.xml``).

PD gains.  The paper gives k_s = 5, k_d = 4 in MathEngine's units without
saying what they are.  Read as SI (N m/rad, N m s/rad) on this 3.4 kg body they
cannot do what the paper says the PD does ("largely eliminates the need to
physically limit joint angles"): the stance knee carries ~2.8 kg at a lever of
up to ~0.3 m (~8 N m), so k_s = 5 N m/rad would sag by more than a radian, and
a swinging leg (I ~ 0.4 kg m^2 about the hip) would have a natural period of
~2.8 s, far slower than a step.  We therefore choose
k_s = 50 N m/rad (static sag under the stance load ~0.1-0.15 rad; swing-leg
natural frequency ~1.8 Hz, the range of a walking step) and
k_d = 2 N m s/rad (damping ratio ~0.2 for the whole leg about the hip and ~0.6
for the shank about the knee: under-damped but without ringing).
Both are config values (``kp``, ``kv``).

Rotational inertia (``inertia``).  ``"geoms"`` (default): MuJoCo computes each
link's inertia from its capsule and sphere with Table I's mass (the thigh
about its centre 0.016 kg m^2).  ``"karma"``: a reading of how the paper's
body may have been built.  MathEngine's Karma gives a new body mass 1 and the
inertia of a unit sphere, 0.4 kg m^2 on each axis, and ``MdtBodySetMass``
changes the mass only; the paper gives masses and nothing else.  If the
inertia tensors were never set, each of the 13 MathEngine bodies (Sect.
II-A1) kept 0.4 kg m^2: the pelvis link 0.4, and each leg link, a composite
of two spheres and a link, 1.2 about its centre of mass (the parallel-axis
terms of its parts are below 0.03 and unknown, so left out): about 80 times
the inertia its mass and length alone imply.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar, Collection

import mujoco
import numpy as np

from ..interface.contract import Actuator, Environment
from ..core.errors import UserError
from ..physics.sim import Sims
from ..core.options import option
from ..physics import gait
from ..physics.gait_lab import FootSample
from .base import Body, joint_senses, links_com_velocity, model_file_option

#: Table II target-angle ranges (rad), and the actuator order = motor neurons 1-6
ACTUATORS = (
    "left_hip_pitch",
    "left_hip_roll",
    "left_knee",
    "right_hip_pitch",
    "right_hip_roll",
    "right_knee",
)
#: kg m^2 about each axis through the link's centre of mass, under inertia = "karma"
KARMA_INERTIA = {"pelvis": 0.4, "thigh": 1.2, "shank": 1.2}
TABLE_II = {
    "knee": (-1.4, 0.0),
    "hip_roll": (-0.8, 0.8),
    "hip_pitch": (-1.3, 1.6),
}


def _range_of(actuator: str) -> tuple[float, float]:
    return TABLE_II[actuator.split("_", 1)[1]]


# the heading frame's rows from the forward axis (f_x, f_y): forward (f_x, f_y), left (-f_y, f_x)
_FRAME_COLUMNS, _FRAME_SIGNS = np.array([0, 1, 1, 0]), np.array([1.0, 1.0, -1.0, 1.0])
#: pitch = -asin(R_20) (+ nose down), roll = asin(R_21) (+ left side up)
_TILT_SIGNS = np.array([-1.0, 1.0])


@dataclass(frozen=True, kw_only=True)
class ReilOptions:
    """Options of the reil body."""

    timestep: float = option(0.005, "physics step (control step 0.02 s)", unit="s", low=1e-5, high=0.1)
    kp: float = option(50.0, "PD stiffness (the module docstring says why not the paper's 5)", unit="N m/rad", above=0)
    kv: float = option(2.0, "PD damping", unit="N m s/rad", low=0)
    fall_height: float = option(0.5, "centre-of-mass height below which the walker has fallen", unit="m", above=0)
    fall_tilt: float = option(float(np.pi / 2), "pelvis tilt beyond which the walker has fallen (on its side, upside "
                                                "down)", unit="rad", above=0, high=float(np.pi))
    inertia: str = option("geoms", "link inertias: from the geoms, or MathEngine's default 0.4 kg m^2 per body "
                                   "(`karma`)", choices=("geoms", "karma"))
    model_file: str | None = model_file_option("reil_biped")


class ReilBiped(Body):
    """Reil & Husbands' walker: PD targets in Table II's ranges, sphere feet."""

    name: ClassVar[str] = "reil"
    model_name: ClassVar[str] = "reil_biped"
    action_kind: ClassVar[str] = "position"
    trunk: ClassVar[str] = "pelvis"
    floor_geom: ClassVar[str | None] = "floor"
    contact_sensor: ClassVar[tuple[str, tuple[str, ...]]] = ("foot_contact", ("left", "right"))
    actuators: ClassVar[tuple[Actuator, ...]] = tuple(Actuator(a, a.split("_", 1)[0], a.split("_", 1)[1])
                                                      for a in ACTUATORS)
    #: see :meth:`sensors`
    sensor_widths: ClassVar[dict[str, int]] = {
        "joint_angles": 6,
        "joint_velocities": 6,
        "foot_contact": 2,
        "pelvis_tilt": 2,
        "pelvis_tilt_rate": 2,
        "com_from_feet": 4,
        "com_velocity": 2,
        **gait.WIDTHS,
    }
    sensor_text: ClassVar[dict[str, str]] = {
        "joint_angles": "joint angles (rad) in action order: left hip pitch, left hip roll, left knee, right hip "
                        "pitch, right hip roll, right knee",
        "joint_velocities": "their rates (rad/s), same order",
        "foot_contact": "foot contacts: left, right (0 or 1)",
        "pelvis_tilt": "pelvis tilt: pitch (+ nose down), roll (+ left side up) (rad)",
        "pelvis_tilt_rate": "their rates (rad/s)",
        "com_from_feet": "centre of mass minus the left foot (forward, left), minus the right foot (forward, left) (m, "
                         "heading frame)",
        "com_velocity": "centre-of-mass velocity: forward, left (m/s, heading frame)",
        **gait.TEXT,
    }
    environment: ClassVar[Environment] = Environment(
        "Reil & Husbands' 3D biped", "PD target angles (rad) in Table II's ranges", 0.02, camera_azimuth=135.0)
    #: standing values (the reset pose: straight legs, feet under the hips 0.25 m either side of the centre of
    #: mass) and scales of about one standard deviation of each reading in a 50 s walk of a balance walker
    sensor_norms: ClassVar[dict[str, tuple[tuple[float, ...], tuple[float, ...]]]] = {
        "joint_angles": ((0.0,) * 6, (0.5,) * 6),
        "joint_velocities": ((0.0,) * 6, (4.0,) * 6),
        "foot_contact": ((0.5, 0.5), (0.5, 0.5)),
        "pelvis_tilt": ((0.0, 0.0), (0.2, 0.2)),
        "pelvis_tilt_rate": ((0.0, 0.0), (1.5, 1.5)),
        "com_from_feet": ((0.0, -0.25, 0.0, 0.25), (0.1, 0.1, 0.1, 0.1)),
        "com_velocity": ((0.0, 0.0), (0.5, 0.5)),
        **gait.NORMS,
    }

    #: left/right mirror: the legs' columns swap; the roll axes are mirrored in the model (+ = abduction on both
    #: sides), so joint readings keep their signs; sideways quantities (pelvis roll, lateral offsets and
    #: velocities) and the stance-leg flag change sign
    mirror: ClassVar[dict] = {
        "joint_angles": ((3, 4, 5, 0, 1, 2), (1,) * 6),
        "joint_velocities": ((3, 4, 5, 0, 1, 2), (1,) * 6),
        "foot_contact": ((1, 0), (1, 1)),
        "pelvis_tilt": ((0, 1), (1, -1)),
        "pelvis_tilt_rate": ((0, 1), (1, -1)),
        "com_from_feet": ((2, 3, 0, 1), (1, -1, 1, -1)),
        "com_velocity": ((0, 1), (1, -1)),
        **gait.MIRROR,
    }
    actuator_mirror: ClassVar[tuple] = ((3, 4, 5, 0, 1, 2), (1,) * 6)

    Options: ClassVar[type] = ReilOptions

    def __init__(self, options=None, **given):
        super().__init__(options, **given)
        o = self.options
        self.kp, self.kv, self.fall_height = float(o.kp), float(o.kv), float(o.fall_height)
        self.fall_tilt = float(o.fall_tilt)
        self.inertia = o.inertia

    def action_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        lo, hi = zip(*(_range_of(a) for a in ACTUATORS))
        return np.array(lo), np.array(hi)

    def bind_model(self, model: mujoco.MjModel) -> None:
        names = tuple(model.actuator(i).name for i in range(model.nu))
        if names != ACTUATORS:
            raise UserError(f"reil body: the model's actuators are {names}, expected {ACTUATORS}")
        for i in range(model.nu):  # eq. 1 with this body's gains
            model.actuator_gainprm[i, 0] = self.kp
            model.actuator_biasprm[i, 1] = -self.kp
            model.actuator_biasprm[i, 2] = -self.kv
        m = model
        if self.inertia == "karma":
            for b in range(1, m.nbody):
                part = m.body(b).name.split("_")[-1]
                if part not in KARMA_INERTIA:
                    raise UserError(f"reil body: inertia 'karma' knows the links {sorted(KARMA_INERTIA)}, not "
                                    f"{m.body(b).name!r}")
                m.body_inertia[b] = KARMA_INERTIA[part]
        self._pelvis = m.body("pelvis").id
        self._feet = np.array([m.site("left_foot").id, m.site("right_foot").id])
        self._mass_share = m.body_mass[1:] / m.body_mass[1:].sum()  # links 1.., all in the pelvis's tree
        self._qadr = np.array([m.joint(a).qposadr[0] for a in ACTUATORS])
        self._dadr = np.array([m.joint(a).dofadr[0] for a in ACTUATORS])
        self._foot_geoms = np.array([m.geom(f"{side}_foot").id for side in ("left", "right")])
        self._foot_bodies = m.geom_bodyid[self._foot_geoms]
        self._foot_radius = m.geom_size[self._foot_geoms, 0]
        self._knees = self._qadr[[2, 5]]
        self._touch = np.concatenate(
            [np.arange(m.sensor(s).adr[0], m.sensor(s).adr[0] + 1) for s in ("left_foot_touch", "right_foot_touch")]
        )

    def apply(self, sims: Sims, ids: np.ndarray, action: np.ndarray) -> None:
        sims.ctrl[ids] = action

    def com(self, sims: Sims) -> np.ndarray:
        return sims.subtree_com[:, self._pelvis]

    def planar_position(self, sims: Sims) -> np.ndarray:
        return sims.xpos[:, self._pelvis, :2]

    def heading(self, sims: Sims) -> np.ndarray:
        return sims.kept("heading", self._heading)

    def _heading(self, sims: Sims) -> np.ndarray:
        # the body x axis (forward) is column 0 of the pelvis rotation matrix
        fwd = sims.xmat[:, self._pelvis].reshape(-1, 3, 3)[:, :2, 0]
        return fwd / np.maximum(np.linalg.norm(fwd, axis=1, keepdims=True), 1e-12)

    def fallen(self, sims: Sims, ids: np.ndarray) -> np.ndarray:
        """Centre of mass below ``fall_height`` (m), or the pelvis's up axis tilted beyond
        ``fall_tilt`` (rad; default 90 degrees: on its side or upside down, e.g. a walker
        that cartwheels with its centre of mass still high)."""
        up = sims.xmat[ids, self._pelvis, 8]  # z component of the pelvis z axis
        return (sims.subtree_com[ids, self._pelvis, 2] < self.fall_height) | (up < np.cos(self.fall_tilt))

    def sensors(self, sims: Sims, names: Collection[str] | None = None) -> dict[str, np.ndarray]:
        """Joint angles and velocities (rad, rad/s; actuator order), foot contacts (0/1, left, right),
        and the vestibular and proprioceptive readings a balance controller needs, in the heading
        frame (forward = the pelvis x axis on the ground, left = 90 degrees anticlockwise):

        * ``pelvis_tilt`` ``(P, 2)``: pitch (rad, + nose down), roll (rad, + left side up);
        * ``pelvis_tilt_rate`` ``(P, 2)``: their rates (rad/s);
        * ``com_from_feet`` ``(P, 4)``: centre of mass minus left foot (forward, left), minus right foot (m);
        * ``com_velocity`` ``(P, 2)``: centre-of-mass velocity (forward, left) (m/s);
        * ``stance_leg``, ``since_touchdown`` ``(P, 1)``: the gait's structure (:mod:`evobiped.physics.gait`; left =
          +1).

        Only ``names`` are computed (default all), in the order above.
        """
        want = self.sensor_widths if names is None else names
        contact = self.contacts(sims)
        out = joint_senses(sims, self._qadr, self._dadr, contact, want)
        if "pelvis_tilt" in want:  # (-asin R_20, asin R_21) of the pelvis rotation (row-major)
            out["pelvis_tilt"] = np.arcsin(np.clip(sims.xmat[:, self._pelvis, 6:8], -1, 1)) * _TILT_SIGNS
        if "pelvis_tilt_rate" in want or "com_from_feet" in want or "com_velocity" in want:
            fwd = self.heading(sims)
            # (P, 2, 2): rows forward, left = (-f_y, f_x)
            frame = (fwd[:, _FRAME_COLUMNS] * _FRAME_SIGNS).reshape(-1, 2, 2)
            if "pelvis_tilt_rate" in want:  # pitch is a rotation about the left axis, roll about the forward axis
                out["pelvis_tilt_rate"] = np.einsum("pij,pj->pi", frame, sims.cvel[:, self._pelvis, :2])[:, ::-1]
            if "com_from_feet" in want:
                com = sims.subtree_com[:, self._pelvis, None, :2] - sims.site_xpos[:, self._feet, :2]  # (P, 2 feet, 2)
                out["com_from_feet"] = np.einsum("pij,pfj->pfi", frame, com).reshape(-1, 4)
            if "com_velocity" in want:
                out["com_velocity"] = np.einsum("pij,pj->pi", frame, self._com_velocity(sims)[:, :2])
        if "stance_leg" in want or "since_touchdown" in want or "stance_side" in want:
            out.update(gait.read(contact, sims, want))
        return out

    def _contacts(self, sims: Sims) -> np.ndarray:
        return sims.sensordata[:, self._touch] > 0

    def feet(self, sims: Sims) -> FootSample:
        """The foot spheres against the floor plane (z = 0): a foot touches where MuJoCo makes a contact, at a
        signed distance below the floor geom's margin (0); slip is the horizontal velocity of the sphere's material
        point at the ground, v + w x (-r z)."""
        centre = sims.geom_xpos[:, self._foot_geoms]  # (P, 2, 3)
        height = centre[..., 2] - self._foot_radius
        cvel = sims.cvel[:, self._foot_bodies]  # angular, then linear at the pelvis tree's centre of mass
        w = cvel[..., :3]
        r = centre - sims.subtree_com[:, self._pelvis, None]
        r[..., 2] -= self._foot_radius
        vx = cvel[..., 3] + w[..., 1] * r[..., 2] - w[..., 2] * r[..., 1]
        vy = cvel[..., 4] + w[..., 2] * r[..., 0] - w[..., 0] * r[..., 2]
        force = sims.actuator_force
        return FootSample(contact=height < 0.0, slip=np.hypot(vx, vy), height=height, knee=sims.qpos[:, self._knees],
                          power=force * sims.actuator_velocity, torque=force.copy())

    def gait_constants(self, model: mujoco.MjModel) -> tuple[float, float]:
        data = mujoco.MjData(model)
        mujoco.mj_forward(model, data)
        hip = data.xpos[model.body("left_thigh").id, 2]
        foot = data.geom_xpos[model.geom("left_foot").id, 2] - model.geom_size[model.geom("left_foot").id, 0]
        return float(model.body_mass.sum()), float(hip - foot)

    def _com_velocity(self, sims: Sims) -> np.ndarray:
        """``(P, 3)`` m/s: the links' mass-weighted velocity (:func:`~.base.links_com_velocity`; every link is in the
        pelvis's tree)."""
        return links_com_velocity(sims, self._pelvis, slice(1, None), self._mass_share)
