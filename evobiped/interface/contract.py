"""What a controller needs and what a body and a task offer, checked once when an episode is built.

A body declares its actuators (:class:`Actuator`: name, leg, joint role, in
action order) and its sensors (name -> width) as class attributes, known
without compiling its model; a task declares the sensors it adds
(``Task.sensor_widths``); a controller declares its :class:`Needs` from its
options (``Controller.needs``).  :func:`wire` checks the pair and returns the
controller's inputs ``{sensor name: width}`` in the order they are
concatenated, or raises one ConfigError line naming what is missing.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Mapping

from ..core.errors import ConfigError


@dataclass(frozen=True)
class Actuator:
    """One actuated joint of a body: its MJCF name, its leg and its joint role within the leg."""

    name: str
    #: "left" or "right"
    leg: str
    #: the joint's role within its leg: "hip", "hip_pitch", "hip_roll", "knee", "ankle", ...
    joint: str


@dataclass(frozen=True)
class Environment:
    """A body's Gymnasium environment (``evobiped/<body class name>-v0``, :mod:`evobiped.envs`): what the body is, what
    its action is (after its shape, for docs/gym.md), its control period (s) and the camera's azimuth (degrees; 90
    looks at the walker's left side)."""

    about: str
    action: str
    control_dt: float
    camera_azimuth: float = 90.0


def legs(actuators: tuple[Actuator, ...]) -> dict[str, tuple[str, ...]]:
    """``{leg: its joint roles in action order}``, legs in the order their first actuator comes."""
    out: dict[str, tuple[str, ...]] = {}
    for a in actuators:
        out[a.leg] = out.get(a.leg, ()) + (a.joint,)
    return out


def index(actuators: tuple[Actuator, ...], leg: str, joint: str) -> int:
    """Position of the actuator with this leg and joint role in the action vector."""
    return next(i for i, a in enumerate(actuators) if (a.leg, a.joint) == (leg, joint))


@dataclass(frozen=True)
class Needs:
    """What a controller needs of the body and task it is paired with."""

    #: sensor name -> width (None: any width); all must be offered
    sensors: Mapping[str, int | None] = field(default_factory=dict)
    #: also read every sensor the task adds (placed first)
    task_sensors: bool = False
    #: reads no sensor at all: a task that adds sensors is refused
    deaf: bool = False
    #: a left and a right leg, each with exactly these joint roles (None: any actuators)
    joints: tuple[str, ...] | None = None
    #: two legs with the same joint roles in the same order, one after the other, each starting at its hip
    paired_legs: bool = False
    #: at most this many actuators (None: any number)
    max_actuators: int | None = None
    #: taken whole when the body and task satisfy it (e.g. feedback sensors), left out otherwise
    optional: "Needs | None" = None
    #: reads its inputs normalised: each sensor it reads must have a declared standing value and scale
    normalised: bool = False
    #: reads every sensor offered by default (the task's first), not only the needed ones
    all_sensors: bool = False


@dataclass(frozen=True)
class Offer:
    """What a body and a task offer a controller."""

    actuators: tuple[Actuator, ...]
    #: every sensor name -> width, the body's and the task's
    sensors: Mapping[str, int]
    #: the names of the task's sensors
    task_sensors: tuple[str, ...] = ()
    #: sensor name -> (standing values, scales), for a controller that normalises its inputs
    norms: Mapping[str, tuple] = field(default_factory=dict)
    #: sensors read only when an ``inputs`` list names them, never by default (e.g. ``stance_side``)
    named_only: tuple[str, ...] = ()


def problem(needs: Needs, offer: Offer) -> str | None:
    """Why ``offer`` does not satisfy ``needs`` (one phrase), or None."""
    acts = offer.actuators
    by_leg = legs(acts)
    shown = "; ".join(f"{leg}: {', '.join(j)}" for leg, j in by_leg.items()) or "none"
    if needs.max_actuators is not None and len(acts) > needs.max_actuators:
        return f"drives at most {needs.max_actuators} actuators, the body has {len(acts)}"
    if needs.joints is not None and (set(by_leg) != {"left", "right"}
                                     or any(sorted(j) != sorted(needs.joints) for j in by_leg.values())):
        return f"needs a left and a right leg with the joints {', '.join(needs.joints)}, the body has {shown}"
    if needs.paired_legs:
        half = len(acts) // 2
        first, second = acts[:half], acts[half:]
        same = len(acts) >= 2 and len(acts) % 2 == 0 and [a.joint for a in first] == [a.joint for a in second]
        if not (same and len({a.leg for a in first}) == 1 and len({a.leg for a in second}) == 1
                and first[0].leg != second[0].leg
                and first[0].joint.startswith("hip")):
            return f"needs two legs with the same joints, each starting at its hip, the body has {shown}"
    if needs.deaf and offer.task_sensors:
        return f"reads no sensors; the task adds {', '.join(offer.task_sensors)}"
    missing = [n for n in needs.sensors if n not in offer.sensors]
    if missing:
        return (f"needs the sensors {', '.join(missing)}, not offered (offered: "
                f"{', '.join(sorted(offer.sensors)) or 'none'})")
    wrong = [f"{n} ({w} wide, offered {offer.sensors[n]})" for n, w in needs.sensors.items() if w is not None
             and offer.sensors[n] != w]
    if wrong:
        return f"needs the sensors {', '.join(wrong)}"
    return None


def wire(needs: Needs, offer: Offer, *, chosen: list[str] | None = None, what: str = "controller") -> dict[str, int]:
    """The controller's inputs ``{sensor: width}`` in input order, or ConfigError (one line, starting with ``what``).

    ``chosen`` (the ``inputs`` option) replaces the default choice (the task's sensors when
    ``needs.task_sensors``, then the needed ones, then the optional ones when satisfied); it must
    still hold every needed sensor.
    """
    why = problem(needs, offer)
    if why is not None:
        raise ConfigError(f"{what} {why}")
    if chosen is None:
        names = list(offer.task_sensors) if needs.task_sensors or needs.all_sensors else []
        if needs.all_sensors:
            names += [n for n in offer.sensors if n not in names and n not in offer.named_only]
        names += [n for n in needs.sensors if n not in names]
        if needs.optional is not None and problem(needs.optional, offer) is None:
            names += [n for n in needs.optional.sensors if n not in names]
    else:
        if not isinstance(chosen, (list, tuple)) or not all(isinstance(n, str) for n in chosen):
            raise ConfigError(f"{what} inputs must be a list of sensor names, got {chosen!r}")
        unknown = [n for n in chosen if n not in offer.sensors]
        if unknown:
            raise ConfigError(f"{what} inputs {unknown} are not sensors of the body or task (have "
                              f"{sorted(offer.sensors)})")
        left_out = [n for n in needs.sensors if n not in chosen]
        if left_out:
            raise ConfigError(f"{what} needs the sensors {', '.join(left_out)}; its inputs leave them out")
        if needs.deaf and chosen:
            raise ConfigError(f"{what} reads no sensors; its inputs name {', '.join(chosen)}")
        names = list(chosen)
    if needs.normalised:
        bare = [n for n in names if n not in offer.norms]
        if bare:
            raise ConfigError(f"{what} normalises its inputs, but no standing value and scale is declared for "
                              f"{', '.join(bare)} (declared: {', '.join(sorted(offer.norms)) or 'none'})")
    return {n: int(offer.sensors[n]) for n in names}


def normaliser(inputs: Mapping[str, int], norms: Mapping[str, tuple]) -> tuple:
    """``(centre (k,), scale (k,))`` for inputs ``{sensor: width}`` in order, from declared norms."""
    import numpy as np

    centre = np.concatenate([np.asarray(norms[n][0], float) for n in inputs]) if inputs else np.zeros(0)
    scale = np.concatenate([np.asarray(norms[n][1], float) for n in inputs]) if inputs else np.ones(0)
    return centre, scale
