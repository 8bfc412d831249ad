"""An episode's parts, built once per process: its option tables parsed, the body (and so its compiled model), the
task, and the controller wired to the sensors it needs (the controller contract checked).

Each is kept by what it is built from (the tables as given, in their order and types), so every config of this
process naming the same tables shares them: a run's config and its best genome file's, a replay of another length, a
run's nominal episode beside its perturbed one, a teacher and its student on the same body.  A part keeps no episode
state (an :class:`~evobiped.episode.EpisodeState` does) and nothing changes it after it is built.  The most recently
used :data:`KEPT` of each kind are kept.
"""

from __future__ import annotations

import copy
from collections import OrderedDict
from dataclasses import fields, is_dataclass
from typing import Any, Callable, Hashable

import numpy as np

from ..bodies import body_class
from ..bodies.base import Body
from ..interface.contract import Offer, normaliser, wire
from ..controllers import CONTROLLERS
from ..controllers.base import Controller
from ..core.errors import ConfigError
from ..interface.frame import StanceFrame
from ..controllers.bilateral import Bilateral
from ..physics import gait
from ..core.options import given, parse
from ..tasks import TASKS
from ..tasks.base import Task

#: parts of each kind kept per process (the least recently used beyond this are built again when next asked for)
KEPT = 64


class _Kept:
    """Values by key, the :data:`KEPT` most recently used; a value whose making raises is not kept."""

    def __init__(self):
        self.values: OrderedDict = OrderedDict()

    def get(self, key: Hashable, make: Callable[[], Any]) -> Any:
        if key in self.values:
            self.values.move_to_end(key)
            return self.values[key]
        value = self.values[key] = make()
        if len(self.values) > KEPT:
            self.values.popitem(last=False)
        return value


_PARSED, _BODIES, _TASKS, _CONTROLLERS = _Kept(), _Kept(), _Kept(), _Kept()


def table_key(value: Any) -> Hashable:
    """A hashable key equal for equal tables only: their keys in order, each value with its type (1, 1.0 and True
    differ, as they do in the file a config writes back); a parsed options object by all its fields and the settings
    its table gave.  TypeError for a value of another kind (such a table is parsed every time)."""
    if isinstance(value, dict):
        return ("dict", tuple((k, table_key(v)) for k, v in value.items()))
    if isinstance(value, (list, tuple)):
        return (type(value).__name__, tuple(table_key(v) for v in value))
    if isinstance(value, np.ndarray):
        return ("array", value.dtype.str, value.shape, value.tobytes())
    if is_dataclass(value) and not isinstance(value, type):
        return (type(value), tuple((f.name, table_key(getattr(value, f.name))) for f in fields(value)),
                tuple(given(value)))
    if isinstance(value, (float, np.floating)):
        return (type(value).__name__, repr(value))  # -0.0 and nan as themselves
    if value is None or isinstance(value, (bool, int, str, np.integer, np.bool_)):
        return (type(value).__name__, value)
    raise TypeError(f"no table key for {type(value).__name__}")


def parsed(cls: type, table: Any, where: str) -> Any:
    """``parse(cls, table, where)``, once per process for each table (an ``Options`` object is taken as it is); the
    object parsed holds a copy of the table's values, so a caller changing its table later changes no config."""
    if isinstance(table, cls):
        return table
    try:
        key = (cls, table_key(table))
    except TypeError:
        return parse(cls, table, where)
    return _PARSED.get(key, lambda: parse(cls, copy.deepcopy(table), where))


def body_part(name: str, options: Any) -> tuple[Body, Hashable]:
    """The body ``name`` with its parsed ``options``, and its key."""
    key = (name, table_key(options))
    return _BODIES.get(key, lambda: body_class(name)(options)), key


def task_part(name: str, options: Any, body_key: Hashable) -> tuple[Task, Hashable]:
    """The task ``name`` with its parsed ``options`` for the body of ``body_key`` (a task binds to its body's model)."""
    key = (name, table_key(options), body_key)
    return _TASKS.get(key, lambda: TASKS[name](options)), key


def controller_part(name: str, options: Any, body: Body, task: Task, keys: tuple) -> Controller:
    """The controller ``name`` with its parsed ``options`` for ``body`` and ``task`` (``keys``: theirs), wired to the
    sensors it needs; one ConfigError line where the contract is not met."""
    return _CONTROLLERS.get((name, table_key(options), *keys), lambda: _wired(name, options, body, task))


def _wired(name: str, opts: Any, body: Body, task: Task) -> Controller:
    cls = CONTROLLERS[name]
    added = task.sensor_widths()
    offer = Offer(body.actuators, {**body.sensor_widths, **added}, tuple(added),
                  {**body.sensor_norms, **task.sensor_norms()}, named_only=gait.ON_REQUEST)
    inputs = wire(cls.needs(opts), offer, chosen=opts.inputs, what=f"controller {name!r} (body {body.name!r}, task "
                                                                   f"{task.name!r})")
    ctrl = cls(opts, n_outputs=len(body.actuators), inputs=inputs, actuators=body.actuators)
    where = "episode.controller_options"
    if ctrl.normalises_inputs:
        ctrl.input_norm = normaliser(inputs, offer.norms)
    if opts.input_norm is not None:
        width = sum(inputs.values())
        if not ctrl.normalises_inputs:
            raise ConfigError(f"{where}.input_norm: controller {name!r} reads raw senses here (it does not normalise "
                              "its inputs)")
        if len(opts.input_norm["mean"]) != width:
            raise ConfigError(f"{where}.input_norm: normalises {len(opts.input_norm['mean'])} inputs; the controller "
                              f"reads {width} ({', '.join(f'{n} {w}' for n, w in inputs.items())})")
        ctrl.input_norm = (np.array(opts.input_norm["mean"], float), np.array(opts.input_norm["std"], float))
    if opts.frame == "stance":
        if body.actuator_mirror is None or body.contact_sensor is None:
            raise ConfigError(f"{where}.frame: 'stance' needs a bilateral body with foot contacts; body {body.name!r} "
                              "declares no left/right mirror")
        ctrl.frame = StanceFrame(inputs, {**body.mirror, **task.sensor_mirror()}, body.actuator_mirror,
                                 what=f"{where}.frame")
    if getattr(opts, "symmetric", False):
        if body.actuator_mirror is None:
            raise ConfigError(f"{where}.symmetric: needs a bilateral body; body {body.name!r} declares no left/right "
                              "mirror")
        mirror = StanceFrame(inputs, {**body.mirror, **task.sensor_mirror()}, body.actuator_mirror,
                             what=f"{where}.symmetric")
        ctrl.bilateral = Bilateral((mirror.action_perm, mirror.action_sign), (mirror.input_perm, mirror.input_sign),
                                   what=f"{where}.symmetric")
    if "genes" in given(opts):
        try:
            ctrl.override_genes(opts.genes)
        except ConfigError as exc:
            raise ConfigError(f"{where}.{exc}") from None
    return ctrl
