"""The grounds an episode's trials walk on: its model with another floor friction, tilted into a slope, or under a
share of its gravity (the gravity curriculum), each made once per episode (:class:`Grounds`)."""

from __future__ import annotations

import copy

import mujoco
import numpy as np

from ..bodies.base import Body
from ..core.errors import ConfigError
from ..physics.sim import Sims


class Grounds:
    """``model`` (``body``'s, compiled for an episode) on each ground asked for, made on first use and kept."""

    def __init__(self, body: Body, model: mujoco.MjModel):
        self.body, self.model = body, model
        self._models: dict[tuple[float | None, float, float, float], mujoco.MjModel] = {}

    def sims(self, n: int, *, friction: float | None = None, slope: float = 0.0, slope_direction: float = 0.0,
             gravity: float = 1.0) -> Sims:
        """A new batch of ``n`` simulations on the model with this ground: floor ``friction``, a ``slope`` (grade,
        rise over run) rising towards ``slope_direction`` (rad from +x, the walker's initial facing, towards +y, its
        left), and ``gravity`` times the model's gravity."""
        key = (friction, slope, slope_direction if slope else 0.0, gravity)
        if key not in self._models:
            self._models[key] = self._on_ground(friction, slope, slope_direction, gravity)
        return Sims(self._models[key], n)

    def _on_ground(self, friction: float | None, slope: float, slope_direction: float,
                   gravity: float) -> mujoco.MjModel:
        if friction is None and not slope and gravity == 1.0:
            return self.model
        model = copy.deepcopy(self.model)
        if friction is not None:
            if self.body.floor_geom is None:
                raise ConfigError(f"body {self.body.name!r} has no MuJoCo ground whose friction a trial could change")
            model.geom_friction[model.geom(self.body.floor_geom).id, 0] = friction
        if gravity != 1.0:
            model.opt.gravity[:] = gravity * self.model.opt.gravity
        if slope:  # an inclined plane: gravity tilted down the slope, away from where the floor rises
            g = float(np.linalg.norm(model.opt.gravity))
            a = np.arctan(slope)
            # exact on the axes
            c, s = (0.0 if abs(v) < 1e-12 else float(v) for v in (np.cos(slope_direction), np.sin(slope_direction)))
            model.opt.gravity[:] = (-g * np.sin(a) * c, -g * np.sin(a) * s if s else 0.0, -g * np.cos(a))
        return model
