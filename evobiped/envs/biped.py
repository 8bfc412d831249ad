"""The bipeds as Gymnasium environments: one walker (``gymnasium.Env``) or a batch (``VectorEnv``).

Both are views of :class:`~evobiped.envs.walkers.Walkers`: an episode without a controller, built by
:class:`~evobiped.episode.EpisodeConfig` from the keyword arguments and stepped one control tick at a time (the
reward is the increment of the task's fitness, ``info`` carries the task's terms).  The vector environment steps
its whole batch in one call, and row i of it follows exactly the trajectory of a single environment seeded with
``seed + i``.
"""

from __future__ import annotations

import textwrap
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
from ..physics import gait
from .walkers import EnvOptions, Walkers, env_config, env_name


def _walkers(cls, n: int, kwargs: dict) -> tuple[Walkers, EnvOptions]:
    """The walkers of environment class ``cls`` from its keyword arguments (EnvOptions', then the body's)."""
    config, options = env_config(cls.body_name, cls.default_control_dt, kwargs, f"{cls.body_name} biped environment")
    return Walkers(config, n, options.reset_noise_scale, options.actions), options


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


_VECTOR = ("\n\n    Vector form: ``num_envs`` walkers stepped in one ``mujoco.batch`` call (next-step autoreset).")


def _summary(body: str) -> str:
    """What an environment of registered body ``body`` is, from the body's declarations (its ``environment``, its
    sensors, its actuators), as docstring lines (the default walk task adds no sensor: no task is built here)."""
    cls = BODIES[body]
    parts = gait.by_default(cls.sensor_widths)
    listed = ", ".join(f"``{name}`` ({width}: {cls.sensor_text[name]})" for name, width in parts.items())
    return "\n    ".join(textwrap.wrap(
        f"Observation ``({sum(parts.values())},)`` float64, in this order: {listed}; then the task's sensors, if it "
        f"has any (docs/gym.md has the indices).  Action ``({len(cls.actuators)},)``: {cls.environment.action} "
        f"({', '.join(a.name for a in cls.actuators)}); values outside are clipped.  Reward: the increment of the "
        "task's fitness over the step (by default the walk task's forward fitness: forward progress, m, along the "
        "direction the walker faced at reset, and at a fall the survival credit it lost); ``info`` has the fitness "
        "and the task's terms.  Terminated when it falls (or the simulation blows up: ``info[\"unstable\"]``); "
        "truncated at ``seconds``.", 112)).join(
        (f"{cls.environment.about}: {'PD target angles' if cls.action_kind == 'position' else 'joint torques'} in, "
         "the body's sensors out.\n\n    ", ""))


#: body name -> its environment classes (one walker, the vector form), made once
_CLASSES: dict[str, tuple[type[BipedEnv], type[BipedVectorEnv]]] = {}


def env_classes(body: str) -> tuple[type[BipedEnv], type[BipedVectorEnv]]:
    """The environment classes of registered body ``body`` (one walker, the vector form), made once from its
    declarations: ``<Name>BipedEnv`` and ``<Name>BipedVectorEnv`` (:func:`~evobiped.envs.walkers.env_name`)."""
    if body not in _CLASSES:
        spec, name = BODIES[body].environment, env_name(body)
        fixed = dict(body_name=body, default_control_dt=spec.control_dt, camera_azimuth=spec.camera_azimuth,
                     __module__=__name__)
        _CLASSES[body] = (
            type(f"{name}Env", (BipedEnv,), dict(fixed, __qualname__=f"{name}Env", __doc__=_doc(_summary(body), body))),
            type(f"{name}VectorEnv", (BipedVectorEnv,),
                 dict(fixed, __qualname__=f"{name}VectorEnv", __doc__=_doc(_summary(body) + _VECTOR, body))))
    return _CLASSES[body]


def __getattr__(attr: str):
    """``ReilBipedEnv``, ``TagaBipedVectorEnv``, ...: the environment classes of every registered body with an
    environment (so that Gymnasium's entry points and pickles find them by name)."""
    for body, cls in BODIES.items():
        if cls.environment is not None and attr in (f"{env_name(body)}Env", f"{env_name(body)}VectorEnv"):
            return env_classes(body)[attr.endswith("VectorEnv")]
    raise AttributeError(f"module {__name__!r} has no attribute {attr!r}")
