"""Taga's rhythm-generator parameters (Taga, Yamaguchi & Shimizu 1991, Appendix D) as matsuoka genomes.

The matsuoka controller (:mod:`evobiped.controllers.matsuoka`) evolves these
values as genes; a preset gives the published ones for a controller's genome
layout, by joint role within a leg (hip, knee, ankle; roles beyond the ankle
take the ankle's): time constants tau and tau' (s), output gains p_e and p_f
(N m), adaptation beta, the weights w_fe, w_rl, w_hka, and, with feedback,
the gains a_1..a_8 of Appendix C.
"""

from __future__ import annotations

import numpy as np

from ...controllers.matsuoka import Matsuoka
from ...core.errors import ConfigError

#: Appendix D, by joint role within a leg (hip, knee, ankle): tau, tau' (s), p_e, p_f (N m)
TAGA_ROLE = {
    "tau": (0.05, 0.025, 0.025),
    "tau_adapt": (0.60, 0.30, 0.30),
    "p_e": (85.0, 15.0, 75.0),
    "p_f": (15.0, 15.0, 100.0),
}
TAGA_SCALARS = {"beta": 2.5, "w_fe": -2.0, "w_rl": -1.0, "w_hka": -1.0}
#: a_1..a_8 (Appendix D, feedback)
TAGA_FEEDBACK = (1.5, 1.0, 1.5, 1.5, 3.0, 1.5, 3.0, 1.5)

#: preset name -> (per-role values, scalars, feedback gains)
PRESETS = {"taga": (TAGA_ROLE, TAGA_SCALARS, TAGA_FEEDBACK)}


def preset_genome(controller: Matsuoka, name: str = "taga") -> np.ndarray:
    """The preset's values as a genome ``(G,)`` of ``controller``'s layout (the feedback gains only where it has
    the feedback block); ConfigError naming the presets for an unknown one."""
    if name not in PRESETS:
        raise ConfigError(f"matsuoka: unknown preset {name!r} (choose from {', '.join(PRESETS)})")
    role, scalars, feedback = PRESETS[name]
    r = np.minimum(controller.roles(), 2)
    parts = {b: np.array(v)[r] for b, v in role.items()}
    parts.update({b: np.array([v]) for b, v in scalars.items()})
    parts["feedback"] = np.array(feedback)
    return np.concatenate([parts[b.name] for b in controller.layout.blocks])
