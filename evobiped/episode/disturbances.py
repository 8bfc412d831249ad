"""The disturbances a trial applies to a batch while it runs (evobiped.physics.perturb draws them): noise and offsets on
the actions, pushes on the trunk, and the pelvis assistance's torque before every physics step."""

from __future__ import annotations

import numpy as np

from ..bodies.base import Body
from ..physics.sim import Sims
from .state import EpisodeState


def disturb(state: EpisodeState, action: np.ndarray, low: np.ndarray, high: np.ndarray, trunk: int, t: float) -> np.ndarray:
    """``action`` ``(n, n_act)`` with the state's trials applied at time ``t`` s: each row's target offset and this
    tick's target noise (clipped to ``[low, high]``), and each trial's push set on body ``trunk`` of every row (written
    only while a push is on or has just ended)."""
    st, trials, trial, sims = state, state.trials, state.trial, state.sims
    jitter = st.noise.next()
    if st.offset is not None or jitter is not None:
        disturbed = action + st.offset if st.offset is not None else action.copy()
        if jitter is not None:
            disturbed += jitter[trial]
        action = np.clip(disturbed, low, high)
    if trials.push_start.size > 0:
        force = trials.push_at(t)  # (R, 3) N
        if st.pushed or force.any():
            sims.xfrc_applied[:, trunk, :3] = force[trial]
            st.pushed = bool(force.any())
    return action


def assisted_physics(body: Body, sims: Sims, ids: np.ndarray, trunk: int, substeps: int, stiffness: np.ndarray,
                     damping: float) -> np.ndarray:
    """One control period of physics for rows ``ids`` with the pelvis assistance (``stiffness`` ``(len(ids),)`` N m/rad,
    ``damping`` s) set on body ``trunk`` before every physics step; bool mask of blow-ups."""
    bad = np.zeros(len(ids), bool)
    for _ in range(substeps):
        sims.xfrc_applied[ids, trunk, 3:] = assist_torque(stiffness, damping, sims.xmat[ids, trunk], sims.cvel[ids, trunk, :3])
        bad |= body.advance(sims, ids, 1)
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
