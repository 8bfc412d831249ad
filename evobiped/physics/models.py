"""Where the MJCF files live, from a source checkout or an installed wheel."""

from __future__ import annotations

import sys
from pathlib import Path

import mujoco

from ..core.errors import UserError

_PACKAGE = Path(__file__).resolve().parent.parent  # evobiped/
# an installed wheel carries models/ inside the package; a checkout has it beside it
_CANDIDATES = (_PACKAGE / "models", _PACKAGE.parent / "models")


def _warned(message: str) -> None:
    """MuJoCo's warnings (an unstable simulation, ...) on standard error as MuJoCo prints them, but without its
    ``MUJOCO_LOG.TXT`` in the current folder (the simulation still counts them: an unstable one is a fall)."""
    try:
        sys.stderr.write(f"WARNING: {message}\n")
    except (OSError, ValueError):  # no standard error left (a closed pipe): nothing to say it on
        pass


mujoco.set_mju_user_warning(_warned)  # every simulation's model is compiled here first


def models_dir() -> Path:
    for d in _CANDIDATES:
        if d.is_dir():
            return d
    raise UserError("cannot find the models/ folder (neither in the package nor beside it)")


def model_path(name: str) -> Path:
    """Path of ``models/<name>.xml``."""
    return models_dir() / f"{name}.xml"


def load_model(path: str | Path) -> mujoco.MjModel:
    """Compile an MJCF file; a missing or invalid file is a :class:`UserError`."""
    path = Path(path)
    if not path.is_file():
        raise UserError(f"model file not found: {path}")
    try:
        return mujoco.MjModel.from_xml_path(str(path))
    except ValueError as exc:
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else "invalid MJCF"
        raise UserError(f"model file {path} does not compile: {first}") from None
