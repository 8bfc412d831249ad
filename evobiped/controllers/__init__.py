"""Controllers (one module each) and their registry."""

from .base import Controller
from .ctrnn import CTRNN
from .g3 import G3Controller
from .linear import Linear
from .matsuoka import Matsuoka
from .open_loop import OpenLoop
from .simbicon import Simbicon

# : name -> Controller class; constructed as cls(options, n_outputs=..., inputs={sensor: width},
# actuators=body.actuators)
#: after the episode checks its Needs against the body and task (evobiped.interface.contract)
CONTROLLERS: dict[str, type[Controller]] = {
    CTRNN.name: CTRNN,
    G3Controller.name: G3Controller,
    Linear.name: Linear,
    Matsuoka.name: Matsuoka,
    OpenLoop.name: OpenLoop,
    Simbicon.name: Simbicon,
}

__all__ = ["CONTROLLERS", "CTRNN", "Controller", "G3Controller", "Linear", "Matsuoka", "OpenLoop", "Simbicon"]
