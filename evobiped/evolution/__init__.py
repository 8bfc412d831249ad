"""The GA (ask/tell), evaluation backends, and runs with checkpoints."""

from .evaluate import BACKENDS, Evaluation, make_evaluator
from .ga import GA, GAConfig
from .run import Run, RunConfig

__all__ = ["BACKENDS", "GA", "GAConfig", "Evaluation", "Run", "RunConfig", "make_evaluator"]
