"""The mirrored stance/swing frame: one set of weights serves both legs of a bilateral body.

A bilateral body declares how its readings and actions change when the body is
mirrored left-to-right (:attr:`Body.mirror`, :attr:`Body.actuator_mirror`; a task
its own senses, :meth:`Task.sensor_mirror`): for each sensor a permutation of
its columns and a sign per column, so that the mirrored body's reading is

    x'_i = sign_i * x_{perm_i}

(the legs' columns swap; lateral quantities such as a roll angle, a sideways
velocity or a heading error change sign; a model whose roll axes are already
mirrored keeps their signs).  A controller with ``frame = "stance"`` always sees
the body as if its stance leg were the first leg of the contact sensor (the
Reil body's left): on rows whose stance leg is the other one
(``stance_leg`` = -1, :mod:`evobiped.physics.gait`) its inputs are mirrored before it
reads them and its actions mirrored back before the body takes them.  So the
controller's inputs read "stance side, then swing side" and its outputs are
stance-leg and swing-leg targets, whichever leg stands.
"""

from __future__ import annotations

from typing import Mapping

import numpy as np

from ..core.errors import ConfigError

#: the frames a controller may take (``frame`` controller option)
FRAMES = ("body", "stance")

#: a sensor's mirror: (column permutation, sign per column)
Mirror = tuple[tuple[int, ...], tuple[float, ...]]


def check_mirror(name: str, width: int, mirror: Mirror) -> None:
    """ConfigError unless ``mirror`` is an involution of ``width`` columns with signs +-1."""
    perm, sign = mirror
    p = np.asarray(perm)
    s = np.asarray(sign, float)
    if p.shape != (width,) or s.shape != (width,) or sorted(p.tolist()) != list(range(width)):
        raise ConfigError(f"mirror of {name!r}: needs a permutation and a sign for each of its {width} columns")
    if not np.all(np.abs(s) == 1) or not np.array_equal(p[p], np.arange(width)) or not np.all(s * s[p] == 1):
        raise ConfigError(f"mirror of {name!r}: mirroring twice must give the reading back (an involution with signs "
                          "+-1)")


class StanceFrame:
    """The stance frame for one wiring: ``inputs`` ``{sensor: width}`` in input order, their declared mirrors,
    and the actions' mirror (permutation and signs over the action vector)."""

    def __init__(self, inputs: Mapping[str, int], mirrors: Mapping[str, Mirror], actions: Mirror, *,
                 what: str = "controller"):
        missing = [n for n in inputs if n not in mirrors]
        if missing:
            raise ConfigError(f"{what}: frame 'stance' needs a left/right mirror of every input; none is declared for "
                              f"{', '.join(missing)}")
        perm, sign, start = [], [], 0
        for n, w in inputs.items():
            check_mirror(n, w, mirrors[n])
            perm += [start + i for i in mirrors[n][0]]
            sign += list(mirrors[n][1])
            start += w
        self.input_perm, self.input_sign = np.array(perm, int), np.array(sign, float)
        check_mirror("actions", len(actions[0]), actions)
        self.action_perm, self.action_sign = np.array(actions[0], int), np.array(actions[1], float)

    def inputs(self, x: np.ndarray, flip: np.ndarray) -> np.ndarray:
        """Readings ``(P, k)`` in the stance frame: rows ``flip`` ``(P,)`` bool mirrored."""
        return _mirrored(x, flip, self.input_perm, self.input_sign)

    def swapped(self, a: np.ndarray, rows: np.ndarray, per_unit: int = 1) -> np.ndarray:
        """A controller's per-actuator state ``(P, n_act * per_unit)`` (``per_unit`` columns for each actuator, in
        action order) with the legs' units swapped on rows ``rows`` ``(P,)`` bool (no signs: a neuron's state is
        not a direction)."""
        perm = (self.action_perm[:, None] * per_unit + np.arange(per_unit)).ravel()
        return np.where(rows[:, None], a[:, perm], a)

    def follow(self, state: dict, flip: np.ndarray, per_unit: dict[str, int]) -> dict:
        """A rhythm generator's ``state`` (its arrays ``per_unit`` = {name: columns per actuator}, and ``flip``: the
        rows whose second leg stood at the last tick) in this tick's frame ``flip`` ``(P,)``: where the stance leg
        changed, the legs' units swap places, so each leg's oscillator stays on its leg."""
        changed = flip != state["flip"]
        if not changed.any():
            return state
        return {**state, **{k: self.swapped(state[k], changed, m) for k, m in per_unit.items()}, "flip": flip.copy()}

    def actions(self, a: np.ndarray, flip: np.ndarray) -> np.ndarray:
        """Stance-frame actions ``(P, n_act)`` back on the body's legs: rows ``flip`` mirrored."""
        return _mirrored(a, flip, self.action_perm, self.action_sign)


def _mirrored(a: np.ndarray, flip: np.ndarray, perm: np.ndarray, sign: np.ndarray) -> np.ndarray:
    """``a`` ``(P, k)`` with rows ``flip`` replaced by their mirror ``sign * a[:, perm]`` (``a`` itself if none
    flips)."""
    if not flip.any():
        return a
    return np.where(flip[:, None], a[:, perm] * sign, a)
