"""Named run settings shipped with the package (``evobiped evolve --preset NAME``).

Each preset is a TOML file in ``evobiped/presets/`` in the format of
``evobiped evolve --config``; its first line is a ``#`` comment that says
what it is.  A ``--config`` file and command-line flags override a preset.
A ``[preset]`` table declares what the preset itself needs and is no run
setting: ``needs_start = true`` for one that tunes a given genome (the run
is refused without ``--from``).
"""

from __future__ import annotations

from pathlib import Path

from ..core.errors import UserError

DIRECTORY = Path(__file__).resolve().parent.parent / "presets"


def names() -> list[str]:
    """The shipped presets, sorted."""
    return sorted(p.stem for p in DIRECTORY.glob("*.toml"))


def path(name: str) -> Path:
    """The preset's file (UserError naming the choices for an unknown name)."""
    if name not in names():
        raise UserError(
            f"unknown preset {name!r} (choose from {', '.join(names())}; `evobiped presets` describes them)")
    return DIRECTORY / f"{name}.toml"


def describe(name: str) -> str:
    """The preset's one-line description (its first comment line)."""
    first = path(name).read_text().splitlines()[0]
    return first.lstrip("#").strip()


#: the ``[preset]`` table's declarations and their defaults
DECLARATIONS = {"needs_start": False}


def split_declarations(name: str, table: dict) -> tuple[dict, dict]:
    """Preset ``name``'s table (its TOML) -> its run settings and its declarations (:data:`DECLARATIONS`, checked)."""
    table = dict(table)
    declared = table.pop("preset", {})
    unknown = set(declared) - set(DECLARATIONS) if isinstance(declared, dict) else None
    if unknown is None or unknown or not all(isinstance(v, bool) for v in declared.values()):
        raise UserError(f"preset {name}: [preset] may only declare {', '.join(DECLARATIONS)} (true or false)")
    return table, {**DECLARATIONS, **declared}


def merge(base: dict, over: dict) -> dict:
    """``over`` on top of ``base``, tables merged key by key."""
    out = dict(base)
    for k, v in over.items():
        out[k] = merge(out[k], v) if isinstance(v, dict) and isinstance(out.get(k), dict) else v
    return out
