"""An episode in progress as a value (:class:`EpisodeState`, with what a trial applies to it: :class:`Disturbances`, and
what each row sensed: :class:`RowSenses`), and what a run sets for its episodes (:class:`Context`)."""

from __future__ import annotations

import copy
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from .result import EpisodeResult
from ..interface.normaliser import SenseSums
from ..physics.trials import TargetNoise, Trials
from ..physics.sim import Sims
from ..tasks.base import TaskState

#: ``pose(sims, ids)``: moves rows ``ids`` off the body's initial pose (and calls ``sims.forward(ids)``)
Pose = Callable[[Sims, np.ndarray], None]
#: how k inputs are normalised: ``(centre (k,), scale (k,))``, a reading x read as (x - centre) / scale
Norm = tuple[np.ndarray, np.ndarray]


@dataclass(eq=False, kw_only=True)
class Disturbances:
    """What a trial applies to an episode's rows while they run (:mod:`evobiped.physics.perturb` draws it,
    :mod:`.disturbances` applies it)."""

    trials: Trials
    #: each row's trial ``(n,)``
    trial: np.ndarray
    #: the noise on the PD targets, one draw per control tick
    noise: TargetNoise
    #: rad: each row's actuator-target offsets ``(n, n_act)`` (None: none)
    offset: np.ndarray | None = None
    #: N m/rad: each row's pelvis assistance ``(n,)`` (None: none)
    assist: np.ndarray | None = None
    #: a push force is on some trunk now
    pushed: bool = False

    @classmethod
    def of(cls, trials: Trials, trial: np.ndarray) -> "Disturbances":
        """The disturbances of ``trials`` on rows of trials ``trial`` ``(n,)``."""
        return cls(trials=trials, trial=trial, noise=trials.noise(),
                   offset=trials.target_offset[trial] if trials.target_offset.any() else None,
                   assist=trials.assist[trial] if trials.assist is not None else None)


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
    #: bool ``(n,)``: each row is up; it fell (or blew up); it blew up
    alive: np.ndarray
    fell: np.ndarray
    unstable: np.ndarray
    #: s: when each row fell, the planned length while it is up
    end_time: np.ndarray
    #: where each row began ``(n, 2)`` m, and the direction it faced then ``(n, 2)`` (unit vectors on the ground)
    start_position: np.ndarray
    start_facing: np.ndarray
    #: s per control tick
    control_dt: float
    #: the planned length in control ticks
    n_ticks: int
    #: control ticks simulated so far
    ticks: int = 0
    #: the tick at which each row began ``(n,)`` (0; later for a row :meth:`Episode.restart` began anew)
    born: np.ndarray = field(default_factory=lambda: np.zeros(0, int))
    #: the actions computed but not yet applied, oldest first (``Episode.latency`` > 0)
    pending: list[np.ndarray] = field(default_factory=list)
    #: what the episode's trials apply (None: a nominal episode)
    disturbances: Disturbances | None = None
    #: the run's context: how the controller's inputs are normalised in this episode (None: the controller's own),
    #: and what each row sensed (None: not collected)
    norm: Norm | None = None
    senses: RowSenses | None = None

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

    norm: Norm | None = None
    observe: bool = False
    weights: dict[str, float] | None = None
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
