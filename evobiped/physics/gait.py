"""Senses that carry a gait's structure: which leg stands, and for how long.

A balance law keeps a phase (stance or swing, switched by foot contact and a
timer) and gates its outputs by it; a network fed only instantaneous senses
must build that memory itself.  These two senses hand it over, from any body
that declares its foot-contact sensor (``Body.contact_sensor``):

* ``stance_leg`` ``(n, 1)``: +1 while the first leg of the contact sensor (the
  Reil body's left) is the stance leg, -1 while the second is.  The stance leg
  changes at a touchdown of the other foot, and a touchdown counts only after
  that foot has been off the ground for at least ``MIN_AIRBORNE`` s (hysteresis:
  a foot chattering on contact does not flip it).  At the start it is the leg
  on the ground (the first if both are).
* ``since_touchdown`` ``(n, 1)``: seconds since the stance leg's touchdown
  (since the start before the first), capped at ``CAP`` s.
* ``stance_side`` ``(n, 1)``: ``stance_leg``'s value, declared as a sense that
  does *not* change under the left/right mirror.  In the body frame the two are
  the same; a controller in the mirrored stance frame reads ``stance_leg`` as a
  constant +1 but ``stance_side`` as +1/-1 by which side stands, so its weights on
  ``stance_side`` make its gait asymmetric (it turns): zero weights leave the
  symmetric walker as it was.

The tracker's state lives beside MuJoCo's in ``sims.extra["gait"]`` (copied
with the batch), created on the first read, so bodies whose controllers never
read these senses pay nothing; :func:`update` runs after every control tick.
"""

from __future__ import annotations

import numpy as np

from .sim import Sims

#: s a foot must have been airborne for its touchdown to change the stance leg
MIN_AIRBORNE = 0.06
#: s: ``since_touchdown`` saturates here (a walker standing still)
CAP = 2.0
NAMES = ("stance_leg", "since_touchdown", "stance_side")
WIDTHS = {"stance_leg": 1, "since_touchdown": 1, "stance_side": 1}
#: what each sense reads (docs/gym.md's observation tables)
TEXT = {"stance_leg": "which leg stands: +1 left, −1 right; it changes at the other foot's touchdown after ≥ 0.06 s "
                      "in the air (`evobiped/physics/gait.py`)",
        "since_touchdown": "seconds since the stance leg's touchdown, capped at 2 s",
        "stance_side": "`stance_leg`'s value, not mirrored in the stance frame: a stance-frame network's way to turn"}
#: senses read only when a controller's ``inputs`` name them: they repeat another outside the stance frame, so a
#: controller's default inputs and the Gym observation leave them out
ON_REQUEST = ("stance_side",)
#: standing values and scales for a controller that normalises its inputs
NORMS = {"stance_leg": ((0.0,), (1.0,)), "since_touchdown": ((0.2,), (0.2,)), "stance_side": ((0.0,), (1.0,))}
#: their left/right mirror (:mod:`evobiped.interface.frame`): the stance flag changes sign; the time, and the side
#: (deliberately: it breaks the stance frame's symmetry), do not
MIRROR = {"stance_leg": ((0,), (-1,)), "since_touchdown": ((0,), (1,)), "stance_side": ((0,), (1,))}


def by_default(senses: dict) -> dict:
    """``senses`` (name -> anything) without those read only on request: what an observation holds when not told."""
    return {k: v for k, v in senses.items() if k not in ON_REQUEST}


def _start(contact: np.ndarray, time: np.ndarray) -> dict[str, np.ndarray]:
    """A tracker for rows with contacts ``(n, 2)`` at ``time`` ``(n,)`` s."""
    return {
        "stance": np.where(contact[:, 0] | ~contact[:, 1], 0, 1),
        "touchdown": time.copy(),
        "lifted": np.where(contact, np.inf, time[:, None]),  # when each foot left the ground (inf: on it)
    }


def tracker(contact: np.ndarray, sims: Sims) -> dict[str, np.ndarray]:
    """The batch's tracker (``stance`` ``(n,)``: 0 while the first leg stands, 1 the second; ``touchdown`` ``(n,)`` s;
    ``lifted`` ``(n, 2)`` s), started from ``contact`` ``(n, 2)`` bool (the body's contact sensor now) on first use;
    from then on :func:`update` runs after every control tick."""
    table = sims.extra.get("gait")
    if table is None:
        table = sims.extra["gait"] = _start(contact, sims.time.copy())
    return table


def read(contact: np.ndarray, sims: Sims, names=NAMES) -> dict[str, np.ndarray]:
    """The senses ``names`` (default all) of every row, each ``(n, 1)``; ``contact`` ``(n, 2)`` bool, the body's
    contact sensor now (the tracker starts from it on first use)."""
    table = tracker(contact, sims)
    leg = np.where(table["stance"] == 0, 1.0, -1.0)[:,
                                                    None] if "stance_leg" in names or "stance_side" in names else None
    out = {"stance_leg": leg} if "stance_leg" in names else {}
    if "since_touchdown" in names:
        out["since_touchdown"] = np.minimum(sims.time - table["touchdown"], CAP)[:, None]
    if "stance_side" in names:
        out["stance_side"] = leg.copy()
    return out


def second_stands(contact: np.ndarray, sims: Sims) -> np.ndarray:
    """Rows whose stance leg is the contact sensor's second ``(n,)`` bool (``stance_leg`` = -1: the rows a stance frame
    mirrors); ``contact`` as in :func:`read`."""
    return tracker(contact, sims)["stance"] != 0


def update(contact: np.ndarray, sims: Sims, ids: np.ndarray) -> None:
    """Advance the tracker of rows ``ids`` to now (after a control tick); ``contact`` ``(len(ids), 2)`` bool.
    Nothing when no controller has read the senses."""
    table = sims.extra.get("gait")
    if table is None or len(ids) == 0:
        return
    rows = slice(None) if len(ids) == sims.n else ids  # every row (ids sorted and unique): views, no gathers
    t = sims.time[rows]
    lifted, stance = table["lifted"][rows], table["stance"][rows]
    first = stance == 0  # the other foot is the second
    landed = np.where(first, contact[:, 1], contact[:, 0]) & (t
                                                              - np.where(first, lifted[:, 1],
                                                                         lifted[:, 0]) >= MIN_AIRBORNE)
    table["stance"][rows] = np.where(landed, 1 - stance, stance)
    table["touchdown"][rows] = np.where(landed, t, table["touchdown"][rows])
    # a foot on the ground: inf; a foot that just left it: now; a foot in the air keeps its lift-off time
    table["lifted"][rows] = np.where(contact, np.inf, np.minimum(lifted, t[:, None]))


def restart(contact: np.ndarray, sims: Sims, ids: np.ndarray) -> None:
    """Rows ``ids`` begin anew (contacts ``(len(ids), 2)`` bool at their reset state)."""
    table = sims.extra.get("gait")
    if table is None:
        return
    fresh = _start(contact, sims.time[ids])
    for k, v in fresh.items():
        table[k][ids] = v
