"""The bipeds as Gymnasium environments: one walker (``gymnasium.Env``) or a batch (``VectorEnv``).

Both are views of :class:`~evobiped.envs.walkers.Walkers`: an episode without a controller, built by
:class:`~evobiped.episode.EpisodeConfig` from the keyword arguments and stepped one control tick at a time (the
reward is the increment of the task's fitness, ``info`` carries the task's terms).  The vector environment steps
its whole batch in one call, and row i of it follows exactly the trajectory of a single environment seeded with
``seed + i``.
"""

from __future__ import annotations

from typing import ClassVar

import gymnasium
import numpy as np
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from ..bodies import BODIES
from ..core.errors import ConfigError
from ..core.options import markdown_table
from .camera import Camera
from .walkers import EnvOptions, Walkers, env_config


def _walkers(cls, n: int, kwargs: dict) -> tuple[Walkers, EnvOptions]:
    """The walkers of environment class ``cls`` from its keyword arguments (EnvOptions', then the body's)."""
    config, options = env_config(cls.body_name, cls.default_control_dt, kwargs, f"{cls.body_name} biped environment")
    return Walkers(config, n, options.reset_noise_scale), options


def _doc(summary: str, body: str) -> str:
    """An environment's docstring: ``summary``, then the generated tables of its options and its body's."""
    return (summary + "\n\n    Options (keyword arguments; the body's own beside them):\n\n"
            + markdown_table(EnvOptions) + "\n    The body's options:\n\n" + markdown_table(BODIES[body].Options))


class BipedEnv(gymnasium.Env):
    """One walker of a body as a Gymnasium environment (subclasses fix the body)."""

    body_name: ClassVar[str]
    default_control_dt: ClassVar[float]
    #: degrees; 90 looks at the walker's left side
    camera_azimuth: ClassVar[float] = 90.0
    metadata = {"render_modes": ["rgb_array"], "render_fps": 50}

    def __init__(self, **options):
        self.walkers, o = _walkers(type(self), 1, options)
        self.observation_space, self.action_space = self.walkers.spaces()
        self.metadata = dict(self.metadata, render_fps=round(1 / self.walkers.control_dt))
        self.render_mode = o.render_mode
        self._camera = Camera(self.walkers, o.width, o.height, self.camera_azimuth) if o.render_mode else None
        self._ids = np.zeros(1, int)

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        super().reset(seed=seed)
        if options:
            raise ConfigError(f"reset takes no options, got {sorted(options)}")
        self.walkers.reset(self._ids, [self.np_random])
        return self.walkers.observe()[0], {}

    def step(self, action):
        a = self.walkers.check_action(action, self.action_space.shape)
        if self.walkers.ended[0]:
            raise RuntimeError("step() after the episode ended: call reset() first")
        reward, terminated, truncated, _ = self.walkers.step(self._ids, a[None])
        info = {k: (v[0].copy() if v.ndim > 1 else v[0].item()) for k, v in self.walkers.info().items()}
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

    def __init__(self, num_envs: int = 1, **options):
        if not (isinstance(num_envs, int) and num_envs >= 1):
            raise ConfigError(f"num_envs must be an integer >= 1, got {num_envs!r}")
        self.walkers, o = _walkers(type(self), num_envs, options)
        self.num_envs = num_envs
        self.single_observation_space, self.single_action_space = self.walkers.spaces()
        self.observation_space = batch_space(self.single_observation_space, num_envs)
        self.action_space = batch_space(self.single_action_space, num_envs)
        self.metadata = dict(self.metadata, render_fps=round(1 / self.walkers.control_dt))
        self.render_mode = o.render_mode
        self._camera = Camera(self.walkers, o.width, o.height, self.camera_azimuth) if o.render_mode else None
        self._all = np.arange(num_envs)

    def reset(self, *, seed: int | list[int] | None = None, options: dict | None = None):
        if options:
            raise ConfigError(f"reset takes no options, got {sorted(options)}")
        if seed is None or isinstance(seed, int):
            seeds = [None if seed is None else seed + i for i in range(self.num_envs)]
        else:
            seeds = list(seed)
            if len(seeds) != self.num_envs:
                raise ConfigError(f"reset needs one seed per environment ({self.num_envs}), got {len(seeds)}")
        fresh = self.walkers.state is None or seed is not None  # else each row's generator goes on
        self.walkers.reset(self._all, [seeding.np_random(s)[0] for s in seeds] if fresh else None)
        return self.walkers.observe(), {}

    def step(self, actions):
        a = self.walkers.check_action(actions, self.action_space.shape)
        if self.walkers.state is None:
            raise RuntimeError("step() before reset(): call reset() first")
        n = self.num_envs
        reward, terminated, truncated = np.zeros(n), np.zeros(n, bool), np.zeros(n, bool)
        ended = self.walkers.ended
        resetting = np.flatnonzero(ended)
        going = self._all if resetting.size == 0 else np.flatnonzero(~ended)
        if going.size:
            r, te, tr, _ = self.walkers.step(going, a)
            reward[going], terminated[going], truncated[going] = r, te, tr
        if resetting.size:
            self.walkers.reset(resetting)
        every = np.ones(n, bool)  # Gymnasium's vector info convention: "_key" marks the rows that have "key"
        info = {}
        for k, v in self.walkers.info().items():
            info[k], info[f"_{k}"] = v, every
        return self.walkers.observe(), reward, terminated, truncated, info

    def render(self):
        return None if self._camera is None else tuple(self._camera.frame(i) for i in range(self.num_envs))

    def close_extras(self, **kwargs):
        if self._camera is not None:
            self._camera.close()
            self._camera = None


_REIL = """Reil & Husbands' 3D biped: PD target angles in, the body's sensors out.

    Observation ``(26,)`` float64, in this order: ``joint_angles`` (6, rad) and
    ``joint_velocities`` (6, rad/s) in action order, ``foot_contact`` (2: left, right;
    0/1), ``pelvis_tilt`` (2: pitch, roll; rad) and ``pelvis_tilt_rate`` (2, rad/s),
    ``com_from_feet`` (4: centre of mass minus the left foot, forward and left, then minus
    the right foot; m) and ``com_velocity`` (2: forward, left; m/s), in the heading frame;
    the gait senses ``stance_leg`` (1: +1 while the left leg stands, -1 the right) and
    ``since_touchdown`` (1: s since the stance leg's touchdown, capped at 2 s); then the
    task's sensors, if it has any (docs/gym.md has the indices).
    Action ``(6,)``: PD target angles (rad) of left hip pitch, left hip roll, left knee,
    right hip pitch, right hip roll, right knee, in Table II's ranges (hip pitch
    [-1.3, 1.6], hip roll [-0.8, 0.8], knee [-1.4, 0]); values outside are clipped.
    Reward: the increment of the task's fitness over the step (by default the walk task's
    forward fitness: forward progress of the pelvis, m, along the direction the walker faced
    at reset, and at a fall the survival credit it lost); ``info`` has the fitness and the
    task's terms.  Terminated when it falls (or the simulation blows up:
    ``info["unstable"]``); truncated at ``seconds``."""

_TAGA = """Taga, Yamaguchi & Shimizu's sagittal 5-link biped: joint torques in, its sensors out.

    Observation ``(14,)`` float64, in this order: ``link_angles`` (4: inertial angles of
    right thigh, right shank, left thigh, left shank; rad from the horizontal),
    ``link_velocities`` (4: their rates, rad/s), ``ground_contact`` (2: right, left; 0/1)
    and ``ground_force`` (4: F_g1..F_g4, N).
    Action ``(6,)``: torques (N m) of right hip, knee, ankle and left hip, knee, ankle,
    within +-``max_torque`` (clipped); the ankle torques act only while that foot is on the
    ground.  The Appendix A ground and joint forces are added before every physics step.
    Reward: the increment of the task's fitness over the step (by default forward progress
    of the hip, m, along +x, and at a fall the survival credit lost); ``info`` has the
    fitness and the task's terms.  Terminated when the hip falls below ``fall_height`` (or
    the simulation blows up); truncated at ``seconds``."""

_VECTOR = ("\n\n    Vector form: ``num_envs`` walkers stepped in one ``mujoco.batch`` call (next-step autoreset).")


class ReilBipedEnv(BipedEnv):
    __doc__ = _doc(_REIL, "reil")
    body_name = "reil"
    default_control_dt = 0.02
    camera_azimuth = 135.0


class TagaBipedEnv(BipedEnv):
    __doc__ = _doc(_TAGA, "taga")
    body_name = "taga"
    default_control_dt = 0.01


class ReilBipedVectorEnv(BipedVectorEnv):
    __doc__ = _doc(_REIL + _VECTOR, "reil")
    body_name = "reil"
    default_control_dt = 0.02
    camera_azimuth = 135.0


class TagaBipedVectorEnv(BipedVectorEnv):
    __doc__ = _doc(_TAGA + _VECTOR, "taga")
    body_name = "taga"
    default_control_dt = 0.01
