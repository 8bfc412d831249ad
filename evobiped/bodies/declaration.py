"""A biped's declaration: what evobiped must be told about an MJCF model to evolve walkers on it.

The declaration is a TOML file beside the model (``biped.xml`` and ``biped.toml``), or a TOML file naming its model
(``model = "biped.xml"``, relative to the declaration).  Everything else (senses, mirror, fall test, feet, leg
length, action bounds) is derived from it and the compiled model (:mod:`.declared`)::

    pelvis = "torso"          # the walker's root body (it has the free joint): heading, tilt and the fall test
    forward = "x"             # the pelvis's own axis that points forward when it stands (x, y, -x or -y)
    up = "z"                  # the pelvis's own axis that points up when it stands (z, -z, x, -x, y or -y)
    floor = "floor"           # the ground geom
    joints = ["hip_pitch", "hip_roll", "knee", "ankle"]   # each leg's actuators' roles, the hip first
    mirror_signs = [1, 1, 1, 1]   # per role: -1 where the other leg's joint turns the other way for the same motion
    knee = "knee"             # the role whose angle the gait lab reports as knee swing (optional)
    fall_height = 0.5         # m: the centre of mass below this has fallen (default 55 % of its standing height)
    fall_tilt = 1.5708        # rad: the pelvis's up axis tilted beyond this has fallen (default 90 degrees)

    [legs.left]
    actuators = ["left_hip_pitch", "left_hip_roll", "left_knee", "left_ankle"]
    foot = "left_foot"        # a sphere, capsule, cylinder or box geom: its lowest point meets the ground

    [legs.right]
    actuators = ["right_hip_pitch", "right_hip_roll", "right_knee", "right_ankle"]
    foot = "right_foot"

Every actuator is a position servo (its control a joint target in rad) or a motor (a torque in N m), all of one kind,
each driving one hinge joint; the standing pose is the model's initial one (``qpos0``).
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass
from pathlib import Path

import mujoco

from ..core.errors import ConfigError

#: a declaration's keys: required ones, then those with defaults
REQUIRED = ("pelvis", "joints", "legs")
DEFAULTS = {"forward": "x", "up": "z", "floor": "floor", "mirror_signs": None, "knee": None, "fall_height": None,
            "fall_tilt": math.pi / 2, "model": None}
AXES = {"x": (0, 1.0), "-x": (0, -1.0), "y": (1, 1.0), "-y": (1, -1.0), "z": (2, 1.0), "-z": (2, -1.0)}
LEGS = ("left", "right")
#: the foot shapes whose lowest point the body finds
GEOMS = {int(mujoco.mjtGeom.mjGEOM_SPHERE): "sphere", int(mujoco.mjtGeom.mjGEOM_CAPSULE): "capsule",
         int(mujoco.mjtGeom.mjGEOM_CYLINDER): "cylinder", int(mujoco.mjtGeom.mjGEOM_BOX): "box"}


@dataclass(frozen=True)
class Declaration:
    """A checked declaration (the module docstring says what each field means)."""

    path: Path
    model: Path
    pelvis: str
    forward: str
    up: str
    floor: str
    joints: tuple[str, ...]
    mirror_signs: tuple[float, ...]
    knee: str | None
    fall_height: float | None
    fall_tilt: float
    #: leg -> (actuator names in role order, foot geom)
    legs: dict[str, tuple[tuple[str, ...], str]]


def locate(spec: str) -> tuple[Path, Path]:
    """``(declaration, model)`` of ``mjcf:``'s argument: a model ``.xml`` with its ``.toml`` beside it, or a
    declaration ``.toml`` (its model beside it, or the one it names).  ConfigError when a file is missing."""
    p = Path(spec).expanduser()
    if "/" not in spec and not p.suffix:  # a shipped model's stem: models/<stem>.xml and its declaration
        from ..physics.models import model_path

        p = model_path(spec)
    decl = p.with_suffix(".toml") if p.suffix.lower() == ".xml" else p
    if not decl.is_file():
        raise ConfigError(f"mjcf:{spec}: no declaration {decl} (write one beside the model: docs/own_robot.md)")
    return decl.resolve(), (p.resolve() if p.suffix.lower() == ".xml" else None)


def read_declaration(spec: str) -> Declaration:
    """The declaration of ``mjcf:spec``, its keys and types checked: every problem found, one line each."""
    path, model = locate(spec)
    try:
        table = tomllib.loads(path.read_text())
    except (OSError, UnicodeDecodeError) as exc:
        raise ConfigError(f"{path}: cannot be read ({exc})") from None
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{path}: not TOML ({exc})") from None
    problems = [f"unknown key {k!r} (known: {', '.join(REQUIRED + tuple(DEFAULTS))})"
                for k in table if k not in REQUIRED and k not in DEFAULTS]
    problems += [f"{k} is missing" for k in REQUIRED if k not in table]
    t = {**DEFAULTS, **table}
    for key in ("pelvis", "floor", "forward", "up"):
        if key in t and (not isinstance(t[key], str) or not t[key]):
            problems.append(f"{key} must be a name, got {t[key]!r}")
    for key in ("forward", "up"):
        if isinstance(t[key], str) and t[key] not in AXES:
            problems.append(f"{key} must be one of {', '.join(AXES)}, got {t[key]!r}")
    if isinstance(t["forward"], str) and isinstance(t["up"], str) and t["forward"][-1:] == t["up"][-1:]:
        problems.append(f"forward ({t['forward']}) and up ({t['up']}) must be different axes")
    joints = t.get("joints", [])
    if "joints" in t and not (isinstance(joints, list) and joints and all(isinstance(j, str) and j for j in joints)
            and len(set(joints)) == len(joints)):
        problems.append(f"joints must be a list of distinct role names, the hip first, got {joints!r}")
        joints = []
    signs = t["mirror_signs"] if t["mirror_signs"] is not None else [1] * len(joints)
    if not (isinstance(signs, list) and len(signs) == len(joints) and all(s in (1, -1) for s in signs)):
        problems.append(f"mirror_signs must be {len(joints)} values of 1 or -1 (one per joint role), got {signs!r}")
    if t["knee"] is not None and t["knee"] not in joints:
        problems.append(f"knee must be one of the joint roles ({', '.join(joints)}), got {t['knee']!r}")
    for key, low, high in (("fall_height", 0.0, math.inf), ("fall_tilt", 0.0, math.pi)):
        v = t[key]
        if v is not None and not (isinstance(v, (int, float)) and not isinstance(v, bool) and low < v <= high):
            problems.append(f"{key} must be a number in ({low:g}, {high:g}], got {v!r}")
    legs = {}
    raw = t.get("legs")
    if raw is None:
        pass  # missing: said above
    elif not isinstance(raw, dict) or sorted(raw) != sorted(LEGS):
        problems.append("legs must be the tables [legs.left] and [legs.right], got "
                        f"{sorted(raw) if isinstance(raw, dict) else raw!r}")
    else:
        for side in LEGS:
            leg = raw[side]
            acts = leg.get("actuators") if isinstance(leg, dict) else None
            foot = leg.get("foot") if isinstance(leg, dict) else None
            if not isinstance(leg, dict) or set(leg) - {"actuators", "foot"}:
                problems.append(f"legs.{side} must hold actuators and foot only")
            if not (isinstance(acts, list) and all(isinstance(a, str) for a in acts) and len(acts) == len(joints)):
                problems.append(f"legs.{side}.actuators must name {len(joints)} actuators (one per joint role), got "
                                f"{acts!r}")
                acts = []
            if not isinstance(foot, str) or not foot:
                problems.append(f"legs.{side}.foot must name the foot's geom, got {foot!r}")
            legs[side] = (tuple(acts), foot)
    if t["model"] is not None:
        if not isinstance(t["model"], str):
            problems.append(f"model must be a file name, got {t['model']!r}")
        else:
            model = (path.parent / t["model"]).resolve()
    if model is None:
        model = path.with_suffix(".xml")
    if not problems and not model.is_file():
        problems.append(f"model {model} not found")
    refuse_declaration(path, problems)
    return Declaration(path=path, model=model, pelvis=t["pelvis"], forward=t["forward"], up=t["up"], floor=t["floor"],
                       joints=tuple(joints), mirror_signs=tuple(float(s) for s in signs), knee=t["knee"],
                       fall_height=None if t["fall_height"] is None else float(t["fall_height"]),
                       fall_tilt=float(t["fall_tilt"]), legs=legs)


def refuse_declaration(path: Path, problems: list[str]) -> None:
    """ConfigError listing ``problems`` of the declaration at ``path``, one line each (none: nothing)."""
    if problems:
        lines = "\n".join(f"  {path.name}: {p}" for p in problems)
        raise ConfigError(f"body declaration {path}: {len(problems)} problem{'s' * (len(problems) > 1)}\n{lines}")


def check_model(d: Declaration, m: mujoco.MjModel) -> tuple[str, list[str]]:
    """The actuators' kind (``position`` or ``torque``) and what is wrong with the model for this declaration."""
    problems = []

    def find(kind, name, where):
        i = mujoco.mj_name2id(m, kind, name)
        if i < 0:
            problems.append(f"{where}: the model has no {kind.name[6:].lower()} {name!r}")
        return i

    pelvis = find(mujoco.mjtObj.mjOBJ_BODY, d.pelvis, "pelvis")
    if pelvis >= 0 and (m.body_jntnum[pelvis] < 1 or m.jnt_type[m.body_jntadr[pelvis]] != mujoco.mjtJoint.mjJNT_FREE):
        problems.append(f"pelvis: body {d.pelvis!r} has no free joint (the walker's root must be free)")
    find(mujoco.mjtObj.mjOBJ_GEOM, d.floor, "floor")
    kinds = set()
    for side in LEGS:
        acts, foot = d.legs[side]
        for a in acts:
            i = find(mujoco.mjtObj.mjOBJ_ACTUATOR, a, f"legs.{side}.actuators")
            if i < 0:
                continue
            if m.actuator_trntype[i] != mujoco.mjtTrn.mjTRN_JOINT or m.jnt_type[m.actuator_trnid[
                i, 0]] != mujoco.mjtJoint.mjJNT_HINGE:
                problems.append(f"legs.{side}.actuators: {a!r} does not drive one hinge joint")
            if not m.actuator_ctrllimited[i]:
                problems.append(f"legs.{side}.actuators: {a!r} has no ctrlrange (its bounds are the actions')")
            kinds.add("position" if m.actuator_biastype[i] == mujoco.mjtBias.mjBIAS_AFFINE else "torque")
        g = find(mujoco.mjtObj.mjOBJ_GEOM, foot, f"legs.{side}.foot")
        if g >= 0 and int(m.geom_type[g]) not in GEOMS:
            problems.append(f"legs.{side}.foot: geom {foot!r} must be a sphere, capsule, cylinder or box")
    if len(kinds) > 1:
        problems.append("actuators: all must be position servos or all motors, not both")
    names = [a for side in LEGS for a in d.legs[side][0]]
    if m.nu != len(names) and not problems:
        problems.append(f"actuators: the model has {m.nu} actuators, the legs declare {len(names)}")
    return (kinds.pop() if len(kinds) == 1 else "position"), problems
