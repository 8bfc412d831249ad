"""What a controller reads each control tick, planned once when the episode is built (:class:`SensePlan`): its inputs
in its frame, normalised, and the senses a run collects."""

from __future__ import annotations

import numpy as np

from ..bodies.base import Body
from ..controllers.base import Controller
from ..physics import gait
from ..tasks.base import Task
from .state import EpisodeState


class SensePlan:
    """The inputs of ``controller`` on ``body`` and ``task``: the body's sensor groups and the task's sensors it reads
    (only those are computed each tick), concatenated in its input order, and its stance frame (None: none)."""

    def __init__(self, body: Body, controller: Controller, task: Task):
        self.body, self.controller, self.task = body, controller, task
        #: the inputs by name, in input order
        self.names = tuple(controller.input_names)
        offered = task.sensor_widths()  # a name the task offers is the task's (as the controller contract wires it)
        #: the body's sensor groups read (computed each tick), and whether any of the task's sensors is
        self.body_names = frozenset(n for n in self.names if n not in offered)
        self.reads_task = any(n in offered for n in self.names)
        self.frame = getattr(controller, "frame", None)

    def read(self, st: EpisodeState, P: int) -> tuple[np.ndarray, np.ndarray | None]:
        """The inputs ``(P, k)`` of the ``P`` rows of ``st`` now (in the controller's frame, normalised if it
        normalises) and the rows whose senses and actions its stance frame mirrors (None: no frame).  Adds the senses of
        rows that are up to ``st.senses`` when a run collects them."""
        body, sims = self.body, st.sims
        flip = None if self.frame is None else gait.second_stands(body.contacts(sims), sims)
        if not self.names:
            return np.zeros((P, 0)), flip
        found = body.sensors(sims, self.body_names) if self.body_names else {}
        if self.reads_task:
            found.update(self.task.sensors(body, sims, st.task))
        x = np.concatenate([found[n] for n in self.names], axis=1)
        if flip is not None:
            x = self.frame.inputs(x, flip)
        if st.senses is not None:
            st.senses.add(x, st.alive)
        norm = st.norm if st.norm is not None else self.controller.input_norm
        return (x if norm is None else (x - norm[0]) / norm[1]), flip
