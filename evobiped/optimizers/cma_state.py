"""pycma's strategy as plain JSON data, restored into a freshly made strategy: a resume costs the same at any
generation.

A pickle would be shorter, but loading one runs whatever the file says.  Here
the checkpoint holds data only: numbers, strings, lists, tables, numpy arrays
(dtype, shape and their bytes in base64, so every bit comes back) and, for each
object of pycma's, its attributes.  :func:`restore` writes that data into the
attributes of a strategy made by pycma's own constructor with the run's
options: functions, methods and classes are never read from the file (they
stay as the constructor made them); an object that the fresh strategy lacks is
made by ``cls.__new__`` of a class of pycma's own modules, never by calling
anything the file names.  Objects and arrays shared between attributes are
shared again after a restore.
"""

from __future__ import annotations

import base64
import importlib
import types
from typing import Any

import numpy as np

from ..core.errors import UserError

#: the modules whose classes a stored strategy may hold
MODULE = "cma"
#: how deep a strategy's attributes nest (pycma's: about 6)
MAX_DEPTH = 24

_KEEP = {"~": "keep"}  # a function, method, class or module: the fresh strategy's own stands


class _Encoder:
    def __init__(self):
        self.ids: dict[int, int] = {}
        self.alive: list[Any] = []  # what got an id lives until the encoding ends (ids stay unique)

    def __call__(self, v: Any, depth: int = 0) -> Any:
        if depth > MAX_DEPTH:
            raise ValueError("pycma's state nests deeper than expected")
        if v is None or isinstance(v, (bool, int, str)):
            return v
        if isinstance(v, float):
            return v if np.isfinite(v) else {"~": "float", "v": repr(v)}
        if isinstance(v, (types.FunctionType, types.BuiltinFunctionType, types.MethodType, type,
                          types.ModuleType)) or callable(v) and not hasattr(v, "__dict__"):
            return _KEEP
        if isinstance(v, np.generic):
            return {"~": "scalar", "dtype": v.dtype.str, "b64": base64.b64encode(v.tobytes()).decode()}
        ours = hasattr(v, "__dict__") and type(v).__module__.split(".")[0] == MODULE
        foreign = type(v) not in (list, tuple, dict, np.ndarray) and not ours  # a subclass of someone else's
        if isinstance(v, np.ndarray) and v.dtype.kind not in "biufc" or foreign:
            return _KEEP
        if id(v) in self.ids:
            return {"~": "ref", "id": self.ids[id(v)]}
        n = self.ids[id(v)] = len(self.ids)
        self.alive.append(v)
        if isinstance(v, np.ndarray):  # in its memory order too: a product's last bits depend on it
            order = "F" if v.flags.f_contiguous and not v.flags.c_contiguous else "C"
            return {"~": "array", "id": n, "dtype": v.dtype.str, "shape": list(v.shape), "order": order,
                    "b64": base64.b64encode(v.tobytes(order=order)).decode()}
        attrs = {k: self(x, depth + 1) for k, x in vars(v).items()} if hasattr(v, "__dict__") else {}
        if isinstance(v, tuple):
            return {"~": "tuple", "id": n, "items": [self(x, depth + 1) for x in v]}
        if isinstance(v, list):
            return {"~": "list", "id": n, "cls": _name(type(v)) if type(v) is not list else None, "attrs": attrs,
                    "items": [self(x, depth + 1) for x in v]}
        if isinstance(v, dict):
            return {"~": "dict", "id": n, "cls": _name(type(v)) if type(v) is not dict else None, "attrs": attrs,
                    "items": [[self(k, depth + 1), self(x, depth + 1)] for k, x in v.items()]}
        return {"~": "object", "id": n, "cls": _name(type(v)), "attrs": attrs}


def _name(cls: type) -> str:
    return f"{cls.__module__}:{cls.__qualname__}"


def _class(name: Any) -> type:
    """A class of pycma's (or a dict subclass of it) by name; nothing else."""
    if not isinstance(name, str) or ":" not in name:
        raise ValueError(f"not a class name: {name!r}")
    module, qualname = name.split(":", 1)
    if module.split(".")[0] != MODULE:
        raise ValueError(f"{name} is not one of pycma's classes")
    obj: Any = importlib.import_module(module)
    for part in qualname.split("."):
        obj = getattr(obj, part)
    if not isinstance(obj, type):
        raise ValueError(f"{name} is not a class")
    return obj


def encode(es: Any, asked: list) -> dict:
    """pycma's strategy ``es`` and the solutions it was last asked for (``asked``) as JSON data."""
    enc = _Encoder()
    return {"es": enc(es), "asked": enc(list(asked))}


class _Decoder:
    def __init__(self):
        self.made: dict[int, Any] = {}

    def __call__(self, d: Any, fresh: Any = None, depth: int = 0) -> Any:
        """The value ``d`` encodes, written into ``fresh`` (the fresh strategy's value at the same place) where it
        can."""
        if depth > MAX_DEPTH:
            raise ValueError("nested deeper than a strategy")
        if d is None or isinstance(d, (bool, int, float, str)):
            return d
        if not isinstance(d, dict) or not isinstance(d.get("~"), str):
            raise ValueError(f"unexpected value {str(d)[:40]}")
        kind = d["~"]
        if kind == "keep":
            return fresh
        if kind == "float":
            return float(d["v"])
        if kind == "ref":
            if d.get("id") not in self.made:
                raise ValueError("a reference to nothing")
            return self.made[d["id"]]
        if kind in ("scalar", "array"):
            dtype = np.dtype(d["dtype"])
            if dtype.kind not in "biufc":
                raise ValueError(f"dtype {dtype} is not numeric")
            raw = base64.b64decode(d["b64"], validate=True)
            if kind == "scalar":
                return np.frombuffer(raw, dtype)[0]
            shape = tuple(d["shape"])
            if not all(isinstance(s, int) and s >= 0
                       for s in shape) or int(np.prod(shape)) * dtype.itemsize != len(raw):
                raise ValueError("array bytes do not fit its shape")
            order = d.get("order", "C")
            if order not in ("C", "F"):
                raise ValueError(f"unknown memory order {order!r}")
            return self._keep(d, np.array(np.frombuffer(raw, dtype).reshape(shape, order=order), order=order))
        if kind in ("list", "tuple"):
            if kind == "tuple":
                return self._keep(d, tuple(self(x, None, depth + 1) for x in d["items"]))
            cls = list if d.get("cls") is None else _class(d["cls"])
            if not issubclass(cls, list):
                raise ValueError(f"{d['cls']} is not a list")
            out = self._keep(d, fresh if type(fresh) is cls else cls.__new__(cls))
            old = list(out) if out is fresh else []
            out.clear()
            out.extend(self(x, old[i] if i < len(old) else None, depth + 1) for i, x in enumerate(d["items"]))
            self._attrs(out, d.get("attrs", {}), depth)
            return out
        if kind == "dict":
            cls = dict if d.get("cls") is None else _class(d["cls"])
            if not issubclass(cls, dict):
                raise ValueError(f"{d['cls']} is not a table")
            out = fresh if type(fresh) is cls else cls.__new__(cls)
            if type(fresh) is not cls:
                dict.__init__(out)
            self._keep(d, out)
            old = dict(out)
            out.clear()
            for k, x in d["items"]:
                key = self(k, None, depth + 1)
                out[key] = self(x, old.get(key) if isinstance(key, (str, int, float, tuple, type(None))) else None,
                                depth + 1)
            self._attrs(out, d.get("attrs", {}), depth)
            return out
        if kind == "object":
            cls = _class(d["cls"])
            out = fresh if type(fresh) is cls else cls.__new__(cls)
            self._keep(d, out)
            self._attrs(out, d["attrs"], depth)
            return out
        raise ValueError(f"unknown kind {kind!r}")

    def _attrs(self, out: Any, attrs: Any, depth: int) -> None:
        if not isinstance(attrs, dict) or not all(isinstance(k, str) and not k.startswith("__") for k in attrs):
            raise ValueError("attributes must be a table of names")
        current = dict(getattr(out, "__dict__", {}))
        for k, x in attrs.items():
            setattr(out, k, self(x, current.get(k), depth + 1))

    def _keep(self, d: dict, value: Any) -> Any:
        if not isinstance(d.get("id"), int):
            raise ValueError("an id must be a whole number")
        self.made[d["id"]] = value
        return value


def restore(es: Any, data: Any) -> list:
    """Put the fresh strategy ``es`` in the state ``data`` (:func:`encode`'s); returns the solutions it was asked for.
    UserError (one line) for anything that is not such a state."""
    try:
        if not (isinstance(data, dict) and set(data) == {"es", "asked"} and isinstance(data["es"], dict)
                and data["es"].get("~") == "object" and data["es"].get("cls") == _name(type(es))):
            raise ValueError("not a stored CMA-ES strategy")
        dec = _Decoder()
        dec(data["es"], es)
        asked = dec(data["asked"])
        if not (isinstance(asked, list) and all(isinstance(a, np.ndarray) and a.shape == (len(es.mean),)
                                                for a in asked)):
            raise ValueError("the asked solutions must be arrays of the strategy's dimension")
        return asked
    except UserError:
        raise
    except (ValueError, TypeError, KeyError, AttributeError, IndexError, RecursionError, ImportError, OverflowError,
            base64.binascii.Error) as exc:
        raise UserError("checkpoint: the CMA-ES strategy cannot be restored "
                        f"({str(exc).splitlines()[0] if str(exc) else type(exc).__name__})") from None
