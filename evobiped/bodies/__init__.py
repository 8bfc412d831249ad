"""Bodies (one module per MJCF model) and their registry."""

from .base import Body
from .reil import ReilBiped
from .taga import TagaBiped

#: name -> Body class; a new body is tested by every registry-wide test once added here
BODIES: dict[str, type[Body]] = {
    ReilBiped.name: ReilBiped,
    TagaBiped.name: TagaBiped,
}

__all__ = ["BODIES", "Body", "ReilBiped", "TagaBiped"]
