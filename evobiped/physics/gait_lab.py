"""A gait measured as a gait lab measures it: footfalls, duty factors, flight, slip, work.

A body that declares feet hands over a :class:`FootSample` of its state (``Body.feet``): which feet touch the ground
(the body's real ground contacts: the foot sphere against MuJoCo's floor for the Reil body, the spring-damper ground
for the Taga body), the horizontal speed of each foot's material point at the ground (slip: a rolling sphere has
none, a sliding one its speed), each foot's height above the ground, each leg's knee angle, and the actuators'
mechanical power tau * omega (the force applied during the last physics step times the joint rate it produced: the
exact positive work of that step, over dt).  A :class:`GaitMeter` keeps those samples per simulation row and
:meth:`GaitMeter.measure` turns them into the measures of :data:`MEASURES`, one value per row.

**Sampling** (:data:`SAMPLINGS`).  ``"physics_step"`` samples the state after every physics step (an episode hands
the meter the samples of each control tick's physics steps, ``(S, n, ...)``): what a gait lab reads, and what
``evobiped gait-report`` always measures.  ``"control_tick"`` keeps only the last physics step of each control tick
and debounces stance one way (short contacts dropped, short gaps kept): how the walkers evolved before this sampling
existed were measured, kept so that their presets and files reproduce.  Under it the work of the unread steps is
invisible (a search can move its effort there) and a 20 ms bounce splits a stance in two.

* **stance** is debounced both ways: a gap in contact no longer than ``MIN_GAP`` (0.04 s) inside a stance is a bounce
  and counts as stance (``physics_step`` only), then a contact episode no longer than ``MIN_CONTACT`` (0.04 s) is a
  tap, counted as time in the air (so chatter never inflates a duty factor or the step count);
* **duty factor** of a foot: the share of the time up that it stands; a walk has >= 0.5 on each foot;
* **airborne**: the share of the time up with no foot standing (a walk has none; running and skipping do);
  **double support**: both standing;
* **steps**: stance episodes of all feet; step frequency per second up, step length = forward travel / steps (0
  without a step); **step_leg** the step length in leg lengths, **step_similar** the step length over the step
  dynamic similarity predicts at the walker's Froude number (Alexander 1984: stride 2.3 L Fr^0.3, two steps a
  stride); a walker whose steps are shorter than ``SHUFFLE`` (a third) of that shuffles;
* **slip**: the median over stance samples of the contact point's horizontal speed (m/s), and its share of the speed;
  its 90th percentile (``slip_p90``, ``slip_p90_share``: the tail a median hides); **sliding**: the distance the
  standing feet slid per second up (m/s; finite for any gait: what a fitness can weigh); **slide_per_m**: that
  distance per metre forward (the slip of a step over the step's length);
* **clearance**: the mean over swings of each swing's peak foot height (m); **knee swing**: the mean over swings of
  the knee's excursion (rad, max - min) during the swing (both 0 without a whole swing: every measure a fitness
  may weigh is finite); **lift**: the clearance with each swing's peak capped at ``LIFT_CAP`` (5 cm), what a
  fitness should pay (an uncapped clearance pays a leg kicked a metre high as the walker falls);
* **power**: mean positive mechanical power sum_j max(tau_j omega_j, 0) per kg (W/kg); **cost of transport**: that
  power over (g v) (dimensionless: positive work per metre per body weight); **Froude number** v^2 / (g L);
  **torque_cost**: the mean over time of the squared joint torques summed, per kg (N^2 m^2 / kg; finite for any
  gait, what a fitness can weigh; over the speed, per metre), an effort that, as a muscle's, charges a leg swung
  fast (Kuo 2001: what makes long, slow steps the cheap ones).

The speed v is the forward travel over the time up (the caller's: the walk task's displacement along the initial
facing); L is the body's leg length (hip to the ground, m).  ``control_tick`` meters measure :data:`MEASURES_TICK`
(the measures that sampling had), ``physics_step`` meters every one of :data:`MEASURES`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..core.errors import ConfigError

#: s: a contact episode no longer than this is chatter, not a stance
MIN_CONTACT = 0.04
#: s: a gap in contact no longer than this inside a stance is a bounce, not a swing (``physics_step`` sampling)
MIN_GAP = 0.04
#: a step shorter than this share of the step dynamic similarity predicts is a shuffle
SHUFFLE = 1.0 / 3.0
#: how a meter samples (see the module docstring): name -> the gap (s) its stance debounce merges
SAMPLINGS = {"physics_step": MIN_GAP, "control_tick": 0.0}
#: the help of the tasks' option choosing it
SAMPLING_HELP = ("how the gait terms sample the feet: `physics_step` (after every physics step, stance debounced both "
                 "ways: what gait-report measures) or `control_tick` (the last physics step of each control tick: "
                 "how the walkers evolved before were measured; their presets and files keep it)")
#: m: a swing's peak height counted in ``lift`` at most (a fitness paying foot clearance must not pay a leg kicked
#: high while the walker falls)
LIFT_CAP = 0.05
G = 9.81
#: the per-row measures of :meth:`GaitMeter.measure` (plus ``duty_<foot>`` for each foot): name -> (unit, what it is)
MEASURES = {
    "duty_min": ("", "smallest duty factor of the feet"), "duty_asymmetry": ("", "largest minus smallest duty factor"),
    "airborne": ("", "share of the time up with no foot standing"),
    "double_support": ("", "share of the time up with two feet standing"),
    "steps_per_s": ("1/s", "stance episodes per second up"), "step_length": ("m", "forward travel per step"),
    "slip": ("m/s", "median stance slip speed"), "slip_share": ("", "median stance slip over the speed"),
    "sliding": ("m/s", "stance feet's slip distance per second up (0 without a stance)"),
    "clearance": ("m", "mean peak swing-foot height"),
    "lift": ("m", "mean peak swing-foot height, each swing's capped at LIFT_CAP"),
    "knee_swing": ("rad", "mean knee excursion in swing"),
    "power": ("W/kg", "mean positive mechanical power"), "positive_work": ("J/kg", "positive mechanical work"),
    "cost_of_transport": ("", "positive work / (m g distance forward)"), "froude": ("", "v^2 / (g L)"),
}
#: the measures of a ``control_tick`` meter (the walk and steer tasks' gait terms under that sampling)
MEASURES_TICK = tuple(MEASURES)
MEASURES |= {
    "slip_p90": ("m/s", "90th percentile of the stance slip speed"), "slip_p90_share": ("", "slip_p90 over the speed"),
    "slide_per_m": ("m/m", "stance feet's slip distance per metre forward"),
    "step_leg": ("", "step length in leg lengths"),
    "step_similar": ("", "step length over dynamic similarity's step at the Froude number"),
    "torque_cost": ("N^2 m^2/kg", "mean sum of squared joint torques per kg"),
}


def terms(sampling: str, feet: tuple[str, ...] = ("left", "right")) -> tuple[str, ...]:
    """The names a meter of ``sampling`` measures for ``feet``: ``duty_<foot>``, then its measures."""
    return (*(f"duty_{f}" for f in feet), *(MEASURES if sampling == "physics_step" else MEASURES_TICK))


def check_sampled(names, sampling: str, what: str) -> None:
    """ConfigError naming those of ``names`` that only a ``physics_step`` meter measures, where ``sampling`` is
    another (``what``: the option that names them)."""
    if sampling != "physics_step" and (missing := [k for k in names if k in MEASURES and k not in MEASURES_TICK]):
        raise ConfigError(f"{what}: {', '.join(missing)} measured only under gait_sampling = 'physics_step'")


def similar_step(speed: float, leg_length: float) -> float:
    """The step (m) dynamic similarity predicts for a walker of leg ``leg_length`` m at ``speed`` m/s: half of
    Alexander's stride 2.3 L Fr^0.3, Fr = v^2 / (g L) (0 at rest)."""
    fr = speed * speed / (G * leg_length)
    return 0.5 * 2.3 * leg_length * fr ** 0.3 if fr > 0 else 0.0


@dataclass
class FootSample:
    """One state of ``n`` rows and ``F`` feet: ``contact`` ``(n, F)`` bool, ``slip`` ``(n, F)`` m/s (horizontal speed
    of the foot's point at the ground), ``height`` ``(n, F)`` m (its lowest point above the ground), ``knee`` ``(n, F)``
    rad (NaN: no knee), ``power`` ``(n, J)`` W (tau * omega per actuated joint), ``torque`` ``(n, J)`` N m (tau).  A
    tick's samples (:func:`stacked`) have a leading axis of its S physics steps, ``(S, n, ...)``."""

    contact: np.ndarray
    slip: np.ndarray
    height: np.ndarray
    knee: np.ndarray
    power: np.ndarray
    torque: np.ndarray


#: the fields of a :class:`FootSample`
FIELDS = ("contact", "slip", "height", "knee", "power", "torque")


def stacked(samples: list[FootSample]) -> FootSample:
    """The samples of S successive states as one, each field ``(S, n, ...)``."""
    return FootSample(*(np.stack([getattr(x, k) for x in samples]) for k in FIELDS))


def stance_episodes(contact: np.ndarray, dt: float, min_contact: float = MIN_CONTACT,
                    min_gap: float = 0.0) -> list[tuple[int, int]]:
    """``contact`` ``(T,)`` bool per sample -> the debounced stance episodes as (first sample, end sample exclusive),
    ``dt`` s per sample: runs of contact whose gaps of at most ``min_gap`` s are merged (bounces), then those longer
    than ``min_contact`` s (taps dropped)."""
    c = np.concatenate([[False], np.asarray(contact, bool), [False]])
    runs = np.flatnonzero(np.diff(c.astype(np.int8))).reshape(-1, 2)
    if min_gap > 0 and len(runs) > 1:
        gap = (runs[1:, 0] - runs[:-1, 1]) * dt
        first = np.flatnonzero(np.concatenate([[True], gap > min_gap + 1e-9]))  # runs after a short gap join the last
        runs = np.stack([runs[first, 0], np.append(runs[first[1:] - 1, 1], runs[-1, 1])], axis=1)
    return [(int(a), int(b)) for a, b in runs if (b - a) * dt > min_contact + 1e-9]


def stance_mask(contact: np.ndarray, dt: float, min_contact: float = MIN_CONTACT, min_gap: float = 0.0) -> np.ndarray:
    """``contact`` ``(T,)`` -> the debounced stance ``(T,)`` bool (see :func:`stance_episodes`)."""
    out = np.zeros(len(contact), bool)
    for a, b in stance_episodes(contact, dt, min_contact, min_gap):
        out[a:b] = True
    return out


def measure_one(sample: dict[str, np.ndarray], dt: float, *, forward: float, mass: float, leg_length: float,
                feet: tuple[str, ...], min_gap: float = 0.0) -> dict[str, float]:
    """The measures of one row from its series ``sample`` (``contact``, ``slip``, ``height``, ``knee`` each
    ``(T, F)``, ``power`` ``(T, J)``) over its ``T`` samples of ``dt`` s up; ``forward`` m travelled along its facing;
    ``min_gap`` s: the bounces the stance debounce merges (:func:`stance_episodes`)."""
    contact = sample["contact"]
    T, F = contact.shape
    out = {f"duty_{f}": np.nan for f in feet} | {k: np.nan for k in MEASURES}
    if T == 0:
        return out
    up = T * dt
    stance = np.stack([stance_mask(contact[:, f], dt, MIN_CONTACT, min_gap) for f in range(F)], axis=1)
    duty = stance.mean(axis=0)
    for f, name in enumerate(feet):
        out[f"duty_{name}"] = float(duty[f])
    n_standing = stance.sum(axis=1)
    steps = sum(len(stance_episodes(contact[:, f], dt, MIN_CONTACT, min_gap)) for f in range(F))
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
        clearance=float(np.mean(clear)) if clear else 0.0, lift=float(np.mean(np.minimum(clear, LIFT_CAP))) if clear
            else 0.0,
        knee_swing=float(np.mean(knee)) if knee else 0.0,
        power=float(positive), positive_work=float(positive * up),
        cost_of_transport=float(positive / (G * speed)) if speed > 1e-3 else np.inf,
        froude=float(speed * speed / (G * leg_length)),
    )
    moving = speed > 1e-3
    out["slip_share"] = out["slip"] / speed if moving and np.isfinite(out["slip"]) else np.inf
    p90 = float(np.percentile(slips, 90)) if len(slips) else np.nan
    similar = similar_step(speed, leg_length)
    out.update(slip_p90=p90, slip_p90_share=p90 / speed if moving and np.isfinite(p90) else np.inf,
               slide_per_m=out["sliding"] / speed if moving else np.inf, step_leg=out["step_length"] / leg_length,
               step_similar=out["step_length"] / similar if similar > 0 else 0.0)
    if "torque" in sample:  # what swinging a leg fast costs a muscle (rises steeply with the step rate)
        out["torque_cost"] = float(np.square(sample["torque"]).sum(axis=1).mean() / mass)
    return out


class GaitMeter:
    """The samples of ``n`` rows, tick by tick; rows that are down stop being sampled (each row's series ends
    where it fell)."""

    def __init__(self, n: int, feet: tuple[str, ...], mass: float, leg_length: float, start_time: float = 0.0,
                 sampling: str = "control_tick"):
        """``feet`` names the feet in the order of the samples; ``mass`` kg, ``leg_length`` m; the rows' clock reads
        ``start_time`` s now; ``sampling`` one of :data:`SAMPLINGS`."""
        self.n, self.feet, self.mass, self.leg_length = n, tuple(feet), float(mass), float(leg_length)
        self.sampling, self.min_gap = sampling, SAMPLINGS[sampling]
        #: what :meth:`measure` gives: ``duty_<foot>`` per foot, then the sampling's measures
        self.names = terms(sampling, self.feet)
        self.dt = np.nan  # s per sample: the simulation clock's advance at the first tick over its samples
        self._start_time = float(start_time)
        # the torques only where a measure reads them (torque_cost: physics_step), none kept per tick otherwise
        kept = FIELDS if sampling == "physics_step" else tuple(k for k in FIELDS if k != "torque")
        self.series: dict[str, list[np.ndarray]] = {k: [] for k in kept}
        self.ticked: list[np.ndarray] = []  # per tick: which rows were sampled
        self._measured: tuple[int, dict] | None = None

    def tick(self, sample: FootSample, ids: np.ndarray, time: np.ndarray) -> None:
        """Rows ``ids`` (of ``n``) were up this tick, now at simulated ``time`` ``(len(ids),)`` s; ``sample`` covers
        all ``n`` rows, each field ``(S, n, ...)``: the states after each of the tick's S physics steps
        (:meth:`Body.tick_feet`); a ``control_tick`` meter keeps the last."""
        steps = sample.contact[-1:] if self.sampling == "control_tick" else sample.contact
        if len(ids) and not np.isfinite(self.dt):
            self.dt = (float(time[0]) - self._start_time) / len(steps)
        mask = np.zeros(self.n, bool)
        mask[ids] = True
        self.ticked.extend([mask] * len(steps))  # one mask object per tick: a restart clears its samples together
        for k in self.series:
            v = getattr(sample, k)
            v = v[-1:] if self.sampling == "control_tick" else v
            self.series[k].extend(np.asarray(v, float if k != "contact" else bool))  # fresh per tick: no copy

    def restart(self, ids: np.ndarray) -> None:
        """Rows ``ids`` begin anew: their earlier ticks no longer count."""
        for mask in self.ticked:  # a tick's samples share one mask: cleared once per sample, harmlessly
            mask[ids] = False
        self._measured = None

    def measure(self, forward: np.ndarray) -> dict[str, np.ndarray]:
        """Every measure of :attr:`names`, ``(n,)`` each, for rows that travelled ``forward`` ``(n,)`` m along their
        facing; computed once per sample count."""
        key = len(self.ticked)
        if self._measured is not None and self._measured[0] == key and np.array_equal(self._measured[2], forward):
            return self._measured[1]
        names = self.names
        out = {k: np.full(self.n, np.nan) for k in names}
        if key:
            ticked = np.stack(self.ticked)  # (T, n)
            stacked = {k: np.stack(v) for k, v in self.series.items()}
            for p in range(self.n):
                rows = ticked[:, p]
                one = measure_one({k: v[rows, p] for k, v in stacked.items()}, self.dt, forward=float(forward[p]),
                                  mass=self.mass, leg_length=self.leg_length, feet=self.feet, min_gap=self.min_gap)
                for k in names:
                    out[k][p] = one[k]
        self._measured = (key, out, np.array(forward, copy=True))
        return out
