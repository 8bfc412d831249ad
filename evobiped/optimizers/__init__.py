"""Optimizers behind one ask/tell seam (:class:`~.base.Optimizer`): Reil & Husbands' GA, CMA-ES, evolution strategies
(OpenAI-ES, ARS) and MAP-Elites, and their registry (:data:`OPTIMIZERS`)."""

from .base import Optimizer
from .cma import CMAES, CMAOptions
from .es import ESOptions, EvolutionStrategy
from .ga import GA, GAOptions
from .map_elites import MapElites, MapElitesOptions

#: optimizer name -> class; each an :class:`~.base.Optimizer` (ask/tell/ranking/next_generation) with state/restore
OPTIMIZERS = {"ga": GA, "cma": CMAES, "es": EvolutionStrategy, "map-elites": MapElites}

__all__ = ["CMAES", "CMAOptions", "ESOptions", "EvolutionStrategy", "GA", "GAOptions", "MapElites", "MapElitesOptions",
           "OPTIMIZERS", "Optimizer"]
