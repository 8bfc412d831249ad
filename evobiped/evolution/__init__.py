"""Optimizers behind one ask/tell seam (the GA, CMA-ES), evaluation backends, and runs with checkpoints."""

from .base import Optimizer
from .evaluate import BACKENDS, make_evaluator
from .ga import GA, GAOptions
from .run import Run
from .run_config import RunConfig

__all__ = ["BACKENDS", "GA", "GAOptions", "Optimizer", "Run", "RunConfig", "make_evaluator"]
