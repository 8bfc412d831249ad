"""The GA (ask/tell), evaluation backends, and runs with checkpoints."""

from .evaluate import BACKENDS, make_evaluator
from .ga import GA, GAConfig
from .run import Run, RunConfig

__all__ = ["BACKENDS", "GA", "GAConfig", "Run", "RunConfig", "make_evaluator"]
