"""Perturbed presentations: evolution under disturbance, and the trials of the robustness battery.

A genome can be evaluated on R presentations side by side in one batch, each
with its own disturbances (:class:`Trials`, one row per presentation):

* **pushes**: a horizontal force (N) on the walker's trunk (the Reil pelvis)
  for a duration (s), starting at given times;
* **target offsets**: a constant angle (rad) added to each PD target;
* **target noise**: Gaussian noise (rad) on each PD target, new every control tick;
* **initial-pose noise**: Gaussian noise (rad) on each actuated joint's angle at t = 0;
* **gene noise**: Gaussian noise on every gene of the genome, in units of that gene's range
  (the genome's neighbours: a walker on a flat optimum survives it);
* **ground**: the floor's sliding friction and a slope (grade, rise over run, rising
  towards a direction in the walker's initial-facing frame), the same for every row of a batch.
* **gravity** (a curriculum, not a disturbance): the model's gravity times ``gravity`` (1: as modelled), the
  same for every row of a generation; a schedule from below 1 up to 1 (e.g. ``{start = 0.25, end = 1.0,
  generations = 80}``) lets a network learn to balance a slower fall first (an inverted pendulum of length L
  falls with the time constant sqrt(L / g): at a quarter of g, half as fast).  The gait lab's measures that
  divide by g (cost of transport, Froude number) keep 9.81 m/s^2.
* **pelvis assistance** (a curriculum, not a disturbance): a roll/pitch stiffness
  k (N m/rad) and damping c = ``assist_damping`` k (N m s/rad) that hold the
  trunk upright, applied before every physics step (applied once per control
  tick it destabilises the light pelvis): the torque on the trunk is

      tau = k (z_b x e_z) - c (omega - (omega . e_z) e_z)

  with z_b the trunk's up axis and omega its angular velocity (world frame):
  about |tau| = k sin(tilt) towards upright, blind to the heading (no yaw torque).
  It fades to zero over ``assist_generations`` steps of a clock, k(c) =
  ``assist`` max(0, 1 - c / ``assist_generations``); the clock is the
  generation, or, with ``assist_gate`` > 0 m, the number of earlier generations
  whose best genome's fitness reached the gate (each reduction is earned by
  walking under the current assistance).  ``assist_levels`` scores each genome
  at several fractions of the current assistance, presentation r at
  ``assist_levels[r mod L]`` (e.g. [1, 0.5]: what the next reductions will ask).

:class:`PerturbationOptions` (``[episode.perturbations]`` in a config) says how
the trials of an evolutionary run are drawn: from (run seed, generation) only,
so every genome of a generation meets the same disturbances (common random
numbers: selection compares like with like), and neither a resume nor the
number of workers changes anything.  Every strength may be a schedule over the
generations (:mod:`evobiped.core.schedule`: a curriculum from mild to hard).  A
genome's fitness is the ``aggregate`` of its presentations' fitness:

* ``mean``: the mean over the R presentations;
* ``worst``: the minimum (a walker is as good as its worst trial);
* ``q25``: the lower quartile (linear interpolation), between the two;
* ``quantile``: the ``quantile`` (0 < q < 1, linear interpolation; itself schedulable).

``aggregate_later`` replaces ``aggregate`` from generation ``aggregate_from`` on
(e.g. the mean while walkers learn to walk, a low quantile once they do).

Replays, episodes and the robustness battery run the nominal (unperturbed)
episode unless trials are given explicitly.  What a generation's draw gives, the
presentations' disturbances themselves, is a :class:`~evobiped.physics.trials.Trials`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..core.errors import ConfigError
from ..core.options import check_fields, option, parse, scheduled
from .trials import AGGREGATES, Trials

#: the strengths that may be schedules over the generations (each >= 0; 0: that disturbance is off)
STRENGTHS = ("push_force", "target_offset", "target_noise", "pose_noise", "slope", "gene_noise")


def _friction(v) -> None:
    fr = tuple(v) if isinstance(v, (list, tuple)) else None
    if fr is None or len(fr) not in (0, 2) or any(not isinstance(x, (int, float)) or isinstance(x, bool)
                                                  or not math.isfinite(x) or x <= 0
                                                  for x in fr) or (fr and fr[0] > fr[1]):
        raise ConfigError(f"must be [] or [low, high] with 0 < low <= high, got {v!r}")


def _levels(v) -> None:
    lv = tuple(v) if isinstance(v, (list, tuple)) else None
    if not lv or any(not isinstance(x, (int, float)) or isinstance(x, bool) or not 0 <= x <= 1 for x in lv):
        raise ConfigError(f"must be a non-empty list of fractions 0 <= f <= 1, got {v!r}")


@dataclass(frozen=True, kw_only=True)
class PerturbationOptions:
    """How an evolutionary run draws each generation's perturbed presentations."""

    presentations: int = option(1, "R, presentations per genome (each with its own draws)", low=1, high=64,
                                integer=True)
    pushes: int = option(0, "pushes per presentation, each at a uniform random time in [push_after, T - push_duration]",
                         low=0, integer=True)
    push_force: float = option(10.0, "magnitude of each push (horizontal, uniform random direction)", unit="N", low=0,
                               schedule=True)
    push_duration: float = option(0.1, "duration of each push", unit="s", above=0)
    push_after: float = option(2.0, "no push before this time", unit="s", low=0)
    target_offset: float = option(0.0,
                                  "standard deviation of a constant offset on each PD target, one per presentation",
                                  unit="rad", low=0, schedule=True)
    target_noise: float = option(0.0, "standard deviation of the noise on each PD target at every control tick",
                                 unit="rad", low=0, schedule=True)
    pose_noise: float = option(0.0, "standard deviation of the noise on each actuated joint's initial angle",
                               unit="rad", low=0, schedule=True)
    friction: tuple[float, ...] = option((), "floor friction [low, high], one uniform draw per generation; [] keeps "
                                             "the model's",
                                         check=_friction, span="[], or 0 < low <= high", schedule=True)
    slope: float = option(0.0, "largest grade of the floor (rise over run), one draw per generation: a grade uniform "
                               "in [0, slope] rising towards a uniform random direction of the initial facing's frame",
                          low=0, high=0.5, schedule=True)
    gravity: float = option(1.0, "the gravity's share of the model's, the same for every presentation of a generation "
                                 "(a curriculum: a schedule from below 1 up to 1 slows the fall a network first "
                                 "learns to balance)", above=0, high=1, schedule=True)
    gene_noise: float = option(0.0, "standard deviation of the noise on every gene, in units of that gene's range, one "
                                    "draw per presentation, the same for every genome of a generation", low=0, below=1,
                               schedule=True)
    aggregate: str = option("mean", "how presentations combine into a genome's fitness", choices=tuple(AGGREGATES))
    quantile: float = option(0.25, "q of aggregate `quantile`: the fitness below which a fraction q of the "
                                   "presentations fall", above=0, below=1, schedule=True)
    aggregate_later: str | None = option(None, "the aggregate from generation `aggregate_from` on (none: `aggregate` "
                                               "throughout)", choices=tuple(AGGREGATES))
    aggregate_from: int = option(0, "the first generation of `aggregate_later`", low=0, integer=True)
    assist: float = option(0.0, "pelvis assistance at the start: roll/pitch stiffness holding the trunk upright, faded "
                                "to 0", unit="N m/rad", low=0)
    assist_generations: int = option(0, "steps of the assistance clock over which it fades linearly to zero (>= 1 with "
                                        "assist)", low=0, integer=True)
    assist_gate: float = option(0.0, "fitness a generation's best must reach for the clock to advance (0: the clock is "
                                     "the generation)", low=0)
    assist_levels: tuple[float, ...] = option((1.0,), "fractions of the current assistance, presentation r at levels[r "
                                                      "mod L]", check=_levels, span="[f, ...], 0 <= f <= 1")
    assist_damping: float = option(0.05, "assistance damping per unit stiffness (c = assist_damping k)", unit="s",
                                   low=0, high=1)

    def __post_init__(self):
        check_fields(self, "episode.perturbations")
        if not isinstance(self.friction, dict):
            object.__setattr__(self, "friction", tuple(float(v) for v in self.friction))
        object.__setattr__(self, "assist_levels", tuple(float(v) for v in self.assist_levels))
        if self.assist > 0 and self.assist_generations < 1:
            raise ConfigError("assist_generations: the assistance must fade to zero over >= 1 generations, got "
                              f"{self.assist_generations}")
        if self.assist > 0 and len(self.assist_levels) > self.presentations:
            raise ConfigError(f"assist_levels: {len(self.assist_levels)} levels need as many presentations "
                              f"(presentations = {self.presentations})")

    @classmethod
    def from_dict(cls, d: dict) -> "PerturbationOptions":
        return parse(cls, d, "episode.perturbations")

    @property
    def active(self) -> bool:
        """Anything to perturb (or several presentations to aggregate) in some generation."""
        strong = any(s.start > 0 or s.end > 0 for s in (scheduled(self, n) for n in STRENGTHS if n != "push_force"))
        fr = scheduled(self, "friction")
        gr = scheduled(self, "gravity")
        return (self.presentations > 1 or self.pushes > 0 or bool(fr.start) or bool(fr.end) or strong or self.assist > 0
                or gr.start != 1 or gr.end != 1)

    @property
    def comparable_from(self) -> int:
        """The first generation from which every schedule has reached its end and ``aggregate_later`` (if any) applies:
        from there on, generations meet disturbances of one distribution and their fitness compares (0: no schedule)."""
        ends = [s.after + s.generations
                for s in (scheduled(self, n) for n in (*STRENGTHS, "friction", "quantile", "gravity"))
                if s.start != s.end]
        return max([*ends, self.aggregate_from if self.aggregate_later is not None else 0, 0])

    def at(self, generation: int) -> dict:
        """Every scheduled option's value at ``generation`` (name -> number, friction a tuple)."""
        return {n: scheduled(self, n).at(generation) for n in (*STRENGTHS, "friction", "quantile", "gravity")}

    def aggregate_at(self, generation: int) -> str:
        """The aggregate of ``generation``."""
        return (self.aggregate_later if self.aggregate_later is not None and generation >= self.aggregate_from
                else self.aggregate)

    def assist_clock(self, generation: int, best: list[float]) -> int:
        """The assistance clock at ``generation``: the generation itself, or (gated) how many of the earlier
        generations' best fitness ``best`` (one per generation, in order) reached ``assist_gate``."""
        if self.assist_gate <= 0:
            return int(generation)
        return int(sum(b >= self.assist_gate for b in best[:generation]))

    def key(self, seed: int, generation: int, best: list[float]) -> tuple[int, ...]:
        """What a generation's trials are drawn from (:meth:`draw`): (run seed, generation), and the assistance clock
        when a gate on the earlier generations' best fitness ``best`` (one per generation, in order) sets it."""
        if self.assist > 0 and self.assist_gate > 0:
            return seed, generation, self.assist_clock(generation, best)
        return seed, generation

    def incomparable(self, generation: int, best: list[float]) -> bool:
        """Generation ``generation`` meets disturbances unlike the final ones: a schedule still changes, or the pelvis
        assistance is on (``best`` as in :meth:`key`); its fitness does not compare with a later generation's."""
        return generation < self.comparable_from or self.assist_at(self.assist_clock(generation, best)) > 0

    def helps(self, generation: int, best: list[float]) -> bool:
        """Generation ``generation``'s walkers are helped (``best`` as in :meth:`key`): the pelvis assistance holds
        them, or less than the model's gravity pulls them (a walker helped does not walk)."""
        return self.at(generation)["gravity"] < 1 or self.assist_at(self.assist_clock(generation, best)) > 0

    def assist_at(self, clock: int) -> float:
        """The assistance stiffness (N m/rad) at this clock: ``assist`` faded linearly to 0 over
        ``assist_generations``."""
        if self.assist <= 0:
            return 0.0
        return self.assist * max(0.0, 1.0 - clock / self.assist_generations)

    def draw(self, key: tuple[int, ...], *, seconds: float, n_actuators: int, n_genes: int | None = None) -> "Trials":
        """The trials of one generation, from ``key`` = (run seed, generation) only; ``n_genes``: the genome's
        length (needed for gene noise); a third element of ``key``, when given, is the assistance clock
        (:meth:`assist_clock`; default the generation)."""
        rng = np.random.default_rng([int(key[0]), int(key[1]), 0x7E57])
        v = self.at(int(key[1]))
        R, k = self.presentations, self.pushes
        last = max(self.push_after, seconds - self.push_duration)
        angle = rng.uniform(0.0, 2 * np.pi, (R, k))
        force = np.zeros((R, k, 3))
        force[..., 0], force[..., 1] = v["push_force"] * np.cos(angle), v["push_force"] * np.sin(angle)
        trials = Trials(
            push_start=rng.uniform(self.push_after, last, (R, k)),
            push_force=force,
            push_duration=self.push_duration,
            target_offset=rng.normal(0.0, v["target_offset"], (R, n_actuators)) if v["target_offset"]
                else np.zeros((R, n_actuators)),
            target_noise=v["target_noise"],
            noise_seed=int(rng.integers(2**63)),
            pose_offset=rng.normal(0.0, v["pose_noise"], (R, n_actuators)) if v["pose_noise"]
                else np.zeros((R, n_actuators)),
            friction=float(rng.uniform(*v["friction"])) if v["friction"] else None,
            aggregate=self.aggregate_at(int(key[1])),
            quantile=float(v["quantile"]),
        )
        # draws added after the ones above, only when used: a run without them draws exactly as before
        if v["slope"]:
            trials.slope, trials.slope_direction = float(v["slope"] * rng.uniform()), float(rng.uniform(-np.pi, np.pi))
        if v["gene_noise"]:
            if n_genes is None:
                raise ConfigError("episode.perturbations.gene_noise: these trials are drawn without a genome (no "
                                  "controller)")
            trials.gene_noise = rng.normal(0.0, v["gene_noise"], (R, n_genes))
        trials.gravity = float(v["gravity"])  # no draw: the gravity is the schedule's
        trials.assist = self._assist_rows(int(key[2]) if len(key) > 2 else int(key[1]))
        trials.assist_damping = self.assist_damping
        return trials

    def _assist_rows(self, clock: int) -> np.ndarray | None:
        """``(R,)`` N m/rad per presentation at this clock; None without assistance."""
        k = self.assist_at(clock)
        if k <= 0:
            return None
        levels = self.assist_levels
        return k * np.array([levels[r % len(levels)] for r in range(self.presentations)])
