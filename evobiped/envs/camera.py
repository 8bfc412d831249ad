"""``rgb_array`` frames of a Gymnasium environment's walkers (``mujoco.Renderer``, offscreen)."""

from __future__ import annotations

import mujoco
import numpy as np

from ..core.errors import ConfigError
from ..core.glbackend import no_backend_message
from .walkers import Walkers


class Camera:
    """``rgb_array`` frames of one walker through ``mujoco.Renderer``, the camera following its centre of mass."""

    def __init__(self, walkers: Walkers, width: int, height: int, azimuth: float):
        """``width`` x ``height`` pixels; ``azimuth`` degrees (90 looks at the walker's left side)."""
        self.walkers = walkers
        try:
            self.renderer = mujoco.Renderer(walkers.model, height=int(height), width=int(width))
        except Exception as exc:  # mujoco.FatalError, ValueError (size beyond the offscreen buffer), ...
            raise ConfigError(f"rgb_array: {no_backend_message(exc)}") from None
        self.data = mujoco.MjData(walkers.model)
        self.camera = mujoco.MjvCamera()
        self.camera.type = mujoco.mjtCamera.mjCAMERA_FREE
        self.camera.distance, self.camera.azimuth, self.camera.elevation = 3.0, azimuth, -15.0

    def frame(self, row: int) -> np.ndarray:
        """``(height, width, 3)`` uint8 image of walker ``row``."""
        w, d = self.walkers, self.data
        d.qpos[:], d.qvel[:] = w.sims.qpos[row], w.sims.qvel[row]
        mujoco.mj_forward(w.model, d)
        self.camera.lookat[:] = w.body.com(w.sims)[row]
        self.renderer.update_scene(d, self.camera)
        return self.renderer.render().copy()

    def close(self) -> None:
        self.renderer.close()
