"""What a task adds to an episode: sensor inputs, bookkeeping per tick, fitness.

Fitness is higher-is-better everywhere.
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

from ..bodies.base import Body
from ..options import NoOptions, parse
from ..sim import Sims


class Task:
    """Base class: no sensors, no bookkeeping; subclasses define fitness."""

    name = "task"
    #: the task's options (a dataclass of :func:`evobiped.options.option` fields); constructed as ``cls(**options)``
    Options: ClassVar[type] = NoOptions
    #: full episodes per genome, each from the initial state (e.g. one per sound source)
    presentations: int = 1

    def __init__(self, **options):
        self.options = parse(self.Options, options, f"{self.name} task_options")

    def presentation_of(self, n_rows: int) -> np.ndarray:
        """Presentation of each simulation row ``(n_rows,)``: genome p's presentation j is row p * S + j."""
        return np.arange(n_rows) % self.presentations

    def bind_model(self, model) -> None:
        """Look up what the task needs in the compiled model (ConfigError if missing)."""

    def sensor_widths(self) -> dict[str, int]:
        """Widths of the sensor arrays this task adds, by name (its part of the controller contract)."""
        return {}

    def start(self, body: Body, sims: Sims) -> dict[str, Any]:
        """Task state at t = 0 (after the body's reset)."""
        return {}

    def sensors(self, body: Body, sims: Sims, state: dict[str, Any]) -> dict[str, np.ndarray]:
        """Named sensor arrays ``(P, k)`` for the controller."""
        return {}

    def on_tick(self, body: Body, sims: Sims, state: dict[str, Any], ids: np.ndarray, healthy: np.ndarray, neurons: np.ndarray) -> None:
        """After a control tick; ``ids`` were stepped, ``healthy`` (over ids) are finite."""

    def fitness(self, state: dict[str, Any]) -> np.ndarray:
        """``(P,)`` fitness at the end of the episode."""
        raise NotImplementedError

    def combine(self, fitness: np.ndarray) -> np.ndarray:
        """A genome's fitness from its presentations' ``(P, S)`` -> ``(P,)``."""
        return fitness[:, 0]
