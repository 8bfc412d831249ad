"""What a task adds to an episode: sensor inputs, bookkeeping per tick, fitness and its terms.

Fitness is higher-is-better everywhere.  Beside it a task returns named
fitness terms (:attr:`Task.term_names`, :meth:`Task.terms`), one value per
simulation row, which the episode hands back in ``EpisodeResult.terms``.

The task state is the :class:`TaskState` :meth:`Task.start` returns (a task's own subclass of it), private to the
task except for the fields the episode writes into it: ``end_time`` ``(n,)`` s (when each row's episode ends: the
planned length until it falls), ``seconds`` (the planned length, s) and, when a run sets them for a generation
(``episode.Context``), ``weights``: the fitness weights by term of a task whose fitness weighs its terms.  Everything
else about the task is read through its methods (``end_position``, ``targets``, ``terms``), never through its state.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields
from typing import Any, ClassVar

import numpy as np

from ..bodies.base import Body
from ..core.errors import ConfigError
from ..core.options import NoOptions, constructor_options
from ..physics.gait_lab import GaitMeter
from ..physics.sim import Sims


@dataclass(eq=False, kw_only=True)
class TaskState:
    """What every task's state holds, written by the episode: ``end_time`` ``(n,)`` s, ``seconds`` s, ``weights``
    (term -> weight; None: the task's own); a task's state subclasses it with its own fields."""

    end_time: np.ndarray = field(default_factory=lambda: np.zeros(0))
    seconds: float = 0.0
    weights: dict[str, float] | None = None


#: the fields the episode writes (a task's :meth:`Task.restart` leaves them to it)
EPISODE_FIELDS = frozenset(f.name for f in fields(TaskState))


class Task:
    """Base class: no sensors, no bookkeeping; subclasses define fitness."""

    name = "task"
    #: the task's options (a dataclass of :func:`evobiped.core.options.option` fields); constructed as ``cls(options)``
    Options: ClassVar[type] = NoOptions
    #: full episodes per genome, each from the initial state (e.g. one per sound source)
    presentations: int = 1
    #: names of the fitness terms :meth:`terms` returns, each ``(n,)`` per simulation row
    term_names: ClassVar[tuple[str, ...]] = ()
    #: a paragraph docs/usage.md gives above its generated option table (markdown; "": none)
    docs_note: ClassVar[str] = ""
    #: what each sensor the task may add reads, name -> a line with its units (docs/gym.md; every sensor has one)
    sensor_text: ClassVar[dict[str, str]] = {}
    #: named fitness criteria: name -> the task options that select it (the study's conditions, ``evolve --cyclic``)
    criteria: ClassVar[dict[str, dict]] = {}

    def __init__(self, options: Any = None, **given):
        self.options = constructor_options(self.Options, options, given, f"{self.name} task_options")
        self._gait_constants: tuple[float, float] | None = None  # the body's mass and leg length, once read

    def gait_meter(self, body: Body, sims: Sims, sampling: str = "control_tick") -> GaitMeter:
        """The gait lab's meter (:class:`~evobiped.physics.gait_lab.GaitMeter`) for every row of ``sims`` on ``body``'s
        feet, its clock at the rows' time now, sampling as ``sampling`` says; the body's mass and leg length are read
        once per task.  ConfigError for a body that declares no feet."""
        if self._gait_constants is None:
            self._gait_constants = body.gait_constants(sims.model)
        return GaitMeter(sims.n, body.contact_sensor[1], *self._gait_constants, float(sims.time.max()), sampling)

    @classmethod
    def criterion(cls, name: str, flag: str) -> dict:
        """The task options that select criterion ``name`` where they differ from the defaults (what a flag
        such as ``evolve --cyclic`` adds); ConfigError naming ``flag`` for a task without that criterion."""
        if name not in cls.criteria:
            raise ConfigError(f"{flag}: the {cls.name} task has no {name} criterion "
                              f"(its criteria: {', '.join(cls.criteria) or 'none'})")
        defaults = cls.Options()
        return {k: v for k, v in cls.criteria[name].items() if getattr(defaults, k) != v}

    def presentation_of(self, n_rows: int) -> np.ndarray:
        """Presentation of each simulation row ``(n_rows,)``: genome p's presentation j is row p * S + j."""
        return np.arange(n_rows) % self.presentations

    def draw_sources(self, key: tuple[int, int]) -> Any:
        """What the task draws anew for generation ``key`` = (run seed, generation), the same for every genome (the
        steer task's random sources, the command task's drawn commands), handed to :meth:`take_sources`; None (the
        default): it draws nothing."""
        return None

    def take_sources(self, state: TaskState, drawn: Any) -> None:
        """Follow ``drawn`` (a :meth:`draw_sources` draw, not None) in the episode begun as ``state``."""
        raise NotImplementedError(f"the {self.name} task draws nothing")

    def bind_model(self, model) -> None:
        """Look up what the task needs in the compiled model (ConfigError if missing)."""

    def sensor_widths(self) -> dict[str, int]:
        """Widths of the sensor arrays this task adds, by name (its part of the controller contract)."""
        return {}

    def sensor_norms(self) -> dict[str, tuple[tuple[float, ...], tuple[float, ...]]]:
        """Standing value and scale of each sensor the task adds (as ``Body.sensor_norms``); default none."""
        return {}

    def sensor_mirror(self) -> dict[str, tuple[tuple[int, ...], tuple[float, ...]]]:
        """How each sensor the task adds reads on the left/right mirrored body (:mod:`evobiped.interface.frame`): name
        -> (column permutation, sign per column); default none."""
        return {}

    def start(self, body: Body, sims: Sims) -> TaskState:
        """Task state at t = 0 (after the body's reset)."""
        return TaskState()

    def restart(self, body: Body, sims: Sims, state: TaskState, ids: np.ndarray) -> None:
        """Rows ``ids`` of ``state`` begin anew (after the body's reset of those rows), in place: by default
        they take the rows of a fresh :meth:`start` (a field None there is one these options leave out); a task whose
        state is not kept per row overrides this."""
        fresh = self.start(body, sims)
        for f in fields(fresh):
            value = getattr(fresh, f.name)
            if f.name in EPISODE_FIELDS or value is None:
                continue
            if isinstance(value, dict):  # values by name (the terms' ``kept``), each begun anew as a field is
                for k, v in value.items():
                    self._restart_value(k, v, getattr(state, f.name)[k], ids, sims.n)
            else:
                self._restart_value(f.name, value, getattr(state, f.name), ids, sims.n)

    def _restart_value(self, name: str, value: Any, kept: Any, ids: np.ndarray, n: int) -> None:
        """Rows ``ids`` of ``kept`` (the state's ``name``) begun anew as ``value`` (a fresh start's) has them."""
        if isinstance(value, np.ndarray) and value.shape[:1] == (n,):
            kept[ids] = value[ids]
        elif hasattr(kept, "restart"):  # a per-row record of its own (the gait lab's meter, a command schedule)
            kept.restart(ids)
        elif not isinstance(value, (int, float, str)):
            raise ConfigError(f"{self.name} task: its state {name!r} is not kept per row, so rows cannot begin anew")

    #: the task reads the controller's neuron outputs (:meth:`on_tick`'s ``neurons``): it needs a controller
    def reads_neurons(self) -> bool:
        return False

    def reads_feet_steps(self) -> bool:
        """Whether the task measures the gait lab's samples after every physics step (:meth:`Body.tick_feet`): the
        episode collects them only then."""
        return False

    def sensors(self, body: Body, sims: Sims, state: TaskState) -> dict[str, np.ndarray]:
        """Named sensor arrays ``(P, k)`` for the controller."""
        return {}

    def on_tick(self, body: Body, sims: Sims, state: TaskState, ids: np.ndarray, healthy: np.ndarray,
                neurons: np.ndarray) -> None:
        """After a control tick; ``ids`` were stepped, ``healthy`` (over ids) are finite."""

    def fitness(self, state: TaskState) -> np.ndarray:
        """``(P,)`` fitness at the end of the episode."""
        raise NotImplementedError

    def terms(self, state: TaskState) -> dict[str, np.ndarray]:
        """The fitness terms named in :attr:`term_names`, ``(n,)`` each, at the end of the episode."""
        return {}

    def end_position(self, body: Body, sims: Sims, state: TaskState) -> np.ndarray:
        """Where each row's walker ended on the ground plane, ``(n, 2)`` m (default: its position now)."""
        return body.planar_position(sims)

    def targets(self) -> np.ndarray | None:
        """The ground point each presentation walks towards, ``(S, 2)`` m; None: the task has none."""
        return None

    def fitness_label(self) -> str:
        """What the fitness measures and its unit, for a graph's axis."""
        return "fitness"

    def combine(self, fitness: np.ndarray) -> np.ndarray:
        """A genome's fitness from its presentations' ``(P, S)`` -> ``(P,)``."""
        return fitness[:, 0]
