"""A body made from an MJCF biped and its declaration (:mod:`.declaration`): ``--body mjcf:PATH``.

Everything a body offers is derived from the declaration and the compiled model, none of it written per robot:

* actuators in action order (the left leg's, then the right's, each in the declared joint roles), their kind
  (position servos: PD targets in rad; motors: torques in N m) and bounds (each actuator's ``ctrlrange``);
* senses (the Reil body's, the same names, units and frame): ``joint_angles``, ``joint_velocities`` (rad, rad/s),
  ``foot_contact`` (0/1: the foot's lowest point at or below the ground), ``pelvis_tilt`` (pitch + nose down, roll
  + left side up, rad) and ``pelvis_tilt_rate`` (rad/s), ``com_from_feet`` (centre of mass minus each foot, forward
  and left, m), ``com_velocity`` (forward, left, m/s), and the gait's ``stance_leg``, ``since_touchdown``; their
  standing values from the initial pose and scales of the Reil body's kind (0.5 rad, 4 rad/s, 0.2 rad, 1.5 rad/s,
  0.1 m, 0.5 m/s);
* the left/right mirror (legs swap, each role's ``mirror_signs``; sideways readings change sign);
* the fall test (centre of mass below ``fall_height``, or the pelvis's up axis tilted beyond ``fall_tilt``);
* the gait lab's feet (lowest point of each foot geom, its slip at the ground), knee angles, mass and leg length
  (the first hip's height above the lowest foot point in the initial pose).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import Collection

import mujoco
import numpy as np

from ..core.options import option
from ..interface.contract import Actuator
from ..physics import gait
from ..physics.gait_lab import FootSample
from ..physics.models import load_model
from ..physics.sim import Sims
from .base import Body, joint_senses, links_com_velocity
from .declaration import AXES, GEOMS, LEGS, Declaration, check_model, read_declaration, refuse_declaration

#: the declared body's scales (one standard deviation of a walk's readings, of the Reil body's kind)
SCALES = {"joint_angles": 0.5, "joint_velocities": 4.0, "pelvis_tilt": 0.2, "pelvis_tilt_rate": 1.5,
          "com_from_feet": 0.1, "com_velocity": 0.5}

def _axis(name: str) -> np.ndarray:
    i, s = AXES[name]
    v = np.zeros(3)
    v[i] = s
    return v


def _lowest(kind: str, size: np.ndarray, centre: np.ndarray, rot: np.ndarray) -> np.ndarray:
    """The lowest point ``(P, 3)`` (world frame) of a geom of this ``kind`` and MuJoCo ``size`` ``(3,)`` from its
    centres ``(P, 3)`` and rotations ``(P, 3, 3)``."""
    down = -rot[:, 2, :]  # world -z in the geom's frame, (P, 3): the rows of R are its axes' world components
    if kind == "sphere":
        local = np.zeros_like(down)
    elif kind == "box":
        local = np.where(down >= 0, 1.0, -1.0) * size[:3]
    else:  # capsule, cylinder: along the local z axis; the capsule adds its sphere, the cylinder its rim
        local = np.zeros_like(down)
        local[:, 2] = np.where(down[:, 2] >= 0, 1.0, -1.0) * size[1]
        if kind == "cylinder":
            rim = down.copy()
            rim[:, 2] = 0.0
            local += size[0] * rim / np.maximum(np.linalg.norm(rim, axis=1, keepdims=True), 1e-12)
    point = centre + np.einsum("pij,pj->pi", rot, local)
    if kind in ("sphere", "capsule"):
        point[:, 2] -= size[0]
    return point


@lru_cache(maxsize=None)
def _declared(spec: str, stamp: tuple) -> type[Body]:
    d = read_declaration(spec)
    model = load_model(str(d.model))
    kind, problems = check_model(d, model)
    refuse_declaration(d.path, problems)
    return _make_class(spec, d, model, kind)


def declared_body(spec: str) -> type[Body]:
    """The body class of ``mjcf:spec`` (made once per process and files' modification times)."""
    from .declaration import locate

    decl, xml = locate(spec)
    stamp = tuple(p.stat().st_mtime_ns for p in (decl, xml) if p is not None and p.exists())
    return _declared(spec, stamp)


def _make_class(spec: str, d: Declaration, model: mujoco.MjModel, kind: str) -> type[Body]:
    names = tuple(a for side in LEGS for a in d.legs[side][0])
    actuators = tuple(Actuator(a, side, role) for side in LEGS for a, role in zip(d.legs[side][0], d.joints))
    ids = [model.actuator(a).id for a in names]
    low, high = model.actuator_ctrlrange[ids, 0].copy(), model.actuator_ctrlrange[ids, 1].copy()
    n = len(d.joints)
    swap = tuple(list(range(n, 2 * n)) + list(range(n)))
    signs = tuple(d.mirror_signs) * 2
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    jnt = [model.actuator_trnid[i, 0] for i in ids]
    q0 = tuple(float(data.qpos[model.jnt_qposadr[j]]) for j in jnt)
    body = _instance_less(d, model, kind)
    standing = body.standing(model, data)
    widths = {"joint_angles": 2 * n, "joint_velocities": 2 * n, "foot_contact": 2, "pelvis_tilt": 2,
              "pelvis_tilt_rate": 2, "com_from_feet": 4, "com_velocity": 2, **gait.WIDTHS}
    norms = {"joint_angles": (q0, (SCALES["joint_angles"],) * 2 * n),
             "joint_velocities": ((0.0,) * 2 * n, (SCALES["joint_velocities"],) * 2 * n),
             "foot_contact": ((0.5, 0.5), (0.5, 0.5)), "pelvis_tilt": ((0.0, 0.0), (0.2, 0.2)),
             "pelvis_tilt_rate": ((0.0, 0.0), (1.5, 1.5)),
             "com_from_feet": (tuple(standing), (SCALES["com_from_feet"],) * 4),
             "com_velocity": ((0.0, 0.0), (0.5, 0.5)), **gait.NORMS}
    mirror = {"joint_angles": (swap, signs), "joint_velocities": (swap, signs), "foot_contact": ((1, 0), (1, 1)),
              "pelvis_tilt": ((0, 1), (1, -1)), "pelvis_tilt_rate": ((0, 1), (1, -1)),
              "com_from_feet": ((2, 3, 0, 1), (1, -1, 1, -1)), "com_velocity": ((0, 1), (1, -1)), **gait.MIRROR}
    fall_height = d.fall_height if d.fall_height is not None else 0.55 * float(data.subtree_com[model.body(
        d.pelvis).id, 2])
    order = ", ".join(f"{a.leg} {a.joint}" for a in actuators)
    text = {"joint_angles": f"joint angles (rad) in action order: {order}",
            "joint_velocities": "their rates (rad/s), same order",
            "foot_contact": "foot contacts: left, right (0 or 1; the foot's lowest point at or below the floor)",
            "pelvis_tilt": "pelvis tilt: pitch (+ nose down), roll (+ left side up) (rad)",
            "pelvis_tilt_rate": "their rates (rad/s)",
            "com_from_feet": "centre of mass minus the left foot (forward, left), minus the right foot (m, heading "
                             "frame)",
            "com_velocity": "centre-of-mass velocity: forward, left (m/s, heading frame)", **gait.TEXT}
    attrs = dict(name=f"mjcf:{spec}", sensor_text=text, model_name=d.model.stem, action_kind=kind, trunk=d.pelvis,
                 floor_geom=d.floor,
                 contact_sensor=("foot_contact", LEGS), actuators=actuators, sensor_widths=widths, sensor_norms=norms,
                 mirror=mirror, actuator_mirror=(swap, signs), Options=DeclaredOptions, declaration=d,
                 fall_default=fall_height, timestep_default=float(model.opt.timestep),
                 bounds=(low, high), __doc__=f"The biped declared by {d.path} (model {d.model.name}).")
    return type("DeclaredBiped", (DeclaredBiped,), attrs)


def _instance_less(d: Declaration, model: mujoco.MjModel, kind: str) -> "DeclaredBiped":
    """A bare object of the declared class's methods bound to ``model`` (for what the class needs from its pose)."""
    obj = DeclaredBiped.__new__(DeclaredBiped)
    obj.declaration = d
    obj.bind_model(model)
    return obj


@dataclass(frozen=True, kw_only=True)
class DeclaredOptions:
    """Options of a declared body."""

    timestep: float | None = option(None, "physics step (none: the model's)", unit="s", low=1e-5, high=0.1)
    fall_height: float | None = option(None, "centre-of-mass height below which the walker has fallen (none: the "
                                       "declaration's, else 55 % of its standing height)", unit="m", above=0)
    model_file: str | None = option(None, "MJCF file to load instead of the declared one (the same names)")


class DeclaredBiped(Body):
    """Base of the classes :func:`declared_body` makes (each carries its declaration, bounds and fall height)."""

    declaration: Declaration
    bounds: tuple[np.ndarray, np.ndarray]
    fall_default: float
    timestep_default: float

    def __init__(self, options=None, **given):
        from ..core.options import constructor_options

        self.options = constructor_options(self.Options, options, given, f"{self.name} body_options")
        self.model_file = self.options.model_file or str(self.declaration.model)
        self.timestep = float(self.options.timestep if self.options.timestep is not None else self.timestep_default)
        self.fall_height = float(self.options.fall_height if self.options.fall_height is not None
                                 else self.fall_default)

    def action_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        return self.bounds[0].copy(), self.bounds[1].copy()

    def bind_model(self, m: mujoco.MjModel) -> None:
        d = self.declaration
        self._pelvis = m.body(d.pelvis).id
        acts = [m.actuator(a).id for side in LEGS for a in d.legs[side][0]]
        joints = m.actuator_trnid[acts, 0]
        self._act = np.array(acts)
        self._qadr, self._dadr = m.jnt_qposadr[joints], m.jnt_dofadr[joints]
        self._foot_geoms = np.array([m.geom(d.legs[side][1]).id for side in LEGS])
        self._foot_kinds = [GEOMS[int(m.geom_type[g])] for g in self._foot_geoms]
        self._foot_bodies = m.geom_bodyid[self._foot_geoms]
        tree = np.array([b for b in range(1, m.nbody) if m.body_rootid[b] == self._pelvis])
        self._tree, self._mass_share = tree, m.body_mass[tree] / m.body_mass[tree].sum()
        self._fwd, self._up = _axis(d.forward), _axis(d.up)
        self._left = np.cross(self._up, self._fwd)
        k = d.joints.index(d.knee) if d.knee is not None else None
        self._knees = None if k is None else self._qadr[[k, len(d.joints) + k]]
        self._hip_body = m.jnt_bodyid[joints[0]]
        self._foot_sizes = m.geom_size[self._foot_geoms].copy()

    def standing(self, m: mujoco.MjModel, data: mujoco.MjData) -> tuple[float, ...]:
        """``com_from_feet`` in the initial pose (its standing value)."""
        sims = _One(data)
        return tuple(float(x) for x in self._com_from_feet(sims)[0])

    def apply(self, sims: Sims, ids: np.ndarray, action: np.ndarray) -> None:
        sims.ctrl[np.ix_(ids, self._act)] = action

    def com(self, sims: Sims) -> np.ndarray:
        return sims.subtree_com[:, self._pelvis]

    def planar_position(self, sims: Sims) -> np.ndarray:
        return sims.xpos[:, self._pelvis, :2]

    def _rot(self, sims) -> np.ndarray:
        return sims.xmat[:, self._pelvis].reshape(-1, 3, 3)

    def heading(self, sims: Sims) -> np.ndarray:
        return sims.kept("heading", self._heading)

    def _heading(self, sims) -> np.ndarray:
        fwd = (self._rot(sims) @ self._fwd)[:, :2]
        return fwd / np.maximum(np.linalg.norm(fwd, axis=1, keepdims=True), 1e-12)

    def fallen(self, sims: Sims, ids: np.ndarray) -> np.ndarray:
        up = (sims.xmat[ids, self._pelvis].reshape(-1, 3, 3) @ self._up)[:, 2]
        return (sims.subtree_com[ids, self._pelvis, 2] < self.fall_height) | (up < np.cos(self.declaration.fall_tilt))

    def _frame(self, sims) -> np.ndarray:
        """``(P, 2, 2)``: rows forward and left of the heading frame on the ground."""
        f = self.heading(sims)
        return np.stack([f, np.stack([-f[:, 1], f[:, 0]], axis=1)], axis=1)

    def _feet_points(self, sims) -> np.ndarray:
        """The feet's lowest points ``(P, 2, 3)``."""
        return np.stack([_lowest(kind, size, sims.geom_xpos[:, g], sims.geom_xmat[:, g].reshape(-1, 3, 3))
                         for g, kind, size in zip(self._foot_geoms, self._foot_kinds, self._foot_sizes)], axis=1)

    def _com_from_feet(self, sims) -> np.ndarray:
        com = sims.subtree_com[:, self._pelvis, None, :2] - sims.geom_xpos[:, self._foot_geoms, :2]
        return np.einsum("pij,pfj->pfi", self._frame(sims), com).reshape(-1, 4)

    def sensors(self, sims: Sims, names: Collection[str] | None = None) -> dict[str, np.ndarray]:
        """The senses the module docstring lists; only ``names`` are computed (default all)."""
        want = self.sensor_widths if names is None else names
        contact = self.contacts(sims)
        out = joint_senses(sims, self._qadr, self._dadr, contact, want)
        if "pelvis_tilt" in want:
            rot = self._rot(sims)
            out["pelvis_tilt"] = np.stack([-np.arcsin(np.clip((rot @ self._fwd)[:, 2], -1, 1)),
                                           np.arcsin(np.clip((rot @ self._left)[:, 2], -1, 1))], axis=1)
        if "pelvis_tilt_rate" in want:  # pitch about the left axis, roll about the forward axis
            rates = np.einsum("pij,pj->pi", self._frame(sims), sims.cvel[:, self._pelvis, :2])
            out["pelvis_tilt_rate"] = rates[:, ::-1]
        if "com_from_feet" in want:
            out["com_from_feet"] = self._com_from_feet(sims)
        if "com_velocity" in want:
            out["com_velocity"] = np.einsum("pij,pj->pi", self._frame(sims), self._com_velocity(sims)[:, :2])
        if "stance_leg" in want or "since_touchdown" in want or "stance_side" in want:
            out.update(gait.read(contact, sims, want))
        return out

    def _contacts(self, sims: Sims) -> np.ndarray:
        return self._feet_points(sims)[..., 2] <= 0.0

    def _com_velocity(self, sims) -> np.ndarray:
        return links_com_velocity(sims, self._pelvis, self._tree, self._mass_share)

    def feet(self, sims: Sims) -> FootSample:
        """Each foot's lowest point against the floor plane (z = 0): in contact at or below it; slip is that point's
        horizontal speed, v + w x r."""
        point = self._feet_points(sims)
        cvel = sims.cvel[:, self._foot_bodies]
        r = point - sims.subtree_com[:, self._pelvis, None]
        v = cvel[..., 3:] + np.cross(cvel[..., :3], r)
        knee = (sims.qpos[:, self._knees] if self._knees is not None else np.full(point.shape[:2], np.nan))
        force = sims.actuator_force[:, self._act]
        return FootSample(contact=point[..., 2] <= 0.0, slip=np.hypot(v[..., 0], v[..., 1]), height=point[..., 2],
                          knee=knee, power=force * sims.actuator_velocity[:, self._act], torque=force.copy())

    def gait_constants(self, model: mujoco.MjModel) -> tuple[float, float]:
        data = mujoco.MjData(model)
        mujoco.mj_forward(model, data)
        low = self._feet_points(_One(data))[0, :, 2].min()
        return float(model.body_mass[self._tree].sum()), float(data.xpos[self._hip_body, 2] - low)


class _One:
    """One MjData seen as a batch of one (the fields a body reads, with a leading axis of 1)."""

    def __init__(self, data: mujoco.MjData):
        self._data = data
        self.readings, self._kept = {}, {}

    def __getattr__(self, name):
        if name.startswith("_"):
            raise AttributeError(name)
        return np.asarray(getattr(self._data, name))[None]

    def kept(self, name, read):
        return read(self)
