"""The bipeds as Gymnasium environments: one walker (``gymnasium.Env``) or a batch (``VectorEnv``).

Both are views of :class:`Walkers`: an :class:`~evobiped.episode.Episode` without a controller,
``n`` simulations of one body and a task, stepped one control tick at a time by
:meth:`Episode.step <evobiped.episode.Episode.step>` (the loop every evolution and experiment
uses: the body's actions, custom forces such as the Taga ground before every physics step,
the task's bookkeeping, the fall test).  The reward is the increment of the task's fitness
over the step, and ``info`` carries the task's named terms.  The vector environment steps its
whole batch in one call, and row i of it follows exactly the trajectory of a single
environment seeded with ``seed + i``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

import gymnasium
import mujoco
import numpy as np
from gymnasium import spaces
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from ..bodies import BODIES
from ..episode import Episode, EpisodeState
from ..errors import ConfigError
from ..glbackend import no_backend_message
from ..options import markdown_table, option, parse
from ..tasks import TASKS

_HINGE = int(mujoco.mjtJoint.mjJNT_HINGE)


@dataclass(frozen=True, kw_only=True)
class EnvOptions:
    """Options of the Gymnasium environments (keyword arguments; the body's own options beside them)."""

    seconds: float = option(50.0, "episode length; truncated when reached", unit="s", above=0)
    control_dt: float | None = option(None, "control period: one step is this much physics (none: the environment's, "
                                      "0.02 s for Reil, 0.01 s for Taga); a multiple of the body's physics step",
                                      unit="s", above=0)
    reset_noise_scale: float = option(0.01, "each hinge angle starts U(-s, s) off the body's initial pose", unit="rad", low=0)
    task: str = option("walk", "the task whose fitness increments are the reward (its terms are in `info`)",
                       choices=tuple(TASKS))
    task_options: dict | None = option(None, "the task's options (its table); none: its defaults, but the walk task's "
                                       "`forward` fitness (forward progress per step; at a fall, the survival credit lost)")
    render_mode: str | None = option(None, "none, or `rgb_array` (needs an OpenGL context)", choices=(None, "rgb_array"))
    width: int = option(480, "rendered image width", unit="pixels", low=1, integer=True)
    height: int = option(480, "rendered image height", unit="pixels", low=1, integer=True)


class Walkers:
    """``n`` walkers of body ``body`` stepped together through one :class:`Episode` without controller:
    observation, reward (the task's fitness increments), episode ends.

    Rows are independent: row i's trajectory depends only on its actions and its reset noise.
    """

    def __init__(self, body: str, n: int, options: EnvOptions, body_options: dict[str, Any], default_control_dt: float):
        body_ = BODIES[body](**body_options)  # ConfigError naming the option
        task_options = options.task_options
        if task_options is None:
            task_options = {"fitness": "forward"} if options.task == "walk" else {}
        task = TASKS[options.task](**task_options)
        if task.reads_neurons():
            raise ConfigError(f"{options.task} task: these task options read a controller's neurons, "
                              "which an environment has not (its actions come from outside)")
        dt = default_control_dt if options.control_dt is None else options.control_dt
        self.episode = Episode(body_, None, task, seconds=options.seconds, control_dt=dt)
        self.n, self.noise = int(n), float(options.reset_noise_scale)
        self.body, self.model, self.substeps = body_, self.episode.model, self.episode.substeps
        self.control_dt = self.episode.control_dt
        self.low, self.high = self.episode.low, self.episode.high
        m = self.model
        self._hinges = m.jnt_qposadr[m.jnt_type == _HINGE]  # reset noise goes on these joint angles
        self.sensor_widths = {**body_.sensor_widths, **task.sensor_widths()}
        self.state: EpisodeState | None = None
        self.fitness = np.zeros(self.n)

    @property
    def sims(self):
        return self.state.sims

    @property
    def steps(self) -> np.ndarray:
        """Control ticks each row has taken since its reset ``(n,)``."""
        return self.state.ticks - self.state.born

    @property
    def obs_size(self) -> int:
        return sum(self.sensor_widths.values())

    def reset(self, ids: np.ndarray, rngs: list[np.random.Generator]) -> None:
        """Rows ``ids`` to the body's initial state, each hinge angle moved by U(-s, s) rad drawn from ``rngs[i]``."""

        def pose(sims, rows):
            if self.noise > 0:
                for i in rows:
                    sims.qpos[i, self._hinges] += rngs[i].uniform(-self.noise, self.noise, len(self._hinges))
                sims.forward(rows)

        if self.state is None:
            self.state = self.episode.start(self.n, pose=pose)
        else:
            self.episode.restart(self.state, ids, pose=pose)
        self.fitness[ids] = self.episode.task.fitness(self.state.task)[ids]

    def step(self, ids: np.ndarray, action: np.ndarray):
        """Rows ``ids`` take ``action`` ``(n, n_act)`` (clipped to the bounds; other rows' ignored) for one
        control period.  Returns ``(reward, terminated, truncated, unstable)``, each ``(len(ids),)``."""
        st, task = self.state, self.episode.task
        self.episode.step(st, np.clip(action, self.low, self.high), rows=ids)
        fitness = task.fitness(st.task)
        reward = fitness[ids] - self.fitness[ids]
        self.fitness[ids] = fitness[ids]
        terminated = st.fell[ids]
        truncated = ~terminated & (self.steps[ids] >= st.n_ticks)
        return reward, terminated, truncated, st.unstable[ids]

    def info(self) -> dict[str, np.ndarray]:
        """Per row: the task's fitness and terms (those these task options define: a term NaN on every row is
        left out), where the walker is ``(n, 2)`` m, whether it blew up."""
        st, ep = self.state, self.episode
        terms = {k: v for k, v in ep.task.terms(st.task).items() if not np.isnan(v).all()}
        return {"fitness": self.fitness.copy(), **terms, "position": ep.task.end_position(ep.body, st.sims, st.task).copy(),
                "unstable": st.unstable.copy()}

    def observe(self) -> np.ndarray:
        """``(n, obs_size)``: the body's sensors and the task's, in :attr:`sensor_widths` order (blown-up rows: 0)."""
        st, ep = self.state, self.episode
        found = {**ep.body.sensors(st.sims), **ep.task.sensors(ep.body, st.sims, st.task)}
        obs = np.concatenate([found[k] for k in self.sensor_widths], axis=1)
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


def _walkers(cls, n: int, kwargs: dict) -> tuple[Walkers, EnvOptions]:
    """The walkers of environment class ``cls`` from its keyword arguments (EnvOptions', then the body's)."""
    names = EnvOptions.__dataclass_fields__
    options = parse(EnvOptions, {k: v for k, v in kwargs.items() if k in names}, f"{cls.body_name} biped environment")
    body_options = {k: v for k, v in kwargs.items() if k not in names}
    return Walkers(cls.body_name, n, options, body_options, cls.default_control_dt), options


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
        reward, terminated, truncated, _ = self.walkers.step(self._ids, a[None])
        self._done = bool(terminated[0] or truncated[0])
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
        resetting = np.flatnonzero(self._needs_reset)
        going = self._all if resetting.size == 0 else np.flatnonzero(~self._needs_reset)
        if going.size:
            r, te, tr, _ = self.walkers.step(going, a)
            reward[going], terminated[going], truncated[going] = r, te, tr
        if resetting.size:
            self.walkers.reset(resetting, self._rngs)
        self._needs_reset = terminated | truncated
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
