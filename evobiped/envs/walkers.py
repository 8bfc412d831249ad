"""The walkers behind the Gymnasium environments: an episode without a controller, stepped by outside actions.

:class:`Walkers` is ``n`` simulations of one body and a task through one :class:`~evobiped.episode.Episode`
built by :meth:`EpisodeConfig.build <evobiped.episode.EpisodeConfig.build>` (the path every episode is built by;
its options parsed once, the task checked against an episode without a controller), stepped one control tick at
a time by :meth:`Episode.step <evobiped.episode.Episode.step>`, the loop every evolution and experiment uses.
The reward is the increment of the task's fitness over the step, and ``info`` carries the task's named terms.
What an environment holds in progress is an :class:`EnvState`: the :class:`~evobiped.episode.EpisodeState` and what
only the environments keep per row beside it (the reward baseline, each row's reset-noise generator, which rows
ended).
"""

from __future__ import annotations

import copy
import re
from dataclasses import dataclass
from typing import Any

import mujoco
import numpy as np
from gymnasium import spaces

from ..bodies import BODIES
from ..episode import EpisodeConfig, EpisodeState
from ..episode.parts import parsed
from ..physics import gait
from ..core.options import option
from ..tasks import TASKS

_HINGE = int(mujoco.mjtJoint.mjJNT_HINGE)
#: the environments' action spaces (``EnvOptions.actions``)
ACTION_SPACES = ("native", "unit")


@dataclass(frozen=True, kw_only=True)
class EnvOptions:
    """Options of the Gymnasium environments (keyword arguments; the body's own options beside them).

    ``task_options`` is parsed when the options are (into the task's frozen ``Options``)."""

    seconds: float = option(50.0, "episode length; truncated when reached", unit="s", above=0)
    control_dt: float | None = option(None, "control period: one step is this much physics (none: the one the body "
                                      "declares for its environment, docs/gym.md); a multiple of the body's physics "
                                      "step",
                                      unit="s", above=0)
    reset_noise_scale: float = option(0.01, "each hinge angle starts U(-s, s) off the body's initial pose", unit="rad",
                                      low=0)
    actions: str = option("native", "the action space: `native` (the body's own units and bounds: rad targets or N m "
                          "torques) or `unit` (each action in [-1, 1], mapped linearly onto the body's bounds: what RL "
                          "libraries expect)", choices=ACTION_SPACES)
    task: str = option("walk", "the task whose fitness increments are the reward (its terms are in `info`)",
                       choices=TASKS)  # the registry itself: a task registered later counts
    task_options: Any = option(None, "the task's options (its table); none: its defaults, but the walk task's "
                               "`forward` fitness (forward progress per step; at a fall, the survival credit lost)")
    render_mode: str | None = option(None, "none, or `rgb_array` (needs an OpenGL context)",
                                     choices=(None, "rgb_array"))
    width: int = option(480, "rendered image width", unit="pixels", low=1, integer=True)
    height: int = option(480, "rendered image height", unit="pixels", low=1, integer=True)

    def __post_init__(self):
        table = self.task_options
        if table is None:
            table = {"fitness": "forward"} if self.task == "walk" else {}
        object.__setattr__(self, "task_options", parsed(TASKS[self.task].Options, table, "task_options"))


def env_name(body: str) -> str:
    """The name of registered body ``body``'s environment: ``"reil"`` -> ``"ReilBiped"`` (``evobiped/ReilBiped-v0``)."""
    return "".join(part.title() for part in re.split(r"[-_]", body)) + "Biped"


def env_id(body: str) -> str:
    """The Gymnasium id of registered body ``body``'s environment, ``evobiped/<env_name>-v0``."""
    return f"evobiped/{env_name(body)}-v0"


def observation(body: str, task: str = "walk") -> dict[str, int]:
    """The parts of an environment's observation in order (name -> width): the body's sensors, then the task's
    under its default options (those read only on request left out, as the environment does)."""
    return gait.by_default({**BODIES[body].sensor_widths, **TASKS[task]().sensor_widths()})


def env_config(body: str, default_control_dt: float, kwargs: dict, where: str) -> tuple[EpisodeConfig, EnvOptions]:
    """The episode of an environment of ``body`` from its keyword arguments (:class:`EnvOptions`', then the body's),
    and those options; one ConfigError line for a bad one."""
    names = EnvOptions.__dataclass_fields__
    options = parsed(EnvOptions, {k: v for k, v in kwargs.items() if k in names}, where)
    config = EpisodeConfig(body=body, controller=None, task=options.task, seconds=options.seconds,
                           body_options={k: v for k, v in kwargs.items() if k not in names},
                           task_options=options.task_options,
                           control_dt=default_control_dt if options.control_dt is None else options.control_dt)
    config.check()
    return config, options


@dataclass(eq=False)
class EnvState:
    """An environment's episode in progress, a value: the episode's state, and per row ``(n,)`` the task's fitness
    when the row last stepped or began (the reward baseline: a reward is its increment), the generator of the row's
    reset noise, and whether its episode ended and waits for a reset."""

    episode: EpisodeState
    fitness: np.ndarray
    ended: np.ndarray
    rngs: list[np.random.Generator]

    def copy(self) -> "EnvState":
        """An independent state equal to this one (the episode's, the generators)."""
        return copy.deepcopy(self)


class Walkers:
    """``n`` walkers of ``config``'s body (an episode without controller) stepped together: observation, reward (the
    task's fitness increments), episode ends.

    Rows are independent: row i's trajectory depends only on its actions and its reset noise.
    """

    def __init__(self, config: EpisodeConfig, n: int, reset_noise_scale: float, actions: str = "native"):
        """``actions``: one of :data:`ACTION_SPACES`: the space :meth:`step`'s actions are in."""
        self.config, self.actions = config, actions
        self.episode = config.build()
        self.n, self.noise = int(n), float(reset_noise_scale)
        self.body, self.model = self.episode.body, self.episode.model
        self.control_dt = self.episode.control_dt
        self.low, self.high = self.episode.low, self.episode.high
        m = self.model
        self._hinges = m.jnt_qposadr[m.jnt_type == _HINGE]  # reset noise goes on these joint angles
        #: the observation's senses: the body's and the task's, less those read only on request
        self.sensor_widths = gait.by_default({**self.body.sensor_widths, **self.episode.task.sensor_widths()})
        #: the episode in progress (None before the first reset)
        self.state: EnvState | None = None

    @property
    def sims(self):
        return self.state.episode.sims

    @property
    def steps(self) -> np.ndarray:
        """Control ticks each row has taken since its reset ``(n,)``."""
        st = self.state.episode
        return st.ticks - st.born

    @property
    def ended(self) -> np.ndarray:
        """Rows whose episode ended and that wait for a reset ``(n,)`` (all before the first reset)."""
        return np.ones(self.n, bool) if self.state is None else self.state.ended

    @property
    def obs_size(self) -> int:
        return sum(self.sensor_widths.values())

    def reset(self, ids: np.ndarray, rngs: list[np.random.Generator] | None = None) -> None:
        """Rows ``ids`` to the body's initial state, each hinge angle of row i moved by U(-s, s) rad drawn from its
        generator: ``rngs[i]`` (kept from now on), else the one kept."""
        if rngs is None:
            rngs = self.state.rngs

        def pose(sims, rows):
            if self.noise > 0:
                for i in rows:
                    sims.qpos[i, self._hinges] += rngs[i].uniform(-self.noise, self.noise, len(self._hinges))
                sims.forward(rows)

        if self.state is None:
            self.state = EnvState(self.episode.start(self.n, pose=pose), np.zeros(self.n), np.zeros(self.n, bool), rngs)
        else:
            self.episode.restart(self.state.episode, ids, pose=pose)
        st = self.state
        st.rngs = rngs
        st.fitness[ids] = self.episode.task.fitness(st.episode.task)[ids]
        st.ended[ids] = False

    def step(self, ids: np.ndarray, action: np.ndarray):
        """Rows ``ids`` take ``action`` ``(n, n_act)`` (clipped to the bounds of :meth:`spaces`; other rows' ignored)
        for one control period.  Returns ``(reward, terminated, truncated, unstable)``, each ``(len(ids),)``."""
        env, task = self.state, self.episode.task
        st = self.episode.step(env.episode, self.native(action), rows=ids)
        fitness = task.fitness(st.task)
        reward = fitness[ids] - env.fitness[ids]
        env.fitness[ids] = fitness[ids]
        terminated = st.fell[ids]
        truncated = ~terminated & (self.steps[ids] >= st.n_ticks)
        env.ended[ids] = terminated | truncated
        return reward, terminated, truncated, st.unstable[ids]

    def info(self) -> dict[str, np.ndarray]:
        """Per row: the task's fitness and terms (those these task options define: a term NaN on every row is
        left out), where the walker is ``(n, 2)`` m, whether it blew up."""
        st, ep = self.state.episode, self.episode
        terms = {k: v for k, v in ep.task.terms(st.task).items() if not np.isnan(v).all()}
        return {"fitness": self.state.fitness.copy(), **terms,
                "position": ep.task.end_position(ep.body, st.sims, st.task).copy(), "unstable": st.unstable.copy()}

    def observe(self) -> np.ndarray:
        """``(n, obs_size)``: the body's sensors and the task's, in :attr:`sensor_widths` order (blown-up rows: 0)."""
        st, ep = self.state.episode, self.episode
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

    def native(self, action: np.ndarray) -> np.ndarray:
        """``action`` ``(n, n_act)`` in the space of :attr:`actions`, clipped to its bounds, in the body's units: a
        ``unit`` action a goes to low + (a + 1) / 2 (high - low)."""
        if self.actions == "unit":
            return self.low + 0.5 * (np.clip(action, -1.0, 1.0) + 1.0) * (self.high - self.low)
        return np.clip(action, self.low, self.high)

    def spaces(self) -> tuple[spaces.Box, spaces.Box]:
        """The observation space (unbounded float64) and the action space of :attr:`actions` (float32)."""
        obs = spaces.Box(-np.inf, np.inf, (self.obs_size,), np.float64)
        if self.actions == "unit":
            return obs, spaces.Box(-1.0, 1.0, self.low.shape, dtype=np.float32)
        act = spaces.Box(self.low.astype(np.float32), self.high.astype(np.float32), dtype=np.float32)
        return obs, act
