"""What every body provides to an episode.

A body wraps one MJCF model: its actuators and what they take (PD target
angles in rad, or torques in N m), its initial state, its sensors, the fall
test and the walker's planar position.  All methods act on a :class:`Sims`
batch and return ``(P, ...)`` arrays; ``ids`` selects the simulations to touch.
"""

from __future__ import annotations

import copy
from abc import ABC, abstractmethod
from typing import Any, Callable, ClassVar, Collection, Literal

import mujoco
import numpy as np

from ..interface.contract import Actuator, Environment
from ..core.errors import ConfigError
from ..physics.gait_lab import FootSample, stacked
from ..physics.models import load_model, model_path
from ..physics.sim import Sims
from ..core.options import constructor_options, option


def model_file_option(stem: str):
    """The ``model_file`` option every body has."""
    return option(None, f"MJCF file to load instead of models/{stem}.xml", check=_is_path)


def _is_path(v) -> None:
    if not isinstance(v, str) or not v:
        raise ConfigError(f"must be a file path, got {v!r}")


class Body(ABC):
    """Base class; subclasses are registered in :data:`evobiped.bodies.BODIES`."""

    name: ClassVar[str]
    #: file stem in models/
    model_name: ClassVar[str]
    #: "position": actions are PD target angles (rad); "torque": joint torques (N m)
    action_kind: ClassVar[Literal["position", "torque"]]
    #: True if :meth:`substep` must run before every physics step
    has_custom_forces: ClassVar[bool] = False
    #: the MJCF body that pushes act on (its centre of mass)
    trunk: ClassVar[str]
    #: the MJCF geom of the ground whose friction a trial may change (None: no MuJoCo ground contact)
    floor_geom: ClassVar[str | None] = None
    #: what the body offers a controller (known without compiling the model): its actuators in
    #: action order, each with its leg and joint role, and its sensors, name -> width (see :meth:`sensors`)
    actuators: ClassVar[tuple[Actuator, ...]]
    sensor_widths: ClassVar[dict[str, int]] = {}
    #: what each sensor reads, name -> a line with its units (docs/gym.md's observation tables; every sensor has one)
    sensor_text: ClassVar[dict[str, str]] = {}
    #: a paragraph docs/usage.md gives above its generated option table (markdown; "": none)
    docs_note: ClassVar[str] = ""
    #: the body's Gymnasium environment (None: none), registered by :mod:`evobiped.envs` from :data:`BODIES`
    environment: ClassVar[Environment | None] = None
    #: the sensor telling which feet touch the ground (1/0), and the leg of each of its columns (None: none)
    contact_sensor: ClassVar[tuple[str, tuple[str, ...]] | None] = None
    #: True for a walker confined to its sagittal plane (nothing moves it sideways)
    sagittal: ClassVar[bool] = False
    #: how a controller that normalises its inputs reads each sensor: name -> (standing values, scales), one per
    #: component, in the sensor's units; the controller sees (reading - standing value) / scale
    sensor_norms: ClassVar[dict[str, tuple[tuple[float, ...], tuple[float, ...]]]] = {}
    #: a bilateral body's left/right mirror (:mod:`evobiped.interface.frame`): sensor name -> (column permutation, sign
    #: per column) giving the mirrored body's reading, and the same over the action vector (None: not bilateral)
    mirror: ClassVar[dict[str, tuple[tuple[int, ...], tuple[float, ...]]]] = {}
    actuator_mirror: ClassVar[tuple[tuple[int, ...], tuple[float, ...]] | None] = None

    #: the body's options (a dataclass of :func:`evobiped.core.options.option` fields, each with a
    #: ``timestep`` and a ``model_file``); constructed as ``cls(options)`` (or ``cls(**settings)``)
    Options: ClassVar[type]

    def __init__(self, options: Any = None, **given):
        self.options = constructor_options(self.Options, options, given, f"{self.name} body_options")
        self.timestep = float(self.options.timestep)
        self.model_file = self.options.model_file or str(model_path(self.model_name))

    def build_model(self) -> mujoco.MjModel:
        """A model of this body, the timestep this body's: the MJCF compiled once per body (so once per process and
        body options, :mod:`evobiped.episode.parts`), each caller given its own copy (an episode's, which it may
        change)."""
        model = self.__dict__.get("_model")
        if model is None:
            model = load_model(self.model_file)
            model.opt.timestep = self.timestep
            self.bind_model(model)
            self._model = model
        return copy.deepcopy(model)

    def bind_model(self, model: mujoco.MjModel) -> None:
        """Look up names and ids in the compiled model (UserError if one is missing)."""

    @property
    def actuator_names(self) -> tuple[str, ...]:
        """The actuated joints, in the order actions are given."""
        return tuple(a.name for a in self.actuators)

    @abstractmethod
    def action_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """``(low, high)``, each ``(n_actuators,)``: rad for targets, N m for torques."""

    def reset(self, sims: Sims, ids: np.ndarray | None = None) -> None:
        """Put simulations ``ids`` (default all) in the body's initial state (default: the model's)."""
        sims.reset(ids)

    @abstractmethod
    def apply(self, sims: Sims, ids: np.ndarray, action: np.ndarray) -> None:
        """Set the actuators of simulations ``ids`` to ``action`` ``(len(ids), n_act)``."""

    def contacts(self, sims: Sims) -> np.ndarray:
        """Which feet touch the ground, ``(n, legs)`` bool in the order of :attr:`contact_sensor`; read once per state
        of the batch (:meth:`Sims.kept`: the senses, the gait tracker and the task share it)."""
        return sims.kept("contacts", self._contacts)

    def _contacts(self, sims: Sims) -> np.ndarray:
        name = self.contact_sensor[0]
        return self.sensors(sims, (name,))[name] > 0

    def substep(self, sims: Sims, ids: np.ndarray) -> None:
        """Custom forces before each physics step (only if ``has_custom_forces``)."""

    def advance(self, sims: Sims, ids: np.ndarray, nstep: int, each: Callable[[], None] | None = None) -> np.ndarray:
        """``nstep`` physics steps of simulations ``ids`` (custom forces before each one; ``each()`` after each one,
        the derived fields current); bool mask over ``ids`` of blow-ups (see :meth:`Sims.step`).  One step at a
        time or ``nstep`` at once, the simulations end in the same state to the last bit."""
        if not self.has_custom_forces and each is None:
            return sims.step(ids, nstep)
        bad = np.zeros(len(ids), bool)
        for _ in range(nstep):
            if self.has_custom_forces:
                self.substep(sims, ids)
            bad |= sims.step(ids, 1)
            if each is not None:
                each()
        return bad

    @abstractmethod
    def com(self, sims: Sims) -> np.ndarray:
        """Centre of mass of the walker, ``(P, 3)`` in m."""

    @abstractmethod
    def planar_position(self, sims: Sims) -> np.ndarray:
        """The walker's position on the ground plane, ``(P, 2)`` in m."""

    @abstractmethod
    def heading(self, sims: Sims) -> np.ndarray:
        """The direction the walker faces on the ground plane, ``(P, 2)`` unit vectors."""

    @abstractmethod
    def fallen(self, sims: Sims, ids: np.ndarray) -> np.ndarray:
        """Bool ``(len(ids),)``: the walker has fallen (episode ends)."""

    def sensors(self, sims: Sims, names: Collection[str] | None = None) -> dict[str, np.ndarray]:
        """Named sensor arrays ``(P, k)`` a controller may take as inputs, k as :attr:`sensor_widths` declares: those
        ``names`` (computing only them: an episode asks for what its controller reads), by default all."""
        return {}

    def feet(self, sims: Sims) -> FootSample:
        """The gait lab's sample of every row now (:mod:`evobiped.physics.gait_lab`): feet in the order of
        :attr:`contact_sensor`; bodies without feet refuse (a gait measure needs them)."""
        raise ConfigError(f"body {self.name!r} declares no feet: its gait cannot be measured")

    def tick_feet(self, sims: Sims) -> FootSample:
        """The gait lab's samples of the last control tick, each field ``(S, n, ...)``: the states after each of its S
        physics steps where the episode collected them (``Sims.readings["feet_steps"]``, kept until the state
        changes), else the state now alone (S = 1)."""
        got = sims.readings.get("feet_steps")
        return got if got is not None else stacked([self.feet(sims)])

    def gait_constants(self, model: mujoco.MjModel) -> tuple[float, float]:
        """The body's total mass (kg) and leg length (m, hip to the ground in the initial pose), from ``model``."""
        raise ConfigError(f"body {self.name!r} declares no feet: its gait cannot be measured")


#: cross-product index cycles: (1, 2, 0) and (2, 0, 1)
_NEXT, _AFTER = np.array([1, 2, 0]), np.array([2, 0, 1])


def joint_senses(sims: Sims, qadr: np.ndarray, dadr: np.ndarray, contact: np.ndarray,
                 want: Collection[str]) -> dict[str, np.ndarray]:
    """The senses every jointed body reads alike, those of ``want``: ``joint_angles`` (qpos at ``qadr``, rad),
    ``joint_velocities`` (qvel at ``dadr``, rad/s) and ``foot_contact`` (``contact`` ``(P, F)`` as 0 or 1)."""
    out = {}
    if "joint_angles" in want:
        out["joint_angles"] = sims.qpos[:, qadr]
    if "joint_velocities" in want:
        out["joint_velocities"] = sims.qvel[:, dadr]
    if "foot_contact" in want:
        out["foot_contact"] = contact.astype(float)
    return out


def links_com_velocity(sims: Sims, root: int, links, mass_share: np.ndarray) -> np.ndarray:
    """``(P, 3)`` m/s: the mass-weighted velocity of the centres of mass of ``links`` (body ids, or a slice of them),
    each weighing ``mass_share`` ``(L,)``, in the tree of body ``root``.

    ``cvel`` gives each link's angular and linear velocity at the tree's centre of mass (``subtree_com`` of the
    root); a link's own centre moves at v + w x (xipos - that).  Computed on demand rather than by a MuJoCo sensor,
    which would cost every simulation ~5 % of its step time whether a controller reads it or not.
    """
    cvel = sims.cvel[:, links]
    w, r = cvel[..., :3], sims.xipos[:, links] - sims.subtree_com[:, root, None]
    # w x r: component i is w_(i+1) r_(i+2) - w_(i+2) r_(i+1), the same products and differences as np.cross
    v = cvel[..., 3:] + (w[..., _NEXT] * r[..., _AFTER] - w[..., _AFTER] * r[..., _NEXT])
    return np.einsum("b,pbi->pi", mass_share, v)
