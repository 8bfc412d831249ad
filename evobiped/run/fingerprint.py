"""What a run was created with, kept in its checkpoint, and what a resume finds changed since.

config.json is a file a person may edit; the checkpoint records the settings
the run was made with (``settings``: config.json's, less where the episodes
run, which no result depends on) and the numerical environment config.json
said it started in (``environment``: a resume elsewhere is noted, an edited
record refused).  A resume compares the two and refuses any difference by name
(``seed 5 → 6``): a resumed run never silently mixes two experiments.  Both sides are read through
:meth:`RunConfig.from_dict` first, so a setting added to evobiped since the run began (its default on both sides) is
no difference.
"""

from __future__ import annotations

from typing import Any

from ..core.errors import ConfigError, UserError
from ..core.fileio import json_text
from .run_config import RunConfig

#: settings that say where the episodes run, not what they compute (a resume may change them with flags)
PLACE = ("backend", "workers", "address")


def settings(config: RunConfig, environment: Any = None) -> dict:
    """The settings a checkpoint records: ``config.to_dict()`` less :data:`PLACE`, and config.json's ``environment``
    (None: none recorded)."""
    out = {k: v for k, v in config.to_dict().items() if k not in PLACE}
    if environment is not None:
        out[ENVIRONMENT] = environment
    return out


#: the key of the numerical environment the run started in (config.json's, :func:`evobiped.core.provenance.current`)
ENVIRONMENT = "environment"


def _flat(d: Any, prefix: str = "") -> dict[str, Any]:
    if isinstance(d, dict) and d:
        return {k: v for name, sub in d.items() for k, v in _flat(sub, f"{prefix}{name}.").items()}
    return {prefix[:-1]: d}


def _text(v: Any) -> str:
    return "(not set)" if v is _MISSING else json_text(v).strip().replace("\n", " ").replace("  ", "")


_MISSING = object()


def changes(recorded: Any, config: RunConfig, environment: Any = None) -> list[str]:
    """``setting old → new`` for each setting of ``config`` (and of config.json's ``environment``) that differs
    from the ``recorded`` one (empty: none)."""
    if not isinstance(recorded, dict):
        return ["the recorded settings are not a table"]
    recorded = dict(recorded)
    started_in = recorded.pop(ENVIRONMENT, None)
    try:
        then = settings(RunConfig.from_dict(recorded, where=""), started_in)
    except ConfigError as exc:
        return [f"the recorded settings are unreadable ({exc})"]
    old, new = _flat(then), _flat(settings(config, environment if started_in is not None else None))
    return [f"{k} {_text(old.get(k, _MISSING))} → {_text(new.get(k, _MISSING))}"
            for k in dict.fromkeys([*old, *new]) if old.get(k, _MISSING) != new.get(k, _MISSING)]


def check(recorded: Any, config: RunConfig, environment: Any, config_path) -> None:
    """UserError (one line naming what changed) unless ``config`` and config.json's ``environment`` are the ``recorded``
    ones."""
    diff = changes(recorded, config, environment)
    if diff:
        more = f" (and {len(diff) - 3} more)" if len(diff) > 3 else ""
        raise UserError(f"{config_path} differs from the one this checkpoint was made with: "
                        f"{'; '.join(diff[:3])}{more}; restore it, or start a new run with the new settings")
