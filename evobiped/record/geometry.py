"""What a walker looks like, read generically from a compiled MuJoCo model.

Every geom becomes a :class:`Shape` in its body's frame (capsule, sphere,
ellipsoid, cylinder, box, plane); a body with mass but no geom (e.g. the Taga
biped's hip point mass) becomes a small sphere at its origin.  Nothing here
depends on a particular body, so any MJCF model draws.  Poses use MuJoCo's
conventions: positions in m, quaternions wxyz.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import mujoco
import numpy as np

#: radius (m) of the sphere drawn for a body that has mass but no geom
POINT_MASS_RADIUS = 0.06
#: half side (m) of the square drawn for an infinite plane (MJCF size 0)
PLANE_HALF_SIZE = 20.0

_G = mujoco.mjtGeom
KINDS = {
    int(_G.mjGEOM_PLANE): "plane",
    int(_G.mjGEOM_HFIELD): "hfield",
    int(_G.mjGEOM_SPHERE): "sphere",
    int(_G.mjGEOM_CAPSULE): "capsule",
    int(_G.mjGEOM_ELLIPSOID): "ellipsoid",
    int(_G.mjGEOM_CYLINDER): "cylinder",
    int(_G.mjGEOM_BOX): "box",
    int(_G.mjGEOM_MESH): "mesh",
}


@dataclass(frozen=True)
class Shape:
    """One drawable solid, posed in the frame of body ``body``.

    ``size`` is MuJoCo's ``geom_size`` (3,): sphere (r), capsule/cylinder
    (r, half length), ellipsoid/box (3 half sizes), plane (half x, half y, grid).
    """

    name: str
    kind: str
    body: int
    size: np.ndarray
    pos: np.ndarray
    quat: np.ndarray  # wxyz
    rgba: np.ndarray  # 4 floats in [0, 1]


def safe_name(name: str, fallback: str) -> str:
    """A name usable as one entity-path part (letters, digits, _ and -)."""
    return re.sub(r"[^A-Za-z0-9_\-]", "_", name) if name else fallback


def body_names(model: mujoco.MjModel) -> list[str]:
    return [safe_name(model.body(i).name, f"body{i}") for i in range(model.nbody)]


def shapes(model: mujoco.MjModel) -> list[Shape]:
    """Every visible geom (alpha > 0), plus a sphere for each massive geom-less body."""
    out = []
    for g in range(model.ngeom):
        rgba = model.geom_rgba[g].copy()
        if rgba[3] <= 0:
            continue
        out.append(
            Shape(
                name=safe_name(model.geom(g).name, f"geom{g}"),
                kind=KINDS.get(int(model.geom_type[g]), "other"),
                body=int(model.geom_bodyid[g]),
                size=model.geom_size[g].copy(),
                pos=model.geom_pos[g].copy(),
                quat=model.geom_quat[g].copy(),
                rgba=rgba,
            )
        )
    has_geom = np.zeros(model.nbody, bool)
    has_geom[model.geom_bodyid] = True
    for b in range(1, model.nbody):
        if not has_geom[b] and model.body_mass[b] > 0:
            out.append(
                Shape(
                    name="point_mass",
                    kind="sphere",
                    body=b,
                    size=np.array([POINT_MASS_RADIUS, 0.0, 0.0]),
                    pos=np.zeros(3),
                    quat=np.array([1.0, 0.0, 0.0, 0.0]),
                    rgba=np.array([0.55, 0.55, 0.6, 1.0]),
                )
            )
    return out


def quat_to_mat(q: np.ndarray) -> np.ndarray:
    """Rotation matrices ``(..., 3, 3)`` of unit quaternions ``(..., 4)`` wxyz (MuJoCo's ``mju_quat2Mat`` per
    quaternion)."""
    q = np.asarray(q, float)
    flat = q.reshape(-1, 4)
    out = np.empty((len(flat), 9))
    for i, quat in enumerate(flat):
        mujoco.mju_quat2Mat(out[i], quat)
    return out.reshape(q.shape[:-1] + (3, 3))


def wxyz_to_xyzw(q: np.ndarray) -> np.ndarray:
    """MuJoCo quaternions (wxyz) to Rerun's order (xyzw), any leading shape."""
    q = np.asarray(q)
    return np.concatenate([q[..., 1:], q[..., :1]], axis=-1)


def segment(shape: Shape, body_pos: np.ndarray, body_quat: np.ndarray) -> np.ndarray:
    """World endpoints ``(T, 2, 3)`` of a shape's long axis for body poses ``(T, 3)``, ``(T, 4)``.

    Capsules and cylinders: the two cap centres; boxes and ellipsoids: the
    longest half-axis both ways; spheres: the centre twice.
    """
    if shape.kind in ("capsule", "cylinder"):
        half = np.array([0.0, 0.0, shape.size[1]])
    elif shape.kind in ("box", "ellipsoid"):
        half = np.zeros(3)
        i = int(np.argmax(shape.size))
        half[i] = shape.size[i]
    else:
        half = np.zeros(3)
    axis = quat_to_mat(shape.quat) @ half
    local = np.stack([shape.pos - axis, shape.pos + axis])  # (2, 3)
    R = quat_to_mat(body_quat)  # (T, 3, 3)
    return body_pos[:, None, :] + np.einsum("tij,kj->tki", R, local)
