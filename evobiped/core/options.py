"""Typed options: each body, controller, task and optimizer declares its settings as a dataclass.

A field is declared with :func:`option` (default, meaning, unit and bounds in
its metadata); :func:`parse` checks a table of settings against the dataclass
once, when a config is loaded, and names the setting's path in the one-line
error (``episode.body_options.kp: must be > 0, got -5``).  The parsed object is
frozen and is what every constructor takes; it remembers which settings its
table gave (:func:`given`), so a config writes back what it read.  Checks that relate
several fields live in the dataclass's ``__post_init__`` (ConfigError).
:func:`markdown_table` renders the declarations (:mod:`evobiped.readme` puts
them in the README).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import MISSING, field, fields
from typing import Any, Callable, Collection

from .errors import ConfigError
from .schedule import Schedule
from .validate import number


def option(default: Any, doc: str, *, unit: str = "", low: float | None = None, high: float | None = None,
           above: float | None = None, below: float | None = None, integer: bool = False,
           choices: Collection | None = None,
           check: Callable[[Any], None] | None = None, span: str = "", schedule: bool = False) -> Any:
    """A dataclass field: ``default``, its meaning ``doc`` and ``unit``, and what values it takes.

    ``low``/``high``/``above``/``below``/``integer``: a number in that range; ``choices``: one of these (a registry
    itself, read when a value is checked, so that one registered later counts);
    a bool default: true or false; ``check(value)``: anything else (ConfigError without the
    path); ``span``: the range as the README shows it when ``check`` decides it.  A None
    default also takes None.  ``schedule``: the value may also be a schedule over the generations
    (:class:`~evobiped.core.schedule.Schedule`: a table whose ``start`` and ``end`` are each checked as a plain value);
    read it with :func:`scheduled`.
    """
    meta = dict(doc=doc, unit=unit, low=low, high=high, above=above, below=below, integer=integer, choices=choices,
                check=check, span=span, schedule=schedule)
    if isinstance(default, (list, dict)):
        return field(default_factory=lambda: type(default)(default), metadata=meta)
    return field(default=default, metadata=meta)


@dataclasses.dataclass(frozen=True, kw_only=True)
class NoOptions:
    """The options of a component that has none."""


def _check(f: dataclasses.Field, value: Any, path: str) -> None:
    if f.metadata.get("schedule"):
        Schedule.of(value, path, lambda v, p: _check_value(f, v, p))
    else:
        _check_value(f, value, path)


def scheduled(options: Any, name: str) -> Schedule:
    """The schedule of option ``name`` of the parsed ``options`` (a constant one for a plain value)."""
    return Schedule.of(getattr(options, name))


def _check_value(f: dataclasses.Field, value: Any, path: str) -> None:
    m = f.metadata
    default = f.default if f.default is not MISSING else f.default_factory()
    if value is None and default is None:
        return
    if isinstance(default, bool):
        if not isinstance(value, bool):
            raise ConfigError(f"{path}: must be true or false, got {value!r}")
    elif m.get("choices") is not None:
        if value not in m["choices"]:
            raise ConfigError(f"{path}: must be one of "
                              f"{', '.join(repr(c) if c == '' else str(c) for c in m['choices'])}, got {value!r}")
    elif any(m.get(k) is not None for k in ("low", "high", "above", "below")) or m.get("integer") or (
            isinstance(default, (int, float)) and m.get("check") is None):
        number(value, f"{path}:", low=m["low"], high=m["high"], above=m["above"], below=m["below"],
               integer=m["integer"], unit=m["unit"])
    if m.get("check") is not None:
        try:
            m["check"](value)
        except ConfigError as exc:
            raise ConfigError(f"{path}: {exc}") from None


def join(where: str, name: str) -> str:
    """The path of setting ``name`` inside ``where`` (e.g. ``episode.body_options`` + ``kp``)."""
    return f"{where}.{name}" if where else name


def refuse_unknown(cls: type, values: Any, where: str, *, skip: tuple[str, ...] = ()) -> dict:
    """``values`` if it is a table of ``cls``'s fields (and ``skip``); ConfigError naming the first unknown one."""
    if not isinstance(values, dict):
        raise ConfigError(f"{where or 'settings'}: must be a table of options, got {values!r}")
    inherited = {f.name for base in cls.__mro__[1:] if dataclasses.is_dataclass(base) for f in fields(base)}
    known = [f.name for f in fields(cls) if f.name not in inherited] + [f.name for f in fields(cls)
                                                                        if f.name in inherited]
    for name in values:
        if name not in known and name not in skip:
            raise ConfigError(f"{join(where, name)}: unknown option (choose from {', '.join([*known, *skip])})")
    return values


def check_fields(obj: Any, where: str) -> None:
    """Check every declared field of the dataclass ``obj`` (a ``__post_init__`` calls it); ConfigError naming its
    path."""
    for f in fields(obj):
        if f.metadata:
            _check(f, getattr(obj, f.name), join(where, f.name))


def parse(cls: type, values: Any, where: str, *, skip: tuple[str, ...] = ()) -> Any:
    """``cls(**values)`` after checking every value; ConfigError naming ``where.name`` for a bad one
    (``where: ...`` for one that the dataclass's ``__post_init__`` refuses).

    ``skip``: keys handled elsewhere (left out of the dataclass, not refused).
    """
    if isinstance(values, cls):
        return values
    refuse_unknown(cls, values, where, skip=skip)
    known = {f.name: f for f in fields(cls)}
    for name, value in values.items():
        if name not in skip:
            _check(known[name], value, join(where, name))
    try:
        parsed = cls(**{k: v for k, v in values.items() if k not in skip})
    except ConfigError as exc:
        raise ConfigError(f"{where}: {exc}") from None
    object.__setattr__(parsed, "_given", tuple(k for k in values if k not in skip))
    return parsed


def constructor_options(cls: type, options: Any, keywords: dict, where: str) -> Any:
    """What a constructor takes: the parsed ``options`` (an instance of ``cls``) as it is, or (Python use) the
    ``keywords`` parsed; ConfigError for both at once."""
    if options is not None and keywords:
        raise ConfigError(f"{where}: give one Options object or keyword settings, not both")
    return parse(cls, keywords if options is None else options, where)


def given(options: Any) -> dict:
    """The settings of a parsed options object that its table gave, in their order (what a config file
    writes back: the defaults it left out stay out); {} for one made with its defaults."""
    return {k: getattr(options, k) for k in getattr(options, "_given", ())}


def replace(options: Any, where: str, **changes: Any) -> Any:
    """``options`` with ``changes`` (checked as :func:`parse` checks them), the changed settings given beside
    the ones it had."""
    return parse(type(options), {**given(options), **changes}, where)


def check_value(cls: type, name: str, value: Any, label: str) -> Any:
    """``value`` if option ``name`` of ``cls`` takes it (as :func:`parse` checks it), else ConfigError naming ``label``
    (a command-line flag such as ``--bg``): a command's flags go through the same declarations as a config."""
    _check(next(f for f in fields(cls) if f.name == name), value, label)
    return value


def option_bounds(cls: type, name: str) -> tuple[float | None, float | None]:
    """The declared ``(low, high)`` of option ``name`` of ``cls`` (e.g. to check it in another unit)."""
    m = next(f for f in fields(cls) if f.name == name).metadata
    return m.get("low"), m.get("high")


def _span(m: dict, default: Any) -> str:
    if m.get("schedule"):
        return _span({**m, "schedule": False}, default) + " (or a schedule)"
    if m.get("span"):
        return m["span"]
    if m.get("choices") is not None:
        return ", ".join(f"`{c}`" for c in m["choices"])
    if isinstance(default, bool):
        return "`true`, `false`"
    low, high, above, below = (m.get(k) for k in ("low", "high", "above", "below"))
    if low is not None and high is not None:
        parts = [f"{low:g} to {high:g}"]
    else:
        parts = [f"> {above:g}"] if above is not None else [f">= {low:g}"] if low is not None else []
        parts += [f"< {below:g}"] if below is not None else [f"<= {high:g}"] if high is not None else []
    return ("whole number " if m.get("integer") else "") + ", ".join(parts)


def _shown(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float) and math.isfinite(v):
        return f"{v:g}"
    if isinstance(v, tuple):
        return "[" + ", ".join(_shown(x) for x in v) + "]"
    if v is None:
        return "none"
    if isinstance(v, str):
        return f'"{v}"'
    return str(v)


def markdown_table(cls: type, *, skip: tuple[str, ...] = ()) -> str:
    """The options of ``cls`` (but ``skip``) as a markdown table: name, default, unit, allowed values, meaning."""
    rows = ["| option | default | unit | values | meaning |", "|---|---|---|---|---|"]
    for f in fields(cls):
        if f.name in skip:
            continue
        m = f.metadata
        default = f.default if f.default is not MISSING else f.default_factory()
        rows.append(f"| `{f.name}` | `{_shown(default)}` | {m.get('unit', '')} | {_span(m, default)} | "
                    f"{m.get('doc', '')} |")
    return "\n".join(rows) + "\n"
