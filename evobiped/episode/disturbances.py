"""The disturbances a trial applies to a batch while it runs (evobiped.perturb draws them): noise and offsets on
the actions, pushes on the trunk, and the pelvis assistance's torque before every physics step."""

from __future__ import annotations

import numpy as np

from ..bodies.base import Body
from ..perturb import assist_torque
from ..sim import Sims
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
