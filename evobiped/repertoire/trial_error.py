"""Intelligent trial and error (Cully, Clune, Tarapore & Mouret 2015, *Robots that can adapt like animals*, M-BOA).

The archive's walking elites are the candidates, each at its measures x (scaled to [0, 1] by the archive's
bounds).  The prior of a gait's performance is what the archive predicts on the intact body: the distance a
walker at mean speed v (m/s) turning at w (rad/s) covers in T s, the chord 2 v / |w| |sin(w T / 2)| (v T when it
walks straight).  Performances are divided by the best prior, so the prior's best is 1.  A Gaussian process
with that prior as its mean and a Matern 5/2 kernel (length scale ``rho`` in scaled measure units, variance 1,
observation noise ``noise``) learns from each trial on the damaged body

    mu(x) = P(x) + k(x)^T (K + noise I)^-1 (y - P(X)),   s^2(x) = 1 - k(x)^T (K + noise I)^-1 k(x)

and the next trial is the untried elite with the highest upper confidence bound mu + kappa s.  The search stops
when a trial's performance reaches ``alpha`` times the best mu of any elite (Cully's stopping rule) and that
trial is acceptable (here: it walked; a caller's test, by default any), or after ``trials`` trials.  A trial's
performance: the distance from the start (m) times the fraction of the episode the walker stayed up (a fall costs
what it did not walk).  Cully's values: alpha 0.9, kappa 0.05, noise 1e-3.

Two baselines choose the next trial without the GP (``order``): ``prior`` tries the untried elite with the best
prior (the archive's prediction on the intact body, in order), ``random`` an untried elite drawn at random (a
seeded generator).  Both keep the GP's posterior only for the stopping rule, so the three orders differ in the
choice of trial and in nothing else.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np


@dataclass(frozen=True)
class Attempt:
    """One trial: the elite tried (row of the archive), what the GP predicted of it and what it did."""

    elite: int
    predicted: float  # m
    performance: float  # m: distance x time up / T
    distance: float  # m
    fell: bool
    end_time: float  # s


def prior_distance(speed: np.ndarray, turning_deg: np.ndarray, seconds: float) -> np.ndarray:
    """The distance (m) from the start after ``seconds`` s of a walker at ``speed`` m/s turning at ``turning_deg`` deg/s
    (the chord of its circle; ``(E,)`` each)."""
    w = np.radians(np.asarray(turning_deg, float))
    v = np.asarray(speed, float)
    safe = np.where(np.abs(w) < 1e-9, 1.0, w)
    return np.where(np.abs(w) < 1e-9, v * seconds, 2 * v / np.abs(safe) * np.abs(np.sin(safe * seconds / 2)))


def matern52(a: np.ndarray, b: np.ndarray, rho: float) -> np.ndarray:
    """Matern 5/2 kernel between rows of ``a`` ``(n, d)`` and ``b`` ``(m, d)`` -> ``(n, m)``, variance 1."""
    r = np.sqrt(((a[:, None, :] - b[None, :, :]) ** 2).sum(-1)) / rho
    return (1 + np.sqrt(5) * r + 5 / 3 * r**2) * np.exp(-np.sqrt(5) * r)


def posterior(x: np.ndarray, prior: np.ndarray, tried: list[int], y: np.ndarray, *, rho: float,
              noise: float) -> tuple[np.ndarray, np.ndarray]:
    """The GP's mean and standard deviation ``(E,)`` at every candidate ``x`` ``(E, d)`` after observing ``y`` at rows
    ``tried`` (prior mean ``prior`` ``(E,)``; all in units of the best prior)."""
    if not tried:
        return prior.copy(), np.ones(len(x))
    X = x[tried]
    K = matern52(X, X, rho) + noise * np.eye(len(tried))
    k = matern52(x, X, rho)
    mean = prior + k @ np.linalg.solve(K, y - prior[tried])
    var = 1.0 - np.einsum("ij,ji->i", k, np.linalg.solve(K, k.T))
    return mean, np.sqrt(np.maximum(var, 0.0))


#: how the next trial is chosen (:attr:`TrialAndError.order`)
ORDERS = ("ucb", "prior", "random")


@dataclass(frozen=True)
class TrialAndError:
    """Cully et al. 2015's settings (see the module docstring)."""

    alpha: float = 0.9
    kappa: float = 0.05
    rho: float = 0.15
    noise: float = 1e-3
    trials: int = 20
    order: str = "ucb"  # `ucb` (the GP's upper confidence bound), `prior` (best prior first) or `random`
    seed: int = 0  # the random order's generator

    def __post_init__(self):
        if self.order not in ORDERS:
            raise ValueError(f"order must be one of {', '.join(ORDERS)}, got {self.order!r}")

    def run(self, x: np.ndarray, prior_m: np.ndarray, trial: Callable[[int], tuple[float, bool, float, float]],
            acceptable: Callable[[Attempt], bool] = lambda attempt: True) -> list[Attempt]:
        """Search the candidates at ``x`` ``(E, d)`` (scaled measures) with prior performances ``prior_m`` ``(E,)`` m;
        ``trial(row) -> (distance m, fell, end_time s, seconds s)`` runs one elite on the damaged body.  Returns the
        trials in order; the last one met the stopping rule unless ``trials`` ran out.  ``acceptable(attempt)``: whether
        a trial may end the search."""
        scale = float(prior_m.max())
        prior = prior_m / scale
        tried: list[int] = []
        y: list[float] = []
        out: list[Attempt] = []
        shuffled = np.random.default_rng(self.seed).permutation(len(x)) if self.order == "random" else None
        while len(out) < min(self.trials, len(x)):
            mean, sd = posterior(x, prior, tried, np.array(y), rho=self.rho, noise=self.noise)
            ok = [i for i, a in enumerate(out) if acceptable(a)]
            if ok and max(y[i] for i in ok) >= self.alpha * mean.max():
                break
            k = self._next(mean, sd, prior, tried, shuffled)
            distance, fell, end_time, seconds = trial(k)
            perf = distance * end_time / seconds
            tried.append(k)
            y.append(perf / scale)
            out.append(Attempt(k, float(mean[k] * scale), float(perf), float(distance), bool(fell), float(end_time)))
        return out

    def _next(self, mean: np.ndarray, sd: np.ndarray, prior: np.ndarray, tried: list[int],
              shuffled: np.ndarray | None) -> int:
        """The next elite to try (an index of the candidates) by ``order``."""
        if shuffled is not None:
            return int(shuffled[len(tried)])
        score = mean + self.kappa * sd if self.order == "ucb" else prior.copy()
        score[tried] = -np.inf
        return int(np.argmax(score))
