"""What to simulate (:class:`EpisodeConfig`): registry names, their options parsed once, the episode's length and
timing checked; the one path every episode is built by (:meth:`EpisodeConfig.build`, its parts from :mod:`.parts`)."""

from __future__ import annotations

import copy
import dataclasses
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from ..bodies import DECLARED, body_class, declared_name
from ..bodies.base import Body
from ..controllers import CONTROLLERS
from ..controllers.base import Controller, ControllerOptions
from ..core.errors import ConfigError
from ..core.kernel import KERNELS
from ..interface.genome import GenomeLayout
from ..core.options import given, refuse_unknown
from ..physics.perturb import PerturbationOptions
from ..tasks import TASKS
from ..tasks.base import Task
from ..core.validate import number
from .parts import body_part, controller_part, parsed, task_part
from .timing import check_timing

if TYPE_CHECKING:
    from .loop import Episode


@dataclass(frozen=True, kw_only=True)
class EpisodeConfig:
    """What to simulate: registry names, their options, and the episode length (s); the one way every episode is
    built (evolution, replays, the Gymnasium environments, the Taga experiments, distillation).

    The options are given as tables (a config file's, keyword settings) or as parsed objects; each table
    is parsed once per process (:func:`.parts.parsed`) into its component's frozen ``Options`` (``body_options``: the
    body's, ``controller_options``: the controller's, with the options every controller takes, ``task_options``:
    the task's, ``perturbations``: :class:`PerturbationOptions`), which the parts are built from.
    :meth:`to_dict` writes back the settings the tables gave.  ``controller`` None: the actions come from outside
    (:meth:`Episode.step <evobiped.episode.Episode.step>`, the Gymnasium environments), one every ``control_dt`` s.
    """

    body: str = "reil"
    #: the controller's registry name; None: none (the actions come from outside, every ``control_dt`` s)
    controller: str | None = "ctrnn"
    task: str = "walk"
    seconds: float = 50.0
    #: end a walker's episode when it falls (False: run to the end; only blow-ups stop, e.g. for benchmarks)
    stop_on_fall: bool = True
    body_options: Any = field(default_factory=dict)
    controller_options: Any = field(default_factory=dict)
    task_options: Any = field(default_factory=dict)
    #: how an evolutionary run perturbs each generation (see evobiped.physics.perturb); {} = none
    perturbations: Any = field(default_factory=dict)
    #: s: the control period of an episode without a controller (a multiple of the body's physics step); a
    #: controller's period is its own (its ``dt`` option, else the physics step)
    control_dt: float | None = None
    #: how the control tick's array work runs (:mod:`evobiped.core.kernel`): ``auto`` (compiled where numba is
    #: installed, else NumPy), ``compiled`` or ``numpy``; the same numbers to the last bit in each
    kernel: str = "auto"
    #: a Gymnasium environment's id (``Hopper-v5``, ``evobiped/ReilBiped-v0``): its physics and reward are the episode
    #: (:mod:`.gym_episode`; ``body``, ``task``, ``seconds`` and the perturbations are not used); None: none
    env: str | None = None
    #: the environment's episode settings (:class:`~.gym_episode.GymOptions`: ``max_steps``)
    env_options: Any = field(default_factory=dict)

    def __post_init__(self):
        if self.env is not None or self.env_options not in ({}, None):
            self._check_env()
        if isinstance(self.body, str) and self.body.startswith(DECLARED):  # a file's: found from any directory
            object.__setattr__(self, "body", declared_name(self.body))
        body_cls = body_class(self.body)
        for kind, name, reg in (("controller", self.controller, CONTROLLERS), ("task", self.task, TASKS)):
            if name not in reg and not (kind == "controller" and name is None):
                raise ConfigError(f"episode.{kind}: unknown {kind} {name!r} (choose from {', '.join(sorted(reg))})")
        number(self.seconds, "episode.seconds:", above=0, unit="s")
        if self.kernel not in KERNELS:
            raise ConfigError(f"episode.kernel: unknown kernel {self.kernel!r} (choose from {', '.join(KERNELS)})")
        if not isinstance(self.stop_on_fall, bool):
            raise ConfigError(f"episode.stop_on_fall: must be true or false, got {self.stop_on_fall!r}")
        if self.controller is None:
            if self.controller_options not in ({}, None) and not isinstance(self.controller_options, ControllerOptions):
                raise ConfigError("episode.controller_options: an episode without a controller takes none")
            if self.control_dt is None:
                raise ConfigError("an episode without a controller needs its control period (control_dt)")
            number(self.control_dt, "episode.control_dt:", above=0, unit="s")
        elif self.control_dt is not None:
            raise ConfigError(f"episode.control_dt: only an episode without a controller takes one; controller "
                              f"{self.controller!r} steps at its own period (its dt option)")
        if self.controller is None and self.controller_options is None:
            object.__setattr__(self, "controller_options", {})
        ctrl_cls = ControllerOptions if self.controller is None else CONTROLLERS[self.controller].Options
        for name, cls in (("body_options", body_cls.Options), ("controller_options", ctrl_cls),
                          ("task_options", TASKS[self.task].Options), ("perturbations", PerturbationOptions)):
            object.__setattr__(self, name, parsed(cls, getattr(self, name), f"episode.{name}"))

    def _check_env(self) -> None:
        """An environment's episode: a controller, no body's settings; its ``env_options`` parsed."""
        from .gym_episode import GymOptions

        if not isinstance(self.env, str) or not self.env:
            raise ConfigError(f"episode.env: must be a Gymnasium environment id, got {self.env!r}")
        if self.controller is None:
            raise ConfigError("episode.controller: an environment's episode needs a controller (its genome is evolved)")
        for name in ("body", "task", "seconds", "stop_on_fall", "control_dt"):
            if getattr(self, name) != getattr(EpisodeConfig, name):
                raise ConfigError(f"episode.{name}: an environment's episode ({self.env}) has its own"
                                  + (" length: give env_options.max_steps" if name == "seconds" else ""))
        for name in ("body_options", "task_options", "perturbations"):
            if given(getattr(self, name)) if not isinstance(getattr(self, name), dict) else getattr(self, name):
                raise ConfigError(f"episode.{name}: an environment's episode ({self.env}) takes none")
        object.__setattr__(self, "env_options", parsed(GymOptions, self.env_options or {}, "episode.env_options"))

    def to_dict(self) -> dict:
        """The config as a table (config.json, genome files): every option table as its settings were given
        (``control_dt`` only where it is set); an environment's episode: its id, options and controller alone."""
        d = {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}
        if self.env is not None:
            return {"env": self.env, "env_options": copy.deepcopy(given(self.env_options)),
                    "controller": self.controller, "controller_options": copy.deepcopy(given(self.controller_options)),
                    **({"kernel": self.kernel} if self.kernel != "auto" else {})}
        del d["env"], d["env_options"]
        for name in ("body_options", "controller_options", "task_options", "perturbations"):
            d[name] = copy.deepcopy(given(d[name]))
        if d["control_dt"] is None:
            del d["control_dt"]
        if d["kernel"] == "auto":  # the same numbers whichever runs: files name it only where it was chosen
            del d["kernel"]
        return d

    @property
    def perturbed(self) -> bool:
        """The config perturbs its episodes (it has a perturbations table)."""
        return bool(given(self.perturbations)) or self.perturbations.active

    @property
    def length(self) -> float:
        """s: an episode's planned length (an environment's: its time limit in steps times its step)."""
        if self.env is None:
            return float(self.seconds)
        spec = self.parts()[0].spec
        return float((self.env_options.max_steps or spec.max_steps or 0) * spec.dt)

    @property
    def latency(self) -> int:
        """Control ticks by which the controller's actions reach the body late."""
        return int(self.controller_options.latency)

    def nominal(self) -> "EpisodeConfig":
        """The same episode without perturbations (replays, the robustness battery)."""
        return dataclasses.replace(self, perturbations={})

    def parts(self) -> tuple[Body, Controller | None, Task]:
        """The body, controller (None: none) and task, the controller wired to the sensors it needs: the controller
        contract, the output mapping and the episode's length checked (one ConfigError line on a mismatch); no model is
        compiled.  Built once per process for the same tables (:mod:`.parts`) and shared by :meth:`layout` and every
        :meth:`build` (parts keep no episode state: that is the :class:`EpisodeState`'s, and an episode binds its own
        copy of the controller)."""
        cached = self.__dict__.get("_parts")
        if cached is None:
            cached = self._make_parts()
            object.__setattr__(self, "_parts", cached)
        return cached

    def __getstate__(self) -> dict:
        """Pickled and copied without the built parts (a worker builds its own)."""
        return {k: v for k, v in self.__dict__.items() if k != "_parts"}

    def _make_parts(self) -> tuple[Body, Controller | None, Task]:
        if self.env is not None:
            from .gym_episode import gym_parts

            parts = gym_parts(self.env, self.controller, self.controller_options)
            if parts[0].spec.max_steps is None and self.env_options.max_steps is None:
                raise ConfigError(f"episode.env_options.max_steps: {self.env!r} has no time limit of its own: give one")
            return parts
        body, body_key = body_part(self.body, self.body_options)
        task, task_key = task_part(self.task, self.task_options, body_key)
        if self.controller is None:
            controller = None
            if task.reads_neurons():
                raise ConfigError(f"episode.task_options: these {self.task} task options read a controller's neurons, "
                                  "which an episode without a controller has not (its actions come from outside)")
        else:
            controller = controller_part(self.controller, self.controller_options, body, task, (body_key, task_key))
        check_timing(body, controller, float(self.seconds), control_dt=self.control_dt)
        if body.action_kind != "position":  # offsets and noise are PD-target angles: a body of torques has none
            from ..core.options import scheduled

            for name in ("target_offset", "target_noise"):
                s = scheduled(self.perturbations, name)
                if s.start or s.end:
                    raise ConfigError(f"episode.perturbations.{name}: disturbs PD targets (rad); body {self.body!r} is "
                                      f"driven by {body.action_kind}s and has none")
        return body, controller, task

    def check(self) -> None:
        """Every value checked in this process, without compiling a model: the options, the controller
        contract, the output mapping and the episode's length in control ticks and physics steps (what a worker
        building the episode would refuse); one ConfigError line otherwise."""
        self.parts()

    def layout(self) -> GenomeLayout:
        """The genome layout of this episode's controller, from the declarations alone (no simulation)."""
        controller = self.parts()[1]
        if controller is None:
            raise ConfigError("an episode without a controller has no genome")
        return controller.layout

    def build(self, controller: Controller | None = None) -> "Episode":
        """The episode, its model compiled once per process.  ``controller``: drives it in place of the config's,
        without the config's latency (it delays what it must itself): distillation's blend of a teacher and a
        student, controllers built and checked by their own configs of this body and task."""
        from .loop import Episode

        body, own, task = self.parts()
        if self.env is not None:
            from .gym_episode import GymEpisode

            return GymEpisode(body.spec, own if controller is None else controller, self.env_options)
        return Episode(body, own if controller is None else controller, task, seconds=float(self.seconds),
                       stop_on_fall=bool(self.stop_on_fall), perturbations=self.perturbations
                           if self.perturbations.active else None,
                       latency=self.latency if controller is None else 0, control_dt=self.control_dt,
                       kernel=self.kernel)


def build_episode(**config: Any) -> "Episode":
    """Convenience: ``build_episode(body="reil", seconds=10)``."""
    return EpisodeConfig(**refuse_unknown(EpisodeConfig, config, "episode")).build()
