"""What the compiled episode (:mod:`.whole`) covers: :func:`unsupported` says why an episode runs the lock-step loop
instead, in words."""

from __future__ import annotations

from ...controllers.simbicon import Simbicon
from ...tasks.command import CommandTask
from ...tasks.steer import SteerTask
from .readings import SENSES

#: output kinds (controller -> PD target) the compiled tick maps: :mod:`evobiped.interface.mapping`'s
OUTPUT_MAPS = {"unit": 0, "centred": 1, "centred_full": 2, "angle": 3}
#: the senses of :data:`~.readings.SENSES` a task computes (the others are the body's)
_TASK_SENSES = {"heading_error", "command_speed", "command_turning", "command_stop", "sound", "loudness"}


def unsupported(episode, state, listener=None) -> str | None:
    """Why ``state`` of ``episode`` (watched by ``listener``) cannot run whole in compiled code, in words; None where
    it can."""
    from ...bodies.reil import ReilBiped
    from ...controllers.ctrnn import CTRNN
    from ...tasks.walk import WalkTask

    body, ctrl, task = episode.body, episode.controller, episode.task
    if not episode.compiled:
        return "the kernel is numpy"
    if listener is not None:
        return "a listener watches every tick"
    if type(body) is not ReilBiped or body.has_custom_forces:
        return f"the body {body.name!r}"
    if type(ctrl) not in (CTRNN, Simbicon):
        return f"the controller {ctrl.name!r}"
    task_senses = set(task.sensor_widths())
    unknown = [n for n in ctrl.input_names if n not in SENSES or (n in task_senses) != (n in _TASK_SENSES)]
    if unknown:
        return f"the inputs {', '.join(unknown)}"
    if ctrl.output_kind not in OUTPUT_MAPS or body.action_kind != "position":
        return f"the output map {ctrl.output_kind!r} -> {body.action_kind!r}"
    if type(task) not in (WalkTask, CommandTask, SteerTask):
        return f"the task {task.name!r}"
    if type(task) is not SteerTask and (task.cyclic_weight or task.options.gait_measures):
        return "the walk task's cyclic criterion or gait measures"
    d = state.disturbances
    if episode.latency:
        return "latency"
    if d is not None and (d.offset is not None or d.noise.sigma > 0 or d.trials.push_start.size
                          or d.assist is not None):
        return "presentations disturbed while they run (target noise or offsets, pushes, assistance)"
    return None
