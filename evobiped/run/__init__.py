"""An evolutionary run: its settings (:class:`RunConfig`), the run directory it lives in generation by generation
(:class:`Run`), its checkpoint, per-generation context (normaliser, curriculum) and stopping rule."""

from .run import Run
from .run_config import RunConfig

__all__ = ["Run", "RunConfig"]
