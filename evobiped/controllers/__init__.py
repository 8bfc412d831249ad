"""Controllers (one module each) and their registry."""

from .base import Controller
from .ctrnn import CTRNN

#: name -> Controller class; constructed as cls(n_outputs=..., inputs={name: width}, **options)
CONTROLLERS: dict[str, type[Controller]] = {
    CTRNN.name: CTRNN,
}

__all__ = ["CONTROLLERS", "CTRNN", "Controller"]
