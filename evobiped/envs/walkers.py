"""The bipeds as Gymnasium environments: one walker (``gymnasium.Env``) or a batch (``VectorEnv``).

Both are views of :class:`Walkers`, ``n`` simulations of one body in a
:class:`~evobiped.sim.Sims` batch (``mujoco.batch``): an action sets the
actuators, the body advances one control period in C (custom forces, such as
the Taga ground, before every physics step), and the observation is the body's
own sensors.  The vector environment steps its whole batch in one call, and row
i of it follows exactly the trajectory of a single environment seeded with
``seed + i``.
"""

from __future__ import annotations

import math
from typing import Any, ClassVar

import gymnasium
import mujoco
import numpy as np
from gymnasium import spaces
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from ..bodies import BODIES
from ..errors import ConfigError
from ..glbackend import no_backend_message
from ..sim import Sims

_HINGE = int(mujoco.mjtJoint.mjJNT_HINGE)


class Walkers:
    """``n`` walkers of body ``body`` stepped together: physics, observation, reward, episode ends.

    Rows are independent: row i's trajectory depends only on its actions and its reset noise.
    """

    def __init__(self, body: str, n: int, *, seconds: float, control_dt: float, alive_bonus: float,
                 reset_noise_scale: float, body_options: dict[str, Any]):
        self.body = BODIES[body](**body_options)  # ConfigError naming the option
        for name, v, ok in (("seconds", seconds, seconds > 0), ("control_dt", control_dt, control_dt > 0),
                            ("reset_noise_scale", reset_noise_scale, reset_noise_scale >= 0)):
            if not (isinstance(v, (int, float)) and math.isfinite(v) and ok):
                raise ConfigError(f"{body} biped environment: bad {name} {v!r}")
        if not (isinstance(alive_bonus, (int, float)) and math.isfinite(alive_bonus)):
            raise ConfigError(f"{body} biped environment: bad alive_bonus {alive_bonus!r}")
        ratio = control_dt / self.body.timestep
        if abs(ratio - round(ratio)) > 1e-9 or round(ratio) < 1:
            raise ConfigError(f"control_dt {control_dt} s is not a multiple of the physics step {self.body.timestep} s")
        self.n, self.substeps = int(n), int(round(ratio))
        self.control_dt, self.seconds = float(control_dt), float(seconds)
        self.max_steps = int(round(seconds / control_dt))
        self.alive_bonus, self.noise = float(alive_bonus), float(reset_noise_scale)
        self.model = self.body.build_model()
        self.sims = Sims(self.model, self.n)
        self.low, self.high = self.body.action_bounds()
        m = self.model
        self._hinges = m.jnt_qposadr[m.jnt_type == _HINGE]  # reset noise goes on these joint angles
        self.body.reset(self.sims)
        self.sensor_names = tuple(self.body.sensors(self.sims))
        self.sensor_widths = tuple(a.shape[1] for a in self.body.sensors(self.sims).values())
        self.steps = np.zeros(self.n, int)
        self.position = np.zeros((self.n, 2))
        self.facing = np.zeros((self.n, 2))

    @property
    def obs_size(self) -> int:
        return sum(self.sensor_widths)

    def reset(self, ids: np.ndarray, rngs: list[np.random.Generator]) -> None:
        """Rows ``ids`` to the body's initial state, each hinge angle moved by U(-s, s) rad drawn from ``rngs[i]``."""
        self.body.reset(self.sims, ids)
        if self.noise > 0:
            for i in ids:
                self.sims.qpos[i, self._hinges] += rngs[i].uniform(-self.noise, self.noise, len(self._hinges))
            self.sims.forward(ids)
        self.steps[ids] = 0
        self.position[ids] = self.body.planar_position(self.sims)[ids]
        self.facing[ids] = self.body.heading(self.sims)[ids]

    def step(self, ids: np.ndarray, action: np.ndarray):
        """Rows ``ids`` take ``action`` ``(len(ids), n_act)`` (clipped to the bounds) for one control period.

        Returns ``(reward, terminated, truncated, unstable)``, each ``(len(ids),)``.
        """
        self.body.apply(self.sims, ids, np.clip(action, self.low, self.high))
        unstable = self.body.advance(self.sims, ids, self.substeps)
        self.steps[ids] += 1
        now = self.body.planar_position(self.sims)[ids]
        progress = np.einsum("pi,pi->p", now - self.position[ids], self.facing[ids])
        self.position[ids] = now
        terminated = unstable | self.body.fallen(self.sims, ids)
        reward = np.where(unstable, 0.0, progress + self.alive_bonus * ~terminated)
        truncated = ~terminated & (self.steps[ids] >= self.max_steps)
        return reward, terminated, truncated, unstable

    def observe(self) -> np.ndarray:
        """``(n, obs_size)``: the body's sensors, concatenated in :attr:`sensor_names` order (blown-up rows: 0)."""
        obs = np.concatenate(list(self.body.sensors(self.sims).values()), axis=1)
        return obs if np.isfinite(obs).all() else np.nan_to_num(obs, nan=0.0, posinf=0.0, neginf=0.0)

    def check_action(self, action, shape: tuple[int, ...]) -> np.ndarray:
        """The action as a float array of ``shape``; ValueError (one line) for a wrong shape or a non-finite value."""
        try:
            a = np.asarray(action, dtype=float)
        except (TypeError, ValueError):
            raise ValueError(f"action must be a float array of shape {shape}, got {type(action).__name__}") from None
        if a.shape != shape:
            raise ValueError(f"action must have shape {shape}, got {a.shape}")
        if not np.isfinite(a).all():
            raise ValueError("action contains NaN or infinity")
        return a

    def spaces(self) -> tuple[spaces.Box, spaces.Box]:
        obs = spaces.Box(-np.inf, np.inf, (self.obs_size,), np.float64)
        act = spaces.Box(self.low.astype(np.float32), self.high.astype(np.float32), dtype=np.float32)
        return obs, act


class Camera:
    """``rgb_array`` frames of one walker through ``mujoco.Renderer``, the camera following its centre of mass."""

    def __init__(self, walkers: Walkers, width: int, height: int, azimuth: float):
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


_OPTIONS_DOC = """
    ===================== =============== =====================================================
    option                default         meaning
    ===================== =============== =====================================================
    ``seconds``           50.0            episode length (s); truncated when reached
    ``control_dt``        {control_dt:<15} control period (s): one ``step`` = this much physics
    ``alive_bonus``       0.0             reward added per step while the walker is up
    ``reset_noise_scale`` 0.01            each hinge angle starts U(-s, s) rad off the initial pose
    ``render_mode``       None            None or ``"rgb_array"`` (needs an OpenGL context)
    ``width``, ``height`` 480, 480        rendered image size (pixels)
{body_rows}
    ===================== =============== =====================================================
"""


class BipedEnv(gymnasium.Env):
    """One walker of a body as a Gymnasium environment (subclasses fix the body)."""

    body_name: ClassVar[str]
    default_control_dt: ClassVar[float]
    #: degrees; 90 looks at the walker's left side
    camera_azimuth: ClassVar[float] = 90.0
    metadata = {"render_modes": ["rgb_array"], "render_fps": 50}

    def __init__(self, *, seconds: float = 50.0, control_dt: float | None = None, alive_bonus: float = 0.0,
                 reset_noise_scale: float = 0.01, render_mode: str | None = None, width: int = 480,
                 height: int = 480, **body_options):
        if render_mode not in (None, "rgb_array"):
            raise ConfigError(f"render_mode must be None or 'rgb_array', got {render_mode!r}")
        dt = self.default_control_dt if control_dt is None else control_dt
        self.walkers = Walkers(self.body_name, 1, seconds=seconds, control_dt=dt, alive_bonus=alive_bonus,
                               reset_noise_scale=reset_noise_scale, body_options=body_options)
        self.observation_space, self.action_space = self.walkers.spaces()
        self.metadata = dict(self.metadata, render_fps=round(1 / self.walkers.control_dt))
        self.render_mode = render_mode
        self._camera = Camera(self.walkers, width, height, self.camera_azimuth) if render_mode == "rgb_array" else None
        self._ids = np.zeros(1, int)
        self._done = True

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        super().reset(seed=seed)
        if options:
            raise ConfigError(f"reset takes no options, got {sorted(options)}")
        self.walkers.reset(self._ids, [self.np_random])
        self._done = False
        return self.walkers.observe()[0], {}

    def step(self, action):
        a = self.walkers.check_action(action, self.action_space.shape)
        if self._done:
            raise RuntimeError("step() after the episode ended: call reset() first")
        reward, terminated, truncated, unstable = self.walkers.step(self._ids, a[None])
        self._done = bool(terminated[0] or truncated[0])
        info = {"unstable": bool(unstable[0]), "position": self.walkers.position[0].copy()}
        return self.walkers.observe()[0], float(reward[0]), bool(terminated[0]), bool(truncated[0]), info

    def render(self):
        return None if self._camera is None else self._camera.frame(0)

    def close(self):
        if self._camera is not None:
            self._camera.close()
            self._camera = None


class BipedVectorEnv(VectorEnv):
    """``num_envs`` walkers of a body stepped as one ``mujoco.batch`` (subclasses fix the body).

    Next-step autoreset: the step after a walker's episode ends resets it (its action is
    ignored; reward 0, neither terminated nor truncated).  Row i matches a single environment
    seeded with ``seed + i``.
    """

    body_name: ClassVar[str]
    default_control_dt: ClassVar[float]
    #: degrees; 90 looks at the walker's left side
    camera_azimuth: ClassVar[float] = 90.0
    metadata = {"render_modes": ["rgb_array"], "render_fps": 50, "autoreset_mode": AutoresetMode.NEXT_STEP}

    def __init__(self, num_envs: int = 1, *, seconds: float = 50.0, control_dt: float | None = None,
                 alive_bonus: float = 0.0, reset_noise_scale: float = 0.01, render_mode: str | None = None,
                 width: int = 480, height: int = 480, **body_options):
        if not (isinstance(num_envs, int) and num_envs >= 1):
            raise ConfigError(f"num_envs must be an integer >= 1, got {num_envs!r}")
        if render_mode not in (None, "rgb_array"):
            raise ConfigError(f"render_mode must be None or 'rgb_array', got {render_mode!r}")
        dt = self.default_control_dt if control_dt is None else control_dt
        self.walkers = Walkers(self.body_name, num_envs, seconds=seconds, control_dt=dt, alive_bonus=alive_bonus,
                               reset_noise_scale=reset_noise_scale, body_options=body_options)
        self.num_envs = num_envs
        self.single_observation_space, self.single_action_space = self.walkers.spaces()
        self.observation_space = batch_space(self.single_observation_space, num_envs)
        self.action_space = batch_space(self.single_action_space, num_envs)
        self.metadata = dict(self.metadata, render_fps=round(1 / self.walkers.control_dt))
        self.render_mode = render_mode
        self._camera = Camera(self.walkers, width, height, self.camera_azimuth) if render_mode == "rgb_array" else None
        self._rngs: list[np.random.Generator] | None = None
        self._all = np.arange(num_envs)
        self._needs_reset = np.zeros(num_envs, bool)

    def reset(self, *, seed: int | list[int] | None = None, options: dict | None = None):
        if options:
            raise ConfigError(f"reset takes no options, got {sorted(options)}")
        if seed is None or isinstance(seed, int):
            seeds = [None if seed is None else seed + i for i in range(self.num_envs)]
        else:
            seeds = list(seed)
            if len(seeds) != self.num_envs:
                raise ConfigError(f"reset needs one seed per environment ({self.num_envs}), got {len(seeds)}")
        if self._rngs is None or seed is not None:
            self._rngs = [seeding.np_random(s)[0] for s in seeds]
        self.walkers.reset(self._all, self._rngs)
        self._needs_reset[:] = False
        return self.walkers.observe(), {}

    def step(self, actions):
        a = self.walkers.check_action(actions, self.action_space.shape)
        if self._rngs is None:
            raise RuntimeError("step() before reset(): call reset() first")
        n = self.num_envs
        reward, terminated, truncated = np.zeros(n), np.zeros(n, bool), np.zeros(n, bool)
        unstable = np.zeros(n, bool)
        resetting = np.flatnonzero(self._needs_reset)
        going = self._all if resetting.size == 0 else np.flatnonzero(~self._needs_reset)
        if going.size:
            r, te, tr, un = self.walkers.step(going, a[going])
            reward[going], terminated[going], truncated[going], unstable[going] = r, te, tr, un
        if resetting.size:
            self.walkers.reset(resetting, self._rngs)
        self._needs_reset = terminated | truncated
        every = np.ones(n, bool)  # Gymnasium's vector info convention: "_key" marks the rows that have "key"
        info = {"unstable": unstable, "_unstable": every, "position": self.walkers.position.copy(), "_position": every}
        return self.walkers.observe(), reward, terminated, truncated, info

    def render(self):
        return None if self._camera is None else tuple(self._camera.frame(i) for i in range(self.num_envs))

    def close_extras(self, **kwargs):
        if self._camera is not None:
            self._camera.close()
            self._camera = None


_REIL_ROWS = """\
    ``timestep``          0.005           physics step (s)
    ``kp``, ``kv``        50.0, 2.0       PD gains (N m/rad, N m s/rad)
    ``fall_height``       0.5             fallen when the centre of mass is below this (m)
    ``fall_tilt``         pi/2            ... or the pelvis is tilted beyond this (rad)
    ``inertia``           "geoms"         link inertias: "geoms" or "karma"
    ``model_file``        None            another MJCF file with the same joints"""

_TAGA_ROWS = """\
    ``timestep``          0.0005          physics step (s)
    ``kg``, ``bg``        1e4, 1e3        ground stiffness (N/m) and damping (N s/m)
    ``slope``             0.0             terrain slope (rise / run) beyond ``slope_start``
    ``slope_start``       0.0             where the slope begins (m along x)
    ``max_torque``        2000.0          action bound: joint torques in +-this (N m)
    ``fall_height``       0.7             fallen when the hip is below this above the terrain (m)
    ``model_file``        None            another MJCF file with the same joints"""

_REIL_DOC = """Reil & Husbands' 3D biped: PD target angles in, the body's sensors out.

    Observation ``(24,)`` float64: joint angles (6, rad) and velocities (6, rad/s) in
    action order, foot contacts (2: left, right; 0/1), pelvis tilt (2: pitch, roll; rad)
    and its rates (2, rad/s), centre of mass minus each foot (4: forward, left; m) and
    the centre of mass's velocity (2: forward, left; m/s), in the heading frame.
    Action ``(6,)``: PD target angles (rad) of left hip pitch, left hip roll, left knee,
    right hip pitch, right hip roll, right knee, in Table II's ranges (hip pitch
    [-1.3, 1.6], hip roll [-0.8, 0.8], knee [-1.4, 0]); values outside are clipped.
    Reward: forward progress of the pelvis (m) along the direction the walker faced at
    reset, plus ``alive_bonus`` per step while it is up.  Terminated when it falls (or
    the simulation blows up: ``info["unstable"]``); truncated at ``seconds``.

    Options (keyword arguments; the body's own after the first six):
""" + _OPTIONS_DOC.format(control_dt=0.02, body_rows=_REIL_ROWS)

_TAGA_DOC = """Taga, Yamaguchi & Shimizu's sagittal 5-link biped: joint torques in, its sensors out.

    Observation ``(14,)`` float64: inertial link angles of right thigh, right shank, left
    thigh, left shank (4, rad from the horizontal) and their rates (4, rad/s), ground
    contacts (2: right, left; 0/1) and ground forces F_g1..F_g4 (4, N).
    Action ``(6,)``: torques (N m) of right hip, knee, ankle and left hip, knee, ankle,
    within +-``max_torque`` (clipped); the ankle torques act only while that foot is on the
    ground.  The Appendix A ground and joint forces are added before every physics step.
    Reward: forward progress of the hip (m) along +x, plus ``alive_bonus`` per step while
    it is up.  Terminated when the hip falls below ``fall_height`` (or the simulation blows
    up); truncated at ``seconds``.

    Options (keyword arguments; the body's own after the first six):
""" + _OPTIONS_DOC.format(control_dt=0.01, body_rows=_TAGA_ROWS)


class ReilBipedEnv(BipedEnv):
    __doc__ = _REIL_DOC
    body_name = "reil"
    default_control_dt = 0.02
    camera_azimuth = 135.0


class TagaBipedEnv(BipedEnv):
    __doc__ = _TAGA_DOC
    body_name = "taga"
    default_control_dt = 0.01


class ReilBipedVectorEnv(BipedVectorEnv):
    __doc__ = _REIL_DOC.replace("Options (keyword", "Vector form: ``num_envs`` walkers stepped in one ``mujoco.batch`` call\n    (next-step autoreset).  Options (keyword")
    body_name = "reil"
    default_control_dt = 0.02
    camera_azimuth = 135.0


class TagaBipedVectorEnv(BipedVectorEnv):
    __doc__ = _TAGA_DOC.replace("Options (keyword", "Vector form: ``num_envs`` walkers stepped in one ``mujoco.batch`` call\n    (next-step autoreset).  Options (keyword")
    body_name = "taga"
    default_control_dt = 0.01
