"""An episode whose physics and task are a Gymnasium environment (``EpisodeConfig(env="Hopper-v5", ...)``):
:class:`GymEpisode` has the :meth:`Episode.run <evobiped.episode.Episode.run>` interface every evaluator calls.

* The controller reads the observation as one sensor, ``observation`` (width: the observation's, offered as the
  task's sensor so every controller reads it by default), declared centre 0 and scale 1: a linear policy reads it raw
  unless the run's running normaliser (``[normalise] running``) normalises it, as ARS V2 does.
* Its outputs map onto the action box as onto a body of torques (:mod:`evobiped.interface.mapping`): ``signed`` and
  ``angle`` outputs are clipped to the box (what the MuJoCo tasks do to a control beyond its range), ``unit`` and
  ``centred`` outputs span it.
* Fitness = the undiscounted return (less ``env_options.reward_shift`` per step, when set); terms ``return``,
  ``length`` (steps) and ``terminated`` (1: the environment ended it, e.g. the hopper fell; 0: its time limit or
  ``max_steps``).  An episode runs to the environment's own TimeLimit (1000 steps for the MuJoCo locomotion tasks)
  unless ``env_options.max_steps`` says otherwise.
* Deterministic and batch-independent: each genome's episode starts from ``env.reset(seed=s)``, s drawn from the
  generation's key (run seed, generation) and the genome's own bits (:func:`reset_seeds`), so a genome's return does
  not depend on its batch, its row or the number of workers, and a resume continues bit for bit.

Each episode row steps its own environment (made once per process, kept by the episode), one
``env.step`` per control step in Python; the controller steps every row at once.
"""

from __future__ import annotations

import zlib
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..core.errors import ConfigError
from ..core.options import check_fields, option
from ..interface.contract import Actuator
from ..interface.mapping import to_action
from .parts import controller_part
from .result import EpisodeResult
from .state import Context, RowSenses

#: the one sensor an environment offers its controller
OBSERVATION = "observation"
#: an episode's terms beside its fitness (the return)
TERMS = ("return", "length", "terminated")
#: this package's own environments: gymnasium imports the module that registers them (its ``module:id`` form)
OWN = "evobiped/"


@dataclass(frozen=True, kw_only=True)
class GymOptions:
    """Settings of a Gymnasium environment's episodes (``[episode.env_options]``)."""

    max_steps: int | None = option(None, "environment steps per episode (none: the environment's own TimeLimit)",
                                   low=1, high=10**7, integer=True)
    reward_shift: float = option(0.0, "subtracted from every step's reward in the fitness (ARS's shift of the survival "
                                 "bonus: 1 for Hopper, Walker2d and Ant); the `return` term stays the environment's")

    def __post_init__(self):
        check_fields(self, "episode.env_options")


def make_env(env_id: str, max_steps: int | None = None):
    """``gymnasium.make(env_id)`` (this package's ``evobiped/...`` environments registered first), its time limit
    ``max_steps`` when given; one ConfigError line for an id gymnasium does not know or an environment that fails."""
    try:
        import gymnasium
    except ImportError:  # pragma: no cover - depends on the installation
        raise ConfigError("episode.env: Gymnasium environments need gymnasium: pip install 'evobiped[gym]'") from None
    name = f"evobiped.envs:{env_id}" if env_id.startswith(OWN) else env_id
    extra = {} if max_steps is None else {"max_episode_steps": int(max_steps)}
    try:
        return gymnasium.make(name, disable_env_checker=True, **extra)
    except gymnasium.error.Error as exc:
        why = str(exc).replace("\n", " ")
        raise ConfigError(f"episode.env: {env_id!r} is no Gymnasium environment here ({why})") from None
    except Exception as exc:  # a registered environment that cannot be made (a missing dependency)
        why = str(exc).replace("\n", " ")
        raise ConfigError(f"episode.env: {env_id!r} cannot be made: {type(exc).__name__}: {why}") from None


@dataclass(frozen=True)
class GymSpec:
    """What an environment declares: observation width, action box ``low``/``high`` ``(n,)``, its step ``dt`` (s), its
    time limit (steps; None: none) and whether it is a MuJoCo environment (``unwrapped.model``)."""

    env_id: str
    obs_dim: int
    low: np.ndarray
    high: np.ndarray
    dt: float
    max_steps: int | None
    mujoco: bool

    @classmethod
    def of(cls, env_id: str) -> "GymSpec":
        """The spec of ``env_id`` (an environment made and closed); ConfigError for a space that is no flat Box."""
        import gymnasium

        env = make_env(env_id)
        try:
            for what, space in (("observation", env.observation_space), ("action", env.action_space)):
                if not isinstance(space, gymnasium.spaces.Box) or len(space.shape) != 1:
                    raise ConfigError(f"episode.env: {env_id!r} has a {type(space).__name__} {what} space {space}; "
                                      "a controller needs flat Box spaces")
            low, high = (np.asarray(b, float) for b in (env.action_space.low, env.action_space.high))
            if not (np.isfinite(low).all() and np.isfinite(high).all()):
                raise ConfigError(f"episode.env: {env_id!r} has an unbounded action box; a controller needs bounds")
            dt = float(getattr(env.unwrapped, "dt", 1.0))
            return cls(env_id, int(env.observation_space.shape[0]), low, high, dt,
                       None if env.spec is None else env.spec.max_episode_steps, hasattr(env.unwrapped, "model"))
        finally:
            env.close()


@dataclass(frozen=True)
class GymBody:
    """The environment as the controller contract sees a body: one actuator per action dimension (``action_0``, ...),
    no sensors of its own (the observation is the task's), no mirror; its actions are values in the box."""

    spec: GymSpec
    action_kind: str = "torque"
    sensor_widths: dict = field(default_factory=dict)
    sensor_norms: dict = field(default_factory=dict)
    mirror: dict = field(default_factory=dict)
    actuator_mirror: Any = None
    contact_sensor: Any = None

    @property
    def name(self) -> str:
        return self.spec.env_id

    @property
    def actuators(self) -> tuple[Actuator, ...]:
        return tuple(Actuator(f"action_{i}", "", "action") for i in range(len(self.spec.low)))

    @property
    def actuator_names(self) -> tuple[str, ...]:
        return tuple(a.name for a in self.actuators)

    def action_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        return self.spec.low, self.spec.high


@dataclass(frozen=True)
class GymTask:
    """The environment as a task: one presentation, fitness the return, terms :data:`TERMS`, the observation its
    sensor (centre 0, scale 1)."""

    spec: GymSpec
    name: str = "gym"
    presentations: int = 1
    term_names: tuple[str, ...] = TERMS

    def sensor_widths(self) -> dict[str, int]:
        return {OBSERVATION: self.spec.obs_dim}

    def sensor_norms(self) -> dict[str, tuple]:
        return {OBSERVATION: (np.zeros(self.spec.obs_dim), np.ones(self.spec.obs_dim))}

    def sensor_mirror(self) -> dict:
        return {}

    def reads_neurons(self) -> bool:
        return False

    def targets(self) -> None:
        return None


_SPECS: dict[str, GymSpec] = {}


def gym_parts(env_id: str, controller: str, options: Any) -> tuple[GymBody, Any, GymTask]:
    """The environment's body and task stand-ins and the controller ``controller`` (parsed ``options``) wired to its
    observation; the spec read once per process."""
    if env_id not in _SPECS:
        _SPECS[env_id] = GymSpec.of(env_id)
    spec = _SPECS[env_id]
    body, task = GymBody(spec), GymTask(spec)
    return body, controller_part(controller, options, body, task, (("gym", env_id), ("gym", env_id))), task


def reset_seeds(key: tuple | None, genomes: np.ndarray) -> list[int]:
    """The ``env.reset`` seed of each genome's episode ``(P,)``: from the generation's key (run seed, generation; None:
    none) and the genome's bits alone (CRC-32 of its float64 genes), so neither its row nor its batch changes it."""
    head = [] if key is None else [int(k) for k in key]
    return [int(np.random.SeedSequence([*head, zlib.crc32(np.ascontiguousarray(g, float).tobytes()), 0x6E7])
                .generate_state(1)[0]) for g in genomes]


class GymEpisode:
    """A controller in a Gymnasium environment, one environment per row; :meth:`run` as an :class:`Episode`'s."""

    perturbations = None

    def __init__(self, spec: GymSpec, controller, options: GymOptions):
        self.spec, self.options = spec, options
        self.body, self.task = GymBody(spec), GymTask(spec)
        self.controller = controller.bound(spec.dt)
        self.control_dt = spec.dt
        #: steps per episode (the config checked that there is a limit: ``EpisodeConfig.parts``)
        self.max_steps = int(options.max_steps if options.max_steps is not None else spec.max_steps)
        self.seconds = self.max_steps * spec.dt
        self._envs: list = []

    @property
    def model(self):
        """The MuJoCo model of a MuJoCo environment (None: none), for recordings of its geometry."""
        return getattr(self.envs(1)[0].unwrapped, "model", None)

    def envs(self, n: int) -> list:
        """At least ``n`` environments of this episode (made once, kept)."""
        while len(self._envs) < n:
            self._envs.append(make_env(self.spec.env_id, self.options.max_steps))
        return self._envs[:n]

    def trials_for(self, key: tuple | None) -> tuple | None:
        """What :meth:`run` draws its reset seeds from: the generation's key (run seed, generation) itself."""
        return None if key is None else tuple(int(k) for k in key)

    def run(self, genomes: np.ndarray, *, seconds: float | None = None, listener=None, trials: tuple | None = None,
            context: Context | None = None) -> EpisodeResult:
        """Every genome ``(P, G)`` (or one ``(G,)``) for one episode in its own environment, reset from ``trials``
        (the key :meth:`trials_for` gives; None: the genome alone).  ``listener``: ``start(episode, envs)``,
        ``tick(step, obs (P, k), action (P, n), reward (P,), rows)`` after each step, ``end(result)``."""
        ctx = context or Context()
        if seconds is not None or ctx.seconds is not None or ctx.weights is not None:
            raise ConfigError("an environment's episode has its own length and fitness: no seconds or weights")
        ctrl = self.controller
        genomes = ctrl.layout.validate(genomes)
        params = ctrl.decode(genomes)
        P = len(genomes)
        envs = self.envs(P)
        obs = np.stack([np.asarray(e.reset(seed=s)[0], float) for e, s in zip(envs, reset_seeds(trials, genomes))])
        state = ctrl.initial_state(params)
        alive, terminated, unstable = np.ones(P, bool), np.zeros(P, bool), np.zeros(P, bool)
        ret, steps = np.zeros(P), np.zeros(P, int)
        senses = RowSenses.zeros(P, obs.shape[1]) if ctx.observe else None
        norm = ctx.norm if ctx.norm is not None else ctrl.input_norm
        low, high = self.spec.low, self.spec.high
        kind = "signed" if ctrl.output_kind == "angle" else ctrl.output_kind  # raw values: clipped to the box
        if listener is not None:
            listener.start(self, envs)
        for k in range(self.max_steps):
            rows = np.flatnonzero(alive)
            if not len(rows):
                break
            if senses is not None:
                senses.add(obs, alive)
            state, out = ctrl.step(params, state, obs if norm is None else (obs - norm[0]) / norm[1])
            action = to_action(kind, low, high, "torque", out)
            reward = np.zeros(P)
            for i in rows:
                o, r, term, trunc, _ = envs[i].step(action[i])
                obs[i], reward[i] = o, r
                steps[i] += 1
                bad = not (np.isfinite(obs[i]).all() and np.isfinite(r))
                if term or trunc or bad or steps[i] >= self.max_steps:
                    alive[i], terminated[i], unstable[i] = False, bool(term), bad
            ret += np.where(np.isfinite(reward), reward, 0.0)
            if listener is not None:
                listener.tick(k + 1, obs, action, reward, rows)
        result = EpisodeResult(
            fitness=ret - float(self.options.reward_shift) * steps, fell=terminated.copy(), unstable=unstable,
            end_time=steps * self.spec.dt,
            start_position=np.zeros((P, 2)), end_position=np.zeros((P, 2)),
            start_facing=np.tile([1.0, 0.0], (P, 1)),
            terms={"return": ret.copy(), "length": steps.astype(float), "terminated": terminated.astype(float)},
            senses=None if senses is None else senses.table())
        if listener is not None:
            listener.end(result)
        return result

    def close(self) -> None:
        for e in self._envs:
            e.close()
        self._envs = []
