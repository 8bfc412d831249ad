"""What a distillation is asked for: its settings (:class:`DistillOptions`) and the student's episode
(:func:`student_config`: the teacher's body and task, a ctrnn fit for senses)."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

from ..physics import gait
from ..bodies import body_class
from ..episode import EpisodeConfig
from ..core.errors import ConfigError
from ..core.options import option, parse

#: the student's controller options: every sense of the Reil body normalised, 40 neurons whose outputs follow
#: the update, ln-tau genes down to the control period, centre-crossing biases, the full-range motor map
STUDENT = dict(
    n_neurons=40, dt=0.02, motor="full", time_constants=[0.02, 5.0], tau_scale="log", outputs="after",
    normalise_inputs=True, input_weights=[-30.0, 30.0], input_sigma=1.0, centre_crossing=True,
)


@dataclass(frozen=True, kw_only=True)
class DistillOptions:
    """How a student is distilled from a teacher."""

    iterations: int = option(5, "DAgger iterations (the first runs the teacher alone)", low=1, high=100, integer=True)
    rollouts: int = option(16, "perturbed rollouts per iteration, side by side", low=1, high=1024, integer=True)
    seconds: float = option(20.0, "length of each rollout", unit="s", above=0, high=1000)
    beta0: float = option(0.5, "teacher's share of the executed targets in the second iteration, halved in each later "
                               "one", low=0, high=1)
    target_noise: float = option(0.01, "noise on the executed PD targets in the rollouts, per tick", unit="rad", low=0)
    pose_noise: float = option(0.02, "noise on the initial joint angles of the rollouts", unit="rad", low=0)
    window: int = option(200, "length of the windows fitted", unit="control ticks", low=2, high=10000, integer=True)
    burn_in: int = option(50, "ticks at the start of a window not scored (the network settles from rest)",
                          unit="control ticks", low=0, integer=True)
    steps: int = option(2000, "Adam steps after each iteration's data", low=1, high=10**6, integer=True)
    batch: int = option(32, "windows per Adam step", low=1, high=10**5, integer=True)
    learning_rate: float = option(1e-2,
                                  "Adam's initial learning rate (gene units), decaying tenfold over all the steps",
                                  above=0, high=1)

    select_seconds: float = option(200.0, "each iteration's student runs this long alone; the best is kept (0: the "
                                          "last one)", unit="s", low=0, high=10000)
    heading_limit: float = option(30.0, "selection prefers students walking within this angle of their initial facing",
                                  unit="deg", above=0, high=180)

    def __post_init__(self):
        if self.burn_in >= self.window:
            raise ConfigError(f"burn_in ({self.burn_in}) must be shorter than window ({self.window})")


def parse_options(values: dict) -> DistillOptions:
    """``DistillOptions`` from a table (a ``[distill]`` config section); one ConfigError line for a bad value."""
    return parse(DistillOptions, values, "distill")


def student_config(teacher_cfg: EpisodeConfig, overrides: dict[str, Any] | None = None, *,
                   seconds: float | None = None) -> EpisodeConfig:
    """The student's episode: the teacher's body and task, ``seconds`` long (default the teacher's), the ``ctrnn``
    controller with :data:`STUDENT` (and ``overrides``) reading every sensor the body declares a standing value for
    but the gait senses (:mod:`evobiped.physics.gait`: the teacher's phase is learnt from the instantaneous senses;
    ``inputs`` in ``overrides`` adds them); no latency, no perturbations."""
    senses = [n for n in body_class(teacher_cfg.body).sensor_norms if n not in gait.NAMES]
    opts = {**STUDENT, "inputs": senses, **(overrides or {})}
    if isinstance(opts.get("n_neurons"), (int, float)) and not isinstance(opts["n_neurons"],
                                                                          bool) and opts["n_neurons"] <= 0:
        raise ConfigError(f"student n_neurons must be > 0, got {opts['n_neurons']}")
    return dataclasses.replace(teacher_cfg, controller="ctrnn", controller_options=opts, perturbations={},
                               seconds=teacher_cfg.seconds if seconds is None else float(seconds))
