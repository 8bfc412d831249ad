"""An episode in progress as a value (:class:`EpisodeState`), what a run sets for its episodes (:class:`Context`), and
who may watch one (:class:`Listener`)."""

from __future__ import annotations

import copy
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Callable, Protocol

import numpy as np

from .result import EpisodeResult
from ..interface.normaliser import SenseSums
from ..physics.perturb import Trials
from ..physics.sim import Sims
from ..tasks.base import TaskState

if TYPE_CHECKING:
    from .loop import Episode


#: ``pose(sims, ids)``: moves rows ``ids`` off the body's initial pose (and calls ``sims.forward(ids)``)
Pose = Callable[[Sims, np.ndarray], None]


class Listener(Protocol):
    """Watches an episode (recording, figures); never changes it."""

    def start(self, episode: "Episode", sims: Sims) -> None: ...
    def tick(self, t: float, sims: Sims, ids: np.ndarray, neurons: np.ndarray, action: np.ndarray, task_state: TaskState) -> None: ...
    def end(self, result: EpisodeResult) -> None: ...


class Listeners:
    """Several listeners as one (e.g. one recorder per presentation)."""

    def __init__(self, *listeners: Listener):
        self.listeners = listeners

    def start(self, episode, sims):
        for x in self.listeners:
            x.start(episode, sims)

    def tick(self, t, sims, ids, neurons, action, task_state):
        for x in self.listeners:
            x.tick(t, sims, ids, neurons, action, task_state)

    def end(self, result):
        for x in self.listeners:
            x.end(result)



@dataclass(eq=False, kw_only=True)
class EpisodeState:
    """A batch of simulations part-way through an episode (:meth:`Episode.start`, :meth:`Episode.advance`).

    Every per-row array is ``(n,)`` over the simulation rows of :meth:`Episode.run`.  A state is a
    value: it owns its simulations (and the body's state kept in them), so two states never share
    anything, and :meth:`copy` forks it: both copies continue independently, each exactly as a
    fresh run would.
    """

    sims: Sims
    #: decoded genomes, one row per simulation (an experiment may change them between advances)
    params: dict[str, np.ndarray]
    #: the controller's state (see :meth:`Controller.initial_state`)
    controller: Any
    #: the task's state (see :class:`evobiped.tasks.base.Task`)
    task: TaskState
    alive: np.ndarray
    fell: np.ndarray
    unstable: np.ndarray
    #: s: when each row fell, the planned length while it is up
    end_time: np.ndarray
    start_position: np.ndarray
    start_facing: np.ndarray
    #: s per control tick
    control_dt: float
    #: the planned length in control ticks
    n_ticks: int
    #: control ticks simulated so far
    ticks: int = 0
    trials: Trials | None = None
    #: each row's trial ``(n,)``, its noise stream, its actuator-target offsets ``(n, n_act)`` rad or None
    trial: np.ndarray | None = None
    noise: Any = None
    offset: np.ndarray | None = None
    #: a push force is on some trunk now
    pushed: bool = False
    #: the actions computed but not yet applied, oldest first (``Episode.latency`` > 0)
    pending: list = field(default_factory=list)
    #: the tick at which each row began ``(n,)`` (0; later for a row :meth:`Episode.restart` began anew)
    born: np.ndarray = field(default_factory=lambda: np.zeros(0, int))
    #: N m/rad: each row's pelvis assistance ``(n,)`` (None: none; see :mod:`evobiped.physics.perturb`)
    assist: np.ndarray | None = None
    #: ``(centre (k,), scale (k,))`` the controller's inputs are normalised with in this episode (None: the controller's)
    norm: tuple | None = None
    #: what each row sensed (None: not collected)
    senses: RowSenses | None = None
    #: what an episode stepped by outside actions (a Gymnasium environment's) keeps per row ``(n,)``, None otherwise:
    #: the task's fitness when the row last stepped or began (the reward baseline: a reward is its increment), the
    #: generator of the row's reset noise, and whether its episode ended and waits for a reset
    fitness: np.ndarray | None = None
    rngs: list | None = None
    ended: np.ndarray | None = None

    @property
    def time(self) -> float:
        """Simulated time so far, s."""
        return self.ticks * self.control_dt

    def copy(self) -> "EpisodeState":
        """An independent state equal to this one (simulations, controller, task, noise streams)."""
        return copy.deepcopy(self)


@dataclass(frozen=True)
class Context:
    """What a run sets for one generation's episodes, beyond the config: the inputs' normaliser
    ``(centre (k,), scale (k,))`` (None: the controller's own), whether to collect the senses visited
    (``EpisodeResult.senses``), fitness weights by term for a task whose fitness weighs its terms (None:
    the task's own) and the episodes' length."""

    norm: tuple | None = None
    observe: bool = False
    weights: dict | None = None
    #: control ticks of senses behind ``norm`` (recorded with it in genome files)
    norm_count: float = 0.0
    #: s: the episodes' length (None: the episode's own)
    seconds: float | None = None

    @property
    def empty(self) -> bool:
        """Nothing beyond the config (a plain run's: its evaluations need no context)."""
        return self.norm is None and not self.observe and self.weights is None and self.seconds is None


@dataclass(eq=False)
class RowSenses:
    """What each row sensed while up (:mod:`evobiped.interface.normaliser`): ``count`` ``(n,)`` control ticks, ``total``
    and ``squares`` ``(n, k)`` sums of its inputs and of their squares."""

    count: np.ndarray
    total: np.ndarray
    squares: np.ndarray

    @classmethod
    def zeros(cls, n: int, k: int) -> "RowSenses":
        return cls(np.zeros(n), np.zeros((n, k)), np.zeros((n, k)))

    def add(self, x: np.ndarray, up: np.ndarray) -> None:
        """One tick's inputs ``x`` ``(n, k)`` of the rows ``up`` ``(n,)`` bool."""
        if up.all():
            self.count += 1
            self.total += x
            self.squares += x * x
        else:
            self.count[up] += 1
            self.total[up] += x[up]
            self.squares[up] += x[up] * x[up]

    def table(self) -> dict[str, np.ndarray]:
        """Copies by name, as :attr:`EpisodeResult.senses` holds them."""
        return {"count": self.count.copy(), "total": self.total.copy(), "squares": self.squares.copy()}


def sense_sums(result: EpisodeResult, rows: np.ndarray) -> SenseSums:
    """What genomes ``rows`` sensed in an episode run with ``Context(observe=True)``, all presentations together."""
    count, total, squares = (result.senses[k] for k in ("count", "total", "squares"))
    return SenseSums(float(count[rows].sum()), total[rows].sum(axis=0), squares[rows].sum(axis=0))
