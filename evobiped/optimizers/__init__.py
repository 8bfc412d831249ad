"""Optimizers behind one ask/tell seam (:class:`~.base.Optimizer`): Reil & Husbands' GA, CMA-ES, evolution strategies
(OpenAI-ES, ARS) and MAP-Elites, and their registry (:data:`OPTIMIZERS`): each registers its name, its settings
(``Options``) and the run config's table they are read from."""

from .base import Optimizer
from .cma import CMAES, CMAOptions
from .es import ESOptions, EvolutionStrategy
from .ga import GA, GAOptions
from .map_elites import MapElites, MapElitesOptions

#: optimizer name -> class; each an :class:`~.base.Optimizer` (ask/tell/ranking/next_generation) with state/restore,
#: its ``Options`` and the config table they are read from (``table``)
OPTIMIZERS: dict[str, type[Optimizer]] = {cls.name: cls for cls in (GA, CMAES, EvolutionStrategy, MapElites)}


def described(quote: str = "`") -> str:
    """Every registered optimizer with what it is: "`ga` (Reil & Husbands' GA), `cma` (CMA-ES), ... or `map-elites`
    (...)"."""
    items = [f"{quote}{name}{quote} ({cls.about})" for name, cls in OPTIMIZERS.items()]
    return ", ".join(items[:-1]) + " or " + items[-1] if len(items) > 1 else items[0]


__all__ = ["CMAES", "CMAOptions", "ESOptions", "EvolutionStrategy", "GA", "GAOptions", "MapElites", "MapElitesOptions",
           "OPTIMIZERS", "Optimizer", "described"]
