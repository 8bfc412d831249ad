"""P simulations of one MuJoCo model, stepped in C between control ticks.

A thin layer over :class:`mujoco.batch.Batch` (persistent, one ``MjData`` per
simulation): live ``(P, ...)`` numpy views of the state and derived fields,
stepping of a subset of simulations, and detection of numerical blow-ups so
that an unstable simulation is reported (and scored as a fall), never raised.

A blow-up is a MuJoCo error or warning (bad qpos/qvel/qacc), a non-finite
state, or any generalised velocity beyond ``MAX_SPEED``: MuJoCo warns only at
1e10, and a simulation on its way there can carry a walker hundreds of metres
in one control tick while still looking finite, which a GA would exploit.
"""

from __future__ import annotations

from typing import Callable

import mujoco
import numpy as np
from mujoco.batch import Batch, SimulationError

_VEL = mujoco.mjtStage.mjSTAGE_VEL
#: warnings that mean the state blew up: BADQPOS, BADQVEL, BADQACC, BADCTRL (this index and after)
FIRST_BAD_WARNING = int(mujoco.mjtWarning.mjWARN_BADQPOS)
#: m/s or rad/s; no part of a walker moves this fast (a 0.5 m link at 100 rad/s: 50 m/s at its tip)
MAX_SPEED = 100.0
_DATA_FIELDS = frozenset(mujoco.batch.DATA_FIELDS)


class Sims:
    """``n`` simulations of ``model``; fields are ``(n, ...)`` arrays.

    A batch is a value: :meth:`copy` (and ``copy.deepcopy``) gives an independent batch in the same
    state, which continues bit for bit as the original would.  ``extra`` holds what a body keeps per
    simulation beside MuJoCo's state (the Taga ground's contact points and pushes): name -> table of
    ``(n, ...)`` arrays, copied with the batch.  ``readings`` keeps what a body read of the current state
    (:meth:`kept`) until the state changes.
    """

    def __init__(self, model: mujoco.MjModel, n: int, *, nthread: int = 1):
        self.model = model
        self.n = n
        self.batch = Batch(model, nsim=n, nthread=nthread, persistent=True)
        self.extra: dict[str, dict[str, np.ndarray]] = {}
        #: what has been read of the current state, by name (a body's contacts and heading): kept until the state
        #: changes (:meth:`reset`, :meth:`forward`, :meth:`step`), so the parts of a control tick (the senses, the gait
        #: tracker, the task, the fall test) share one reading
        self.readings: dict[str, np.ndarray] = {}

    def copy(self) -> "Sims":
        """An independent batch of the same model in this batch's state (MuJoCo's full state and ``extra``)."""
        other = Sims(self.model, self.n, nthread=self.batch.nthread)
        other.batch.state[:] = self.batch.state
        other.batch.forward(stage=_VEL)
        other.extra = {k: {name: a.copy() for name, a in table.items()} for k, table in self.extra.items()}
        return other

    def __deepcopy__(self, memo: dict) -> "Sims":
        return self.copy()

    def __getattr__(self, name: str) -> np.ndarray:
        # qpos, qvel, ctrl, xpos, xquat, subtree_com, sensordata, ...: live views, bound on first use and kept as
        # attributes, so later reads (dozens per control tick) never come here again
        if name.startswith("_") or name not in _DATA_FIELDS:
            raise AttributeError(name)
        arr = self.__dict__[name] = self.batch.bind(name)
        return arr

    def kept(self, name: str, read: Callable[["Sims"], np.ndarray]) -> np.ndarray:
        """``read(self)`` of the current state, read once until the state changes; read-only, as every reader shares
        it."""
        got = self.readings.get(name)
        if got is None:
            got = self.readings[name] = read(self)
            got.flags.writeable = False
        return got

    def reset(self, ids: np.ndarray | None = None) -> None:
        """Simulations ``ids`` (default all) to the model's initial state, derived fields current."""
        self.readings.clear()
        self.batch.reset(ids=ids)
        self.batch.forward(ids=ids, stage=_VEL)

    def forward(self, ids: np.ndarray | None = None) -> None:
        """Recompute derived fields after the caller wrote qpos/qvel."""
        self.readings.clear()
        self.batch.forward(ids=ids, stage=_VEL)

    def step(self, ids: np.ndarray, nstep: int) -> np.ndarray:
        """Advance simulations ``ids`` by ``nstep`` physics steps.

        Returns a bool mask over ``ids`` of simulations that became unstable
        (MuJoCo error, warning such as bad QACC, non-finite state, or a
        velocity beyond ``MAX_SPEED``).
        Derived fields (xpos, subtree_com, sensordata) are current afterwards.
        """
        failed = np.zeros(len(ids), bool)
        if len(ids) == 0:
            return failed
        self.readings.clear()
        every = len(ids) == self.n  # all simulations (ids are sorted and unique): whole views, no copies
        rows = slice(None) if every else ids
        try:
            self.batch.step(ids=None if every else ids, nstep=nstep, stage=_VEL)
        except SimulationError as exc:
            failed |= np.isin(ids, exc.ids)
        # each warning's (lastinfo, number): its count, not its last info (a bad position at DOF 0 has info 0)
        warn = self.batch.warning[rows, FIRST_BAD_WARNING:, 1].any(axis=1)
        # NaN fails the comparison, so "not below the bound" catches it too
        wild = ~(np.abs(self.qvel[rows]) < MAX_SPEED).all(axis=1) | ~np.isfinite(self.qpos[rows]).all(axis=1)
        return failed | warn | wild
