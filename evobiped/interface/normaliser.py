"""Observation normalisation kept by a run: running mean and standard deviation of the senses visited.

Evolution strategies on raw senses meet inputs of very different scales (a
contact flag of 0/1, a joint rate of several rad/s); a policy sees each input
as (x - mean) / std over the states its walkers have visited so far (Salimans
et al. 2017; Mania et al. 2018).  Each generation's walkers add the sums of what
they sensed (ES: its evaluation rows, theta itself; the GA, CMA-ES and
MAP-Elites, which have no rows of their own for the generation: every row they
evaluated) (:class:`SenseSums`, collected by the episode); the
statistics are merged exactly (Chan, Golub & LeVeque's pairwise form of
Welford's update), so the result does not depend on how the rows were split
into batches, and the normaliser used by generation g is the one made from
generations 0 .. g-1 (the first generation uses the declared standing values
and scales).

The std is floored per input: ``floor`` times the declared scale (so an input
that barely varied so far does not blow up when it first moves), and an
absolute floor for named sensors (a foot-contact flag, 0.5).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..core.errors import UserError


@dataclass
class SenseSums:
    """What some rows sensed: ``count`` ticks, ``total`` ``(k,)`` and ``squares`` ``(k,)`` sums of each input."""

    count: float
    total: np.ndarray
    squares: np.ndarray


@dataclass(frozen=True)
class Normaliser:
    """Running statistics of k inputs: ``count`` ticks, ``mean`` ``(k,)``, ``m2`` ``(k,)`` (sum of squared
    deviations)."""

    count: float
    mean: np.ndarray
    m2: np.ndarray

    @classmethod
    def empty(cls, k: int) -> "Normaliser":
        return cls(0.0, np.zeros(k), np.zeros(k))

    def add(self, sums: SenseSums) -> "Normaliser":
        """These statistics merged with ``sums`` (a new value)."""
        n_b = float(sums.count)
        if n_b <= 0:
            return self
        mean_b = sums.total / n_b
        m2_b = np.maximum(sums.squares - n_b * mean_b * mean_b, 0.0)
        n = self.count + n_b
        delta = mean_b - self.mean
        mean = self.mean + delta * (n_b / n)
        m2 = self.m2 + m2_b + delta * delta * (self.count * n_b / n)
        return Normaliser(n, mean, m2)

    def centre_scale(self, declared: tuple[np.ndarray, np.ndarray], floor: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(centre (k,), scale (k,))`` to normalise with: the declared ones until a tick was seen, then the
        running mean and std, the std at least ``floor`` ``(k,)``."""
        if self.count < 2:
            return declared
        std = np.sqrt(self.m2 / self.count)
        return self.mean.copy(), np.maximum(std, floor)

    def to_dict(self) -> dict:
        return {"count": self.count, "mean": [float(v) for v in self.mean], "m2": [float(v) for v in self.m2]}

    @classmethod
    def from_dict(cls, table, k: int, where: str = "checkpoint: normaliser") -> "Normaliser":
        """Read back :meth:`to_dict` (UserError, one line, when it is malformed or not ``k`` wide)."""
        try:
            count = float(table["count"])
            mean, m2 = np.array(table["mean"], float), np.array(table["m2"], float)
        except (TypeError, KeyError, ValueError):
            raise UserError(f"{where}: must be a table of count, mean and m2") from None
        if mean.shape != (k,) or m2.shape != (k,) or not (np.isfinite(mean).all() and np.isfinite(m2).all()
                                                          and count >= 0) \
                or (m2 < 0).any():
            raise UserError(f"{where}: needs {k} finite means and non-negative m2 values and a count >= 0")
        return cls(count, mean, m2)


def frozen_table(centre: np.ndarray, scale: np.ndarray, count: float) -> dict:
    """The ``input_norm`` controller option a genome file freezes: what its walker was normalised with."""
    return {"mean": [float(v) for v in centre], "std": [float(v) for v in scale], "count": float(count)}
