"""Bodies (one module per MJCF model) and their registry."""

from .base import Body
from .reil import ReilBiped

#: name -> Body class; a new body is tested by every registry-wide test once added here
BODIES: dict[str, type[Body]] = {
    ReilBiped.name: ReilBiped,
}

__all__ = ["BODIES", "Body", "ReilBiped"]
