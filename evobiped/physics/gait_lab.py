"""A gait measured as a gait lab measures it: footfalls, duty factors, flight, slip, work.

Every tick, a body that declares feet hands over a :class:`FootSample` (``Body.feet``): which feet touch the ground
(the body's real ground contacts: the foot sphere against MuJoCo's floor for the Reil body, the spring-damper ground
for the Taga body), the horizontal speed of each foot's material point at the ground (slip: a rolling sphere has
none, a sliding one its speed), each foot's height above the ground, each leg's knee angle, and the actuators'
mechanical power tau * omega.  A :class:`GaitMeter` keeps those samples per simulation row and :meth:`GaitMeter.measure`
turns them into the measures of :data:`MEASURES`, one value per row:

* **stance** is debounced: a contact episode that lasts no longer than ``MIN_CONTACT`` (0.04 s) is a tap or a
  bounce, counted as time in the air (so chatter never inflates a duty factor);
* **duty factor** of a foot: the share of the time up that it stands; a walk has >= 0.5 on each foot;
* **airborne**: the share of the time up with no foot standing (a walk has none; running and skipping do);
  **double support**: both standing;
* **steps**: stance episodes of all feet; step frequency per second up, step length = forward travel / steps (0
  without a step);
* **slip**: the median over stance ticks of the contact point's horizontal speed (m/s), and its share of the speed;
  **sliding**: the distance the standing feet slid per second up (m/s; finite for any gait: what a fitness can weigh);
* **clearance**: the mean over swings of each swing's peak foot height (m); **knee swing**: the mean over swings of
  the knee's excursion (rad, max - min) during the swing (both 0 without a whole swing: every measure a fitness
  may weigh is finite); **lift**: the clearance with each swing's peak capped at ``LIFT_CAP`` (5 cm), what a
  fitness should pay (an uncapped clearance pays a leg kicked a metre high as the walker falls);
* **power**: mean positive mechanical power sum_j max(tau_j omega_j, 0) per kg (W/kg); **cost of transport**: that
  power over (g v) (dimensionless: positive work per metre per body weight); **Froude number** v^2 / (g L).

The speed v is the forward travel over the time up (the caller's: the walk task's displacement along the initial
facing); L is the body's leg length (hip to the ground, m).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: s: a contact episode no longer than this is chatter, not a stance
MIN_CONTACT = 0.04
#: m: a swing's peak height counted in ``lift`` at most (a fitness paying foot clearance must not pay a leg kicked
#: high while the walker falls)
LIFT_CAP = 0.05
G = 9.81
#: the per-row measures of :meth:`GaitMeter.measure` (plus ``duty_<foot>`` for each foot), with their units
MEASURES = {
    "duty_min": "smallest duty factor of the feet", "duty_asymmetry": "largest minus smallest duty factor",
    "airborne": "share of the time up with no foot standing", "double_support": "share of the time up with two feet standing",
    "steps_per_s": "stance episodes per second up", "step_length": "forward travel per step (m)",
    "slip": "median stance slip speed (m/s)", "slip_share": "median stance slip over the speed",
    "sliding": "stance feet's slip distance per second up (m/s; 0 without a stance)",
    "clearance": "mean peak swing-foot height (m)", "lift": "mean peak swing-foot height, each swing's capped at LIFT_CAP (m)",
    "knee_swing": "mean knee excursion in swing (rad)",
    "power": "mean positive mechanical power (W/kg)", "positive_work": "positive mechanical work (J/kg)",
    "cost_of_transport": "positive work / (m g distance forward)", "froude": "v^2 / (g L)",
}


@dataclass
class FootSample:
    """One tick of ``n`` rows and ``F`` feet: ``contact`` ``(n, F)`` bool, ``slip`` ``(n, F)`` m/s (horizontal speed of
    the foot's point at the ground), ``height`` ``(n, F)`` m (its lowest point above the ground), ``knee`` ``(n, F)``
    rad (NaN: no knee), ``power`` ``(n, J)`` W (tau * omega per actuated joint)."""

    contact: np.ndarray
    slip: np.ndarray
    height: np.ndarray
    knee: np.ndarray
    power: np.ndarray


def stance_episodes(contact: np.ndarray, dt: float, min_contact: float = MIN_CONTACT) -> list[tuple[int, int]]:
    """``contact`` ``(T,)`` bool per tick -> the debounced stance episodes as (first tick, end tick exclusive): runs of
    contact longer than ``min_contact`` s (``dt`` s per tick)."""
    c = np.concatenate([[False], np.asarray(contact, bool), [False]])
    edges = np.flatnonzero(np.diff(c.astype(np.int8)))
    runs = edges.reshape(-1, 2)
    return [(int(a), int(b)) for a, b in runs if (b - a) * dt > min_contact + 1e-9]


def stance_mask(contact: np.ndarray, dt: float, min_contact: float = MIN_CONTACT) -> np.ndarray:
    """``contact`` ``(T,)`` -> the debounced stance ``(T,)`` bool (see :func:`stance_episodes`)."""
    out = np.zeros(len(contact), bool)
    for a, b in stance_episodes(contact, dt, min_contact):
        out[a:b] = True
    return out


def measure_one(sample: dict[str, np.ndarray], dt: float, *, forward: float, mass: float, leg_length: float,
                feet: tuple[str, ...]) -> dict[str, float]:
    """The measures of one row from its per-tick series ``sample`` (``contact``, ``slip``, ``height``, ``knee`` each
    ``(T, F)``, ``power`` ``(T, J)``) over its ``T`` ticks of ``dt`` s up; ``forward`` m travelled along its facing."""
    contact = sample["contact"]
    T, F = contact.shape
    out = {f"duty_{f}": np.nan for f in feet} | {k: np.nan for k in MEASURES}
    if T == 0:
        return out
    up = T * dt
    stance = np.stack([stance_mask(contact[:, f], dt) for f in range(F)], axis=1)
    duty = stance.mean(axis=0)
    for f, name in enumerate(feet):
        out[f"duty_{name}"] = float(duty[f])
    n_standing = stance.sum(axis=1)
    steps = sum(len(stance_episodes(contact[:, f], dt)) for f in range(F))
    speed = forward / up
    slips = sample["slip"][stance]
    clear, knee = [], []
    for f in range(F):
        swing = np.concatenate([[False], ~stance[:, f], [False]])
        edges = np.flatnonzero(np.diff(swing.astype(np.int8))).reshape(-1, 2)
        for a, b in edges:
            if a == 0 or b >= T:  # a swing cut by the start or the end of the record is not a whole swing
                continue
            clear.append(sample["height"][a:b, f].max())
            k = sample["knee"][a:b, f]
            if np.isfinite(k).all():
                knee.append(k.max() - k.min())
    positive = np.maximum(sample["power"], 0.0).sum(axis=1).mean() / mass
    out.update(
        duty_min=float(duty.min()), duty_asymmetry=float(duty.max() - duty.min()),
        airborne=float((n_standing == 0).mean()), double_support=float((n_standing >= 2).mean()),
        steps_per_s=steps / up, step_length=forward / steps if steps else 0.0,
        slip=float(np.median(slips)) if len(slips) else np.nan, sliding=float(slips.sum() / T),
        clearance=float(np.mean(clear)) if clear else 0.0, lift=float(np.mean(np.minimum(clear, LIFT_CAP))) if clear else 0.0,
        knee_swing=float(np.mean(knee)) if knee else 0.0,
        power=float(positive), positive_work=float(positive * up),
        cost_of_transport=float(positive / (G * speed)) if speed > 1e-3 else np.inf,
        froude=float(speed * speed / (G * leg_length)),
    )
    out["slip_share"] = out["slip"] / speed if speed > 1e-3 and np.isfinite(out["slip"]) else np.inf
    return out


class GaitMeter:
    """The samples of ``n`` rows, tick by tick; rows that are down stop being sampled (each row's series ends
    where it fell)."""

    def __init__(self, n: int, feet: tuple[str, ...], mass: float, leg_length: float, start_time: float = 0.0):
        """``feet`` names the feet in the order of the samples; ``mass`` kg, ``leg_length`` m; the rows' clock reads
        ``start_time`` s now."""
        self.n, self.feet, self.mass, self.leg_length = n, tuple(feet), float(mass), float(leg_length)
        self.dt = np.nan  # s per tick: the simulation clock's advance at the first tick
        self._start_time = float(start_time)
        self.series: dict[str, list[np.ndarray]] = {k: [] for k in ("contact", "slip", "height", "knee", "power")}
        self.ticked: list[np.ndarray] = []  # per tick: which rows were sampled
        self._measured: tuple[int, dict] | None = None

    def tick(self, sample: FootSample, ids: np.ndarray, time: np.ndarray) -> None:
        """Rows ``ids`` (of ``n``) were up this tick, now at simulated ``time`` ``(len(ids),)`` s; ``sample`` covers
        all ``n`` rows."""
        if len(ids) and not np.isfinite(self.dt):
            self.dt = float(time[0]) - self._start_time
        mask = np.zeros(self.n, bool)
        mask[ids] = True
        self.ticked.append(mask)
        for k in self.series:
            self.series[k].append(np.asarray(getattr(sample, k), float if k != "contact" else bool))  # fresh per tick: no copy

    def restart(self, ids: np.ndarray) -> None:
        """Rows ``ids`` begin anew: their earlier ticks no longer count."""
        for mask in self.ticked:
            mask[ids] = False
        self._measured = None

    def measure(self, forward: np.ndarray) -> dict[str, np.ndarray]:
        """Every measure (:data:`MEASURES`, ``duty_<foot>``), ``(n,)`` each, for rows that travelled ``forward``
        ``(n,)`` m along their facing; computed once per tick count."""
        key = len(self.ticked)
        if self._measured is not None and self._measured[0] == key and np.array_equal(self._measured[2], forward):
            return self._measured[1]
        names = [f"duty_{f}" for f in self.feet] + list(MEASURES)
        out = {k: np.full(self.n, np.nan) for k in names}
        if key:
            ticked = np.stack(self.ticked)  # (T, n)
            stacked = {k: np.stack(v) for k, v in self.series.items()}
            for p in range(self.n):
                rows = ticked[:, p]
                one = measure_one({k: v[rows, p] for k, v in stacked.items()}, self.dt, forward=float(forward[p]),
                                  mass=self.mass, leg_length=self.leg_length, feet=self.feet)
                for k in names:
                    out[k][p] = one[k]
        self._measured = (key, out, np.array(forward, copy=True))
        return out
