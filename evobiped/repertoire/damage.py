"""A damaged body (Cully et al. 2015's damage, on a walker): a weakened joint, a locked joint, a shortened leg.

A damage is written ``KIND:PART[:AMOUNT]``:

* ``weak:JOINT:F`` - the actuator of joint ``JOINT`` keeps the fraction ``F`` (0 to 1) of its strength: its
  gains (a position actuator's stiffness and damping, a motor's gear) times ``F``;
* ``locked:JOINT`` - the joint is held at its angle of the initial pose (its range narrowed to +- 0.5 mrad, its
  limit as stiff as MuJoCo keeps stable: time constant two timesteps);
* ``short:LEG:D`` - leg ``LEG``'s shank is ``D`` m shorter (its capsule, foot and foot site moved up by ``D``; masses
  and inertias as before).

It changes the MuJoCo model of a built :class:`~evobiped.episode.Episode` before its simulations are made; a
damage that names no joint (leg) of the body is refused with one line naming the body's.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..episode import EpisodeConfig
from ..core.errors import UserError

KINDS = ("weak", "locked", "short")
#: rad: half the range a locked joint keeps
LOCK_SLACK = 5e-4


@dataclass(frozen=True)
class Damage:
    """``kind`` (weak, locked, short), ``part`` (an actuated joint's name, or a leg), ``amount`` (weak: the fraction of
    strength kept; short: m; locked: 0)."""

    kind: str
    part: str
    amount: float = 0.0

    def __str__(self) -> str:
        return f"{self.kind}:{self.part}" + (f":{self.amount:g}" if self.kind != "locked" else "")


def parse_damage(text: str, episode: EpisodeConfig) -> Damage:
    """The damage ``text`` names on ``episode``'s body (UserError, one line, for anything it cannot be)."""
    parts = text.split(":")
    kind = parts[0]
    if kind not in KINDS or len(parts) != (2 if kind == "locked" else 3):
        raise UserError(f"--damage {text!r}: expected weak:JOINT:F, locked:JOINT or short:LEG:D")
    body = episode.parts()[0]
    if kind == "short":
        legs = sorted({a.leg for a in body.actuators})
        if parts[1] not in legs:
            raise UserError(f"--damage {text!r}: the {body.name} body has no leg {parts[1]!r} (its legs: "
                            f"{', '.join(legs)})")
    elif parts[1] not in body.actuator_names:
        raise UserError(f"--damage {text!r}: the {body.name} body has no joint {parts[1]!r} (its joints: "
                        f"{', '.join(body.actuator_names)})")
    amount = 0.0
    if kind != "locked":
        try:
            amount = float(parts[2])
        except ValueError:
            amount = float("nan")
        ok = 0 <= amount <= 1 if kind == "weak" else 0 < amount < 0.5
        if not ok:
            raise UserError(f"--damage {text!r}: "
                            + ("F must be a fraction 0 to 1" if kind == "weak" else "D must be 0 to 0.5 m"))
    return Damage(kind, parts[1], amount)


def damaged_episode(episode: EpisodeConfig, damage: Damage | None):
    """``episode`` built (an :class:`~evobiped.episode.Episode`), its body damaged (None: intact)."""
    ep = episode.build()
    if damage is None:
        return ep
    m = ep.model
    if damage.kind == "short":
        leg = damage.part
        names = {f"{leg}_shank": "capsule", f"{leg}_foot": "foot"}
        try:
            shank, foot = (m.geom(n).id for n in names)
            site = m.site(f"{leg}_foot").id
        except KeyError:
            raise UserError(
                f"--damage {damage}: the {ep.body.name} body has no {leg}_shank and {leg}_foot to shorten") from None
        d = damage.amount
        axis = m.geom_pos[foot] - m.geom_pos[shank]  # from the shank's centre to the foot (unit below)
        axis = axis / np.linalg.norm(axis)
        m.geom_size[shank, 1] -= d / 2
        m.geom_pos[shank] -= axis * d / 2
        m.geom_pos[foot] -= axis * d
        m.site_pos[site] -= axis * d
        return ep
    a = m.actuator(damage.part).id
    if damage.kind == "weak":
        m.actuator_gainprm[a, 0] *= damage.amount
        m.actuator_biasprm[a, 1:3] *= damage.amount
        return ep
    j = m.actuator_trnid[a, 0]
    sims = ep.sims(1)
    ep.body.reset(sims)
    q0 = float(sims.qpos[0, m.jnt_qposadr[j]])
    m.jnt_range[j] = (q0 - LOCK_SLACK, q0 + LOCK_SLACK)
    m.jnt_limited[j] = 1  # (the simulations made from now on; the one above is dropped)
    m.jnt_solref[j] = (2 * m.opt.timestep, 1.0)  # the stiffest limit MuJoCo keeps stable: a lock, not a spring
    return ep
