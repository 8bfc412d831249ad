"""Bodies (one module per MJCF model) and their registry; a biped of the user's own is ``mjcf:PATH``, its class made
from the model and its declaration (:mod:`.declared`)."""

from .base import Body
from .reil import ReilBiped
from .taga import TagaBiped

#: name -> Body class; a new body is tested by every registry-wide test once added here
BODIES: dict[str, type[Body]] = {
    ReilBiped.name: ReilBiped,
    TagaBiped.name: TagaBiped,
}

#: the prefix of a declared body's name: ``mjcf:PATH`` (an MJCF model and its declaration)
DECLARED = "mjcf:"


def declared_name(name: str) -> str:
    """``mjcf:PATH`` with PATH absolute (a shipped model's stem, ``mjcf:box_biped``, stays as it is)."""
    from pathlib import Path

    spec = name[len(DECLARED):]
    return name if "/" not in spec and not Path(spec).suffix else DECLARED + str(Path(spec).expanduser().resolve())


def body_class(name: str) -> type[Body]:
    """The body class of ``name``: a registered one, or the one declared by ``mjcf:PATH`` (ConfigError: neither)."""
    if isinstance(name, str) and name.startswith(DECLARED):
        from .declared import declared_body

        return declared_body(name[len(DECLARED):])
    if name not in BODIES:
        from ..core.errors import ConfigError

        raise ConfigError(f"episode.body: unknown body {name!r} (choose from {', '.join(sorted(BODIES))}, "
                          f"or {DECLARED}PATH for an MJCF biped with its declaration)")
    return BODIES[name]


__all__ = ["BODIES", "DECLARED", "Body", "ReilBiped", "TagaBiped", "body_class", "declared_name"]
