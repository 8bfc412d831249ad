"""The disturbances a trial applies to a batch while it runs (evobiped.physics.perturb draws them, :func:`draw_trials`
a generation's): noise and offsets on the actions, pushes on the trunk, and the pelvis assistance's torque before every
physics step."""

from __future__ import annotations

import numpy as np

from ..bodies.base import Body
from ..physics.perturb import PerturbationOptions
from ..physics.trials import Trials
from ..physics.sim import Sims
from ..tasks.base import Task
from .state import Disturbances


def draw_trials(perturbations: PerturbationOptions | None, task: Task, key: tuple[int, int] | None, *, seconds: float,
                n_actuators: int, n_genes: int | None) -> Trials | None:
    """The perturbed presentations of generation key = (run seed, generation) (None: nominal) of an episode of
    ``seconds`` s under ``perturbations``, with the task's random sources of that generation (the steer task's sources,
    the command task's drawn commands; shared by every genome); ``n_genes`` None: no controller (no gene noise)."""
    drawn = task.draw_sources(key) if key is not None else None
    if key is None or (perturbations is None and drawn is None):
        return None
    trials = Trials.nominal(1, n_actuators) if perturbations is None else perturbations.draw(
        key, seconds=seconds, n_actuators=n_actuators, n_genes=n_genes)
    trials.sources = drawn
    return trials


def disturb(d: Disturbances, sims: Sims, action: np.ndarray, low: np.ndarray, high: np.ndarray, trunk: int,
            t: float) -> np.ndarray:
    """``action`` ``(n, n_act)`` with the disturbances ``d`` applied at time ``t`` s: each row's target offset and this
    tick's target noise (clipped to ``[low, high]``), and each trial's push set on body ``trunk`` of every row of
    ``sims`` (written only while a push is on or has just ended)."""
    trials, trial = d.trials, d.trial
    jitter = d.noise.next()
    if d.offset is not None or jitter is not None:
        disturbed = action + d.offset if d.offset is not None else action.copy()
        if jitter is not None:
            disturbed += jitter[trial]
        action = np.clip(disturbed, low, high)
    if trials.push_start.size > 0:
        force = trials.push_at(t)  # (R, 3) N
        if d.pushed or force.any():
            sims.xfrc_applied[:, trunk, :3] = force[trial]
            d.pushed = bool(force.any())
    return action


def assisted_physics(body: Body, sims: Sims, ids: np.ndarray, trunk: int, substeps: int, stiffness: np.ndarray,
                     damping: float, each=None) -> np.ndarray:
    """One control period of physics for rows ``ids`` with the pelvis assistance (``stiffness`` ``(len(ids),)`` N m/rad,
    ``damping`` s) set on body ``trunk`` before every physics step (``each()`` after each, as :meth:`Body.advance`);
    bool mask of blow-ups."""
    bad = np.zeros(len(ids), bool)
    for _ in range(substeps):
        sims.xfrc_applied[ids, trunk, 3:] = assist_torque(stiffness, damping, sims.xmat[ids, trunk],
                                                          sims.cvel[ids, trunk, :3])
        bad |= body.advance(sims, ids, 1, each)
    return bad


def assist_torque(stiffness: np.ndarray, damping: float, xmat: np.ndarray, omega: np.ndarray) -> np.ndarray:
    """The assistance torque on the trunk, world frame: ``(n, 3)`` N m.

    ``stiffness`` ``(n,)`` N m/rad, ``damping`` s (c = damping * stiffness), ``xmat`` ``(n, 9)`` the trunk's
    orientation (row-major), ``omega`` ``(n, 3)`` its angular velocity (rad/s, world frame).  Restoring:
    k (z_b x e_z) = k (z_y, -z_x, 0); damping: -c on the horizontal components of omega.
    """
    k = stiffness[:, None]
    tau = np.zeros((len(stiffness), 3))
    # z_b = column 2 of the rotation: (m02, m12, m22) = xmat[:, 2], [:, 5], [:, 8]
    tau[:, 0], tau[:, 1] = xmat[:, 5], -xmat[:, 2]
    tau[:, :2] = k * tau[:, :2] - damping * k * omega[:, :2]
    return tau
