"""What a controller reads each control tick: its inputs in its frame, normalised, and the senses a run collects."""

from __future__ import annotations

import numpy as np

from ..physics import gait
from ..bodies.base import Body
from ..controllers.base import Controller
from ..interface.frame import flips
from ..tasks.base import Task
from .state import EpisodeState


def controller_inputs(body: Body, ctrl: Controller, task: Task, st: EpisodeState, P: int) -> tuple[np.ndarray, np.ndarray | None]:
    """The controller's inputs ``(P, k)`` now (in its frame, normalised if it normalises) and the rows whose senses and
    actions its stance frame mirrors (None: no frame).  Collects the senses of rows that are up (``st.senses``)."""
    sims = st.sims
    frame = getattr(ctrl, "frame", None)
    names = ctrl.input_names
    available = task.sensors(body, sims, st.task) if names else {}
    if any(n not in available for n in names):  # body sensors only when the controller reads one
        available = {**body.sensors(sims), **available}
    flip = None
    if frame is not None:  # the stance leg from the body's senses when they were read this tick (one gait read per tick)
        flip = flips(available["stance_leg"] if "stance_leg" in available else gait.read(body.contacts(sims), sims)["stance_leg"])
    if not names:
        return np.zeros((P, 0)), flip
    x = np.concatenate([available[n] for n in names], axis=1)
    if flip is not None:
        x = frame.inputs(x, flip)
    if st.senses is not None:
        count, total, squares = st.senses
        if st.alive.all():
            count += 1
            total += x
            squares += x * x
        else:
            up = st.alive
            count[up] += 1
            total[up] += x[up]
            squares[up] += x[up] * x[up]
    norm = st.norm if st.norm is not None else ctrl.input_norm
    return (x if norm is None else (x - norm[0]) / norm[1]), flip
