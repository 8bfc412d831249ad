"""The sagittal biped of Taga, Yamaguchi & Shimizu 1991 (``models/taga_biped.xml``).

MuJoCo integrates the rigid links (hip point mass on slide x/z, hinge hips and knees, uniform rods); this module
adds, before every physics step, the forces of Appendix A that MJCF cannot express, as generalized forces in
``qfrc_applied`` computed for the whole batch at once:

* the ground: a 2D spring-damper at each ankle, active while the ankle is below the terrain y_g(x), whose rest
  point (x_r0, y_r0) is reset to the point where the ankle first touches (Raibert 1984)::

      F_x = -k_g (x_r - x_r0) - b_g dx_r/dt
      F_y = -k_g (y_r - y_r0) + b_g max(0, -dy_r/dt)

* hip friction -b_1 |x_5 - pi/2| dx_5/dt on each thigh;
* knee friction -(b_2 + b_k f(x_5 - x_11)) (dx_5/dt - dx_11/dt) and the knee's elastic stop, read as the one-sided
  linear spring k_k max(0, x_5 - x_11) (the literal k_k h(x_5 - x_11) is a constant 1e4 N m step, numerically
  ill-posed);
* the joint torques T_r1..T_r6 (actions, N m), the ankle torques only while that ankle is in contact (h(F_g2),
  h(F_g4) with h(0) = 0).

Other external forces (a perturbation's push, Fig. 7's) act through MuJoCo's ``xfrc_applied``, as on any body.

Angles are Taga's inertial angles from the horizontal (pi/2 = vertical, increasing as the distal end swings
backward): thigh x_5 = pi/2 + hip, shank x_11 = x_5 + knee.  The forces are explicit, so the physics step is small
(0.5 ms; halving it changes the walking metrics by < 1 %, see docs/taga.md).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar, Collection

import mujoco
import numpy as np

from ..interface.contract import Actuator, Environment
from ..core.errors import ConfigError, UserError
from ..physics.gait_lab import FootSample
from ..physics.sim import Sims
from ..core.options import option
from .base import Body, model_file_option

#: actions in this order (N m); T_r1, T_r3, T_r5 (right) and T_r2, T_r4, T_r6 (left)
ACTUATORS = ("right_hip", "right_knee", "right_ankle", "left_hip", "left_knee", "left_ankle")
#: Appendix D, musculo-skeletal system (SI units)
APPENDIX_D = dict(l1=0.5, l2=0.6, b1=10.0, b2=10.0, bk=1000.0, kk=10000.0, kg=10000.0, bg=1000.0)
#: Appendix E: hip (x_1, x_2) in m, thigh and shank angles (rad) of the right and left legs
INITIAL_HIP = (0.0, 1.09)
INITIAL_ANGLES = {"right": 0.45 * np.pi, "left": 0.57 * np.pi}


def _per_simulation(low: float, strict: bool):
    """A check: one number, or a list of them (one per simulation), each > low (strict) or >= low."""

    def check(v) -> None:
        a = np.asarray(v, float) if isinstance(v,
                                               (int, float, list, tuple,
                                                np.ndarray)) and not isinstance(v, bool) else None
        if a is None or a.ndim > 1 or a.size == 0 or not np.isfinite(a).all() or not (np.all(
            a > low) if strict else np.all(a >= low)):
            raise ConfigError(f"must be a number {'>' if strict else '>='} {low:g} (or a list, one per simulation), "
                              f"got {v!r}")

    return check


@dataclass(frozen=True, kw_only=True)
class TagaOptions:
    """Options of the taga body."""

    timestep: float = option(0.0005, "physics step (the forces are explicit: keep it small)", unit="s", low=1e-5,
                             high=0.005)
    kg: float = option(APPENDIX_D["kg"], "ground stiffness k_g (Appendix D)", unit="N/m",
                       check=_per_simulation(0.0, True), span="> 0, or one per simulation")
    bg: float = option(APPENDIX_D["bg"], "ground damping b_g (Appendix D)", unit="N s/m",
                       check=_per_simulation(0.0, False), span=">= 0, or one per simulation")
    slope: float = option(0.0, "terrain slope beyond `slope_start`, rise over run (0.02 = 2 %, uphill)", low=-0.5,
                          high=0.5)
    slope_start: float = option(0.0, "where the slope begins, along x", unit="m")
    max_torque: float = option(2000.0, "joint torque bound (never reached by Taga's generator)", unit="N m", above=0)
    fall_height: float = option(0.7, "hip height above the terrain below which the walker has fallen", unit="m",
                                above=0)
    model_file: str | None = model_file_option("taga_biped")


def _last_axis(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``np.stack([a, b], -1)`` without its generic overhead (this runs several times per control tick)."""
    out = np.empty(a.shape + (2,))
    out[..., 0], out[..., 1] = a, b
    return out


class TagaBiped(Body):
    """Taga's 5-link sagittal walker with the Appendix A ground and joint forces."""

    name: ClassVar[str] = "taga"
    model_name: ClassVar[str] = "taga_biped"
    action_kind: ClassVar[str] = "torque"
    trunk: ClassVar[str] = "hip"
    has_custom_forces: ClassVar[bool] = True
    contact_sensor: ClassVar[tuple[str, tuple[str, ...]]] = ("ground_contact", ("right", "left"))
    sagittal: ClassVar[bool] = True
    actuators: ClassVar[tuple[Actuator, ...]] = tuple(Actuator(a, *a.split("_")) for a in ACTUATORS)
    #: see :meth:`sensors`
    sensor_widths: ClassVar[dict[str, int]] = {"link_angles": 4, "link_velocities": 4, "ground_contact": 2,
                                               "ground_force": 4}
    sensor_text: ClassVar[dict[str, str]] = {
        "link_angles": "inertial angles of right thigh, right shank, left thigh, left shank (rad from the horizontal)",
        "link_velocities": "their rates (rad/s), same order", "ground_contact": "ground contacts: right, left (0 or 1)",
        "ground_force": "ground forces F_g1..F_g4 (N)"}
    environment: ClassVar[Environment] = Environment("Taga's sagittal 5-link biped",
                                                     "joint torques (N m), ±`max_torque`", 0.01)
    #: standing values and scales for a controller that normalises its inputs: about the mean and standard deviation
    #: of each reading over seconds 2-10 of the Appendix D walker's gait (the same for both legs)
    sensor_norms: ClassVar[dict] = {
        "link_angles": ((1.39, 1.72, 1.39, 1.72), (0.3, 0.35, 0.3, 0.35)),
        "link_velocities": ((0.0,) * 4, (2.2, 2.8, 2.2, 2.8)),
        "ground_contact": ((0.5, 0.5), (0.5, 0.5)),
        "ground_force": ((0.0, 335.0, 0.0, 335.0), (120.0, 345.0, 120.0, 345.0))}
    #: left/right mirror: a sagittal body's legs swap and nothing changes sign
    mirror: ClassVar[dict] = {"link_angles": ((2, 3, 0, 1), (1,) * 4), "link_velocities": ((2, 3, 0, 1), (1,) * 4),
                              "ground_contact": ((1, 0), (1, 1)), "ground_force": ((2, 3, 0, 1), (1,) * 4)}
    actuator_mirror: ClassVar[tuple] = ((3, 4, 5, 0, 1, 2), (1,) * 6)

    Options: ClassVar[type] = TagaOptions

    def __init__(self, options=None, **given):
        super().__init__(options, **given)
        o = self.options
        # kg, bg: one value, or one per simulation of the batch (P,)
        self.p = dict(APPENDIX_D, kg=np.asarray(o.kg, float), bg=np.asarray(o.bg, float))
        self.slope, self.slope_start = float(o.slope), float(o.slope_start)
        self.max_torque, self.fall_height = float(o.max_torque), float(o.fall_height)

    # ------------------------------------------------------------ structure
    def action_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """``+-max_torque`` N m (2000 by default: never reached by Taga's generator)."""
        h = np.full(len(ACTUATORS), self.max_torque)
        return -h, h

    def bind_model(self, model: mujoco.MjModel) -> None:
        try:
            joints = ("root_x", "root_z", "right_hip", "right_knee", "left_hip", "left_knee")
            self._qadr = np.array([model.joint(j).qposadr[0] for j in joints])
            self._dadr = np.array([model.joint(j).dofadr[0] for j in joints])
            self._hip = model.body("hip").id
        except KeyError as exc:
            raise UserError(f"taga body: the model lacks {exc}") from None
        if model.nv != 6:
            raise UserError(f"taga body: expected 6 degrees of freedom, the model has {model.nv}")

    def terrain(self, x: np.ndarray) -> np.ndarray:
        """y_g(x) in m: level, then a constant slope from ``slope_start`` on."""
        return self.slope * np.maximum(np.asarray(x, float) - self.slope_start, 0.0)

    # ------------------------------------------------------------ state
    def _ground(self, sims: Sims) -> dict:
        """This body's state in the batch (``sims.extra``, copied with it): ground contacts, forces, torques."""
        st = sims.extra.get(self.name)
        if st is None:
            n = sims.n
            st = sims.extra[self.name] = dict(
                rest=np.zeros((n, 2, 2)),  # (P, leg, xy) rest points
                contact=np.zeros((n, 2), bool),  # ankle below the terrain (right, left)
                force=np.zeros((n, 4)),  # F_g1..F_g4 (N)
                torque=np.zeros((n, 6)),  # commanded T_r (ACTUATORS order)
            )
        return st

    def set_ground(self, sims: Sims, kg, bg) -> None:
        """From now on the ground under the simulations of ``sims`` has stiffness ``kg`` (N/m) and damping ``bg``
        (N s/m), each one value or one per simulation ``(n,)`` (until then: the body's ``kg`` and ``bg`` options);
        kept in ``sims.extra``, so a forked episode state keeps its ground."""
        st = self._ground(sims)
        st["kg"], st["bg"] = np.asarray(kg, float), np.asarray(bg, float)

    def reset(self, sims: Sims, ids: np.ndarray | None = None) -> None:
        """Appendix E: hip at (0, 1.09) m, straight legs at 0.45 pi (right) and 0.57 pi (left), at rest;
        simulations ``ids`` (default all), their ground contacts and applied forces cleared."""
        rows = slice(None) if ids is None else ids
        sims.reset(ids)
        q = sims.qpos
        q[rows, self._qadr[0]], q[rows, self._qadr[1]] = INITIAL_HIP
        q[rows, self._qadr[2]], q[rows,
                                  self._qadr[4]] = INITIAL_ANGLES["right"] - np.pi / 2, INITIAL_ANGLES[
                                      "left"] - np.pi / 2
        q[rows, self._qadr[3]] = q[rows, self._qadr[5]] = 0.0
        sims.qvel[rows] = sims.qfrc_applied[rows] = 0.0
        for a in self._ground(sims).values():
            a[rows] = 0
        sims.forward(ids)  # after the ground's state, so no reading of the old state is kept

    # ------------------------------------------------------------ kinematics
    def links(self, sims: Sims) -> dict[str, np.ndarray]:
        """Taga's coordinates, each ``(P,)`` or ``(P, 2)`` (right, left leg).

        ``hip`` (P, 2) position, ``dhip`` velocity; ``thigh``/``shank`` inertial
        angles and ``dthigh``/``dshank`` rates (P, 2); ``knee``/``ankle`` (P, 2, 2)
        positions and ``dankle`` (P, 2, 2) velocities.
        """
        q, v = sims.qpos[:, self._qadr], sims.qvel[:, self._dadr]
        (l1, l2), hip, dhip = (self.p["l1"], self.p["l2"]), q[:, :2], v[:, :2]
        thigh = np.pi / 2 + q[:, [2, 4]]
        shank = thigh + q[:, [3, 5]]
        dthigh = v[:, [2, 4]]
        dshank = dthigh + v[:, [3, 5]]
        cos_t, sin_t, cos_s, sin_s = np.cos(thigh), np.sin(thigh), np.cos(shank), np.sin(shank)
        ut = _last_axis(cos_t, -sin_t)  # (P, 2, 2) unit vectors hip->knee
        us = _last_axis(cos_s, -sin_s)
        knee = hip[:, None, :] + l1 * ut
        ankle = knee + l2 * us
        dt_ = _last_axis(-sin_t, -cos_t) * dthigh[..., None]
        ds_ = _last_axis(-sin_s, -cos_s) * dshank[..., None]
        dankle = dhip[:, None, :] + l1 * dt_ + l2 * ds_
        return dict(hip=hip, dhip=dhip, thigh=thigh, shank=shank, dthigh=dthigh, dshank=dshank, knee=knee, ankle=ankle,
                    dankle=dankle)

    # ------------------------------------------------------------ forces
    def apply(self, sims: Sims, ids: np.ndarray, action: np.ndarray) -> None:
        self._ground(sims)["torque"][ids] = action

    def substep(self, sims: Sims, ids: np.ndarray) -> None:
        st, p, k = self._ground(sims), self.p, self.links(sims)
        ax, ay = k["ankle"][ids, :, 0], k["ankle"][ids, :, 1]
        vx, vy = k["dankle"][ids, :, 0], k["dankle"][ids, :, 1]
        below = ay - self.terrain(ax) < 0
        touch, rest = below & ~st["contact"][ids], st["rest"][ids]
        rest[..., 0] = np.where(touch, ax, rest[..., 0])
        rest[..., 1] = np.where(touch, self.terrain(ax), rest[..., 1])
        st["rest"][ids], st["contact"][ids] = rest, below
        kg, bg = st.get("kg", p["kg"]), st.get("bg", p["bg"])  # the ground under each simulation, else the body's
        kg, bg = (kg[ids, None] if kg.ndim else kg), (bg[ids, None] if bg.ndim else bg)
        fx = np.where(below, -kg * (ax - rest[..., 0]) - bg * vx, 0.0)
        fy = np.where(below, -kg * (ay - rest[..., 1]) + bg * np.maximum(-vy, 0.0), 0.0)
        st["force"][ids] = np.stack([fx[:, 0], fy[:, 0], fx[:, 1], fy[:, 1]], 1)
        on = (fy > 0).astype(float)  # h(F_g2), h(F_g4) with h(0) = 0
        T = st["torque"][ids]
        t_hip, t_knee, t_ankle = T[:, [0, 3]], T[:, [1, 4]], T[:, [2, 5]] * on
        thigh, shank, dthigh, dshank = k["thigh"][ids], k["shank"][ids], k["dthigh"][ids], k["dshank"][ids]
        over = np.maximum(thigh - shank, 0.0)  # knee hyperextension x5 - x11 (rad)
        knee_rel = dshank - dthigh
        # link torques (in the sense of increasing inertial angle)
        tau_shank = -(p["b2"] + p["bk"] * over) * knee_rel + p["kk"] * over - t_knee - t_ankle
        q_hip = -p["b1"] * np.abs(thigh - np.pi / 2) * dthigh + t_hip - t_ankle  # thigh + shank torques
        q_knee = tau_shank
        # the ground force at the ankle: generalized forces r x F about each joint's y axis
        hip, knee = k["hip"][ids][:, None, :], k["knee"][ids]
        ankle = k["ankle"][ids]

        def moment(r, fx_, fz_):
            return r[..., 1] * fx_ - r[..., 0] * fz_

        q_hip, q_knee = q_hip + moment(ankle - hip, fx, fy), q_knee + moment(ankle - knee, fx, fy)
        qf = np.zeros((len(ids), 6))
        qf[:, 0], qf[:, 1], qf[:, [2, 4]], qf[:, [3, 5]] = fx.sum(1), fy.sum(1), q_hip, q_knee
        sims.qfrc_applied[np.ix_(ids, self._dadr)] = qf

    def feet(self, sims: Sims) -> FootSample:
        """The ankles (point feet) on the spring-damper ground: a foot stands while the ground pushes it up; slip is
        the ankle's speed along the ground, power each joint torque times its rate (the ankle's only in contact)."""
        k, st = self.links(sims), self._ground(sims)
        on, T, knee_rate = st["force"][:, [1, 3]] > 0, st["torque"], sims.qvel[:, self._dadr[[3, 5]]]
        power = np.concatenate([T[:, [0, 3]] * k["dthigh"], -T[:, [1, 4]] * knee_rate,
                                -T[:, [2, 5]] * on * k["dshank"]], axis=1)
        return FootSample(contact=on, slip=np.abs(k["dankle"][..., 0]), height=k["ankle"][..., 1]
                          - self.terrain(k["ankle"][..., 0]),
                          knee=sims.qpos[:, self._qadr[[3, 5]]], power=power,
                          torque=np.concatenate([T[:, [0, 3]], T[:, [1, 4]], T[:, [2, 5]] * on], axis=1))

    def gait_constants(self, model: mujoco.MjModel) -> tuple[float, float]:
        return float(model.body_mass.sum()), self.p["l1"] + self.p["l2"]

    # ------------------------------------------------------------ observations
    def com(self, sims: Sims) -> np.ndarray:
        return sims.subtree_com[:, self._hip]

    def planar_position(self, sims: Sims) -> np.ndarray:
        """The hip's (x, y) on the ground plane (y = 0: the walker stays in its plane)."""
        return sims.xpos[:, self._hip, :2]

    def heading(self, sims: Sims) -> np.ndarray:
        out = np.zeros((sims.n, 2))
        out[:, 0] = 1.0
        return out

    def hip_height(self, sims: Sims) -> np.ndarray:
        """Hip height above the terrain under it, ``(P,)`` m."""
        x, z = sims.qpos[:, self._qadr[0]], sims.qpos[:, self._qadr[1]]
        return z - self.terrain(x)

    def fallen(self, sims: Sims, ids: np.ndarray) -> np.ndarray:
        return self.hip_height(sims)[ids] < self.fall_height

    def sensors(self, sims: Sims, names: Collection[str] | None = None) -> dict[str, np.ndarray]:
        """Feedback of Appendix C and more, only ``names`` (default all); leg order (right, left).

        ``link_angles`` (P, 4): inertial angles x5, x11, x8, x14 (right thigh,
        right shank, left thigh, left shank; rad from the horizontal);
        ``link_velocities`` (P, 4): their rates (rad/s); ``ground_contact``
        (P, 2): h(F_g2), h(F_g4); ``ground_force`` (P, 4): F_g1..F_g4 (N).
        """
        want, out = self.sensor_widths if names is None else names, {}
        if "link_angles" in want or "link_velocities" in want:
            k = self.links(sims)
            for name, (a, b) in (("link_angles", ("thigh", "shank")), ("link_velocities", ("dthigh", "dshank"))):
                if name in want:
                    out[name] = np.stack([k[a][:, 0], k[b][:, 0], k[a][:, 1], k[b][:, 1]], 1)
        force = self._ground(sims)["force"]
        if "ground_contact" in want:
            out["ground_contact"] = (force[:, [1, 3]] > 0).astype(float)
        if "ground_force" in want:
            out["ground_force"] = force.copy()
        return out
