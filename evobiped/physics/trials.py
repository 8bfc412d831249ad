"""R perturbed presentations, drawn (``evobiped.physics.perturb.PerturbationOptions.draw``) or given (the robustness
battery's): each row's pushes, target offsets and noise, initial-pose noise, gene noise, ground, pelvis assistance
and sources, and how the presentations' fitness combines into a genome's (the aggregates)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: aggregate name -> ``((P, R) fitness, q) -> (P,)``
AGGREGATES = {
    "mean": lambda f, q: f.mean(axis=1),
    "worst": lambda f, q: f.min(axis=1),
    "q25": lambda f, q: np.quantile(f, 0.25, axis=1),
    "quantile": lambda f, q: np.quantile(f, q, axis=1),
}


@dataclass
class Trials:
    """R presentations' disturbances; arrays have R rows (``k`` pushes each)."""

    #: s, ``(R, k)``
    push_start: np.ndarray
    #: N, world frame, ``(R, k, 3)``
    push_force: np.ndarray
    #: s
    push_duration: float
    #: rad, ``(R, n_act)``
    target_offset: np.ndarray
    #: rad, standard deviation per tick
    target_noise: float = 0.0
    noise_seed: int = 0
    #: rad, ``(R, n_act)`` added to the actuated joints' initial angles
    pose_offset: np.ndarray | None = None
    #: floor sliding friction (None: the model's)
    friction: float | None = None
    #: grade (rise over run) of the floor, rising towards ``slope_direction``
    slope: float = 0.0
    #: rad: where the floor rises, in the initial-facing frame (0: ahead, pi/2: to the left, pi: behind)
    slope_direction: float = 0.0
    #: the gravity's share of the model's (1: as modelled; below 1: a slower fall, the gravity curriculum's)
    gravity: float = 1.0
    #: ``(R, G)``: noise added to every gene, in units of that gene's range (None: none)
    gene_noise: np.ndarray | None = None
    aggregate: str = "mean"
    #: N m/rad, ``(R,)``: the trunk's upright stiffness per presentation (None: no assistance)
    assist: np.ndarray | None = None
    #: s: damping (N m s/rad) per unit of that stiffness
    assist_damping: float = 0.05
    #: q of the ``quantile`` aggregate
    quantile: float = 0.25
    #: m, ``(S, 2)``: a generation's sources for a task that draws them (the steer task's random sources; None: its own)
    sources: np.ndarray | None = None

    @property
    def R(self) -> int:
        return len(self.target_offset)

    @classmethod
    def nominal(cls, R: int, n_actuators: int, **kw) -> "Trials":
        """R undisturbed presentations; keywords set the fields to change."""
        base = dict(push_start=np.zeros((R, 0)), push_force=np.zeros((R, 0, 3)), push_duration=0.1,
                    target_offset=np.zeros((R, n_actuators)))
        return cls(**{**base, **kw})

    def noise(self) -> "TargetNoise":
        return TargetNoise(self.target_noise, self.noise_seed, self.target_offset.shape)

    def push_at(self, t: float) -> np.ndarray:
        """The force on each presentation's trunk during the control period starting at ``t`` s: ``(R, 3)`` N."""
        on = (self.push_start <= t + 1e-9) & (t + 1e-9 < self.push_start + self.push_duration)
        return (self.push_force * on[..., None]).sum(axis=1)

    def combine(self, fitness: np.ndarray) -> np.ndarray:
        """``(P, R)`` presentation fitness -> ``(P,)`` by the aggregate."""
        return AGGREGATES[self.aggregate](fitness, self.quantile)


class TargetNoise:
    """Noise on the PD targets: one ``(R, n_act)`` draw per control tick, shared by every genome."""

    def __init__(self, sigma: float, seed: int, shape: tuple[int, int]):
        self.sigma, self.shape = float(sigma), shape
        self.rng = np.random.default_rng(seed)

    def next(self) -> np.ndarray | None:
        return self.rng.normal(0.0, self.sigma, self.shape) if self.sigma > 0 else None
