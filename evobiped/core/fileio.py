"""Atomic file writes and JSON reading with clear errors.

Every file evobiped writes goes through :func:`atomic_write`: written to a
temporary file in the same folder, flushed, fsynced, renamed over the target
and the folder fsynced, so a killed process (or a lost machine) leaves the old
file or the new one, never half.  A write that fails (disk full, no
permission) raises :class:`WriteError`, one line naming the file.

Testing hook: with ``EVOBIPED_FAULT_KILL_AT_REPLACE=N`` in the environment the
process SIGKILLs itself just before its Nth rename (the fault-injection tests
kill a run between every pair of writes this way).
"""

from __future__ import annotations

import base64
import binascii
import json
import os
import signal
import sys
import tempfile
import tomllib
from pathlib import Path
from typing import Any

import numpy as np

from .errors import ConfigError, UserError


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


_UMASK = _umask()
_replaces = 0


class WriteError(UserError):
    """A file that cannot be written: ``cannot write PATH: reason`` (exit status 2, nothing half-written)."""

    def __init__(self, path: str | Path, exc: OSError | str):
        self.path, self.reason = Path(path), exc if isinstance(exc, str) else exc.strerror or str(exc)
        super().__init__(f"cannot write {self.path}: {self.reason}")

    def __reduce__(self):  # pickled as its path and reason: it crosses from a pool's worker to the command
        return type(self), (self.path, self.reason)


def _fault_point() -> None:
    """The testing hook: SIGKILL this process at the Nth rename (see the module docstring)."""
    global _replaces
    at = os.environ.get("EVOBIPED_FAULT_KILL_AT_REPLACE")
    if at:
        _replaces += 1
        if _replaces == int(at):
            os.kill(os.getpid(), signal.SIGKILL)


def fsync_directory(directory: str | Path) -> None:
    """Make a rename or a new file in ``directory`` durable."""
    fd = os.open(directory, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def atomic_write(path: str | Path, data: str | bytes) -> None:
    """Replace ``path`` by ``data`` whole or not at all; :class:`WriteError` if it cannot be written."""
    path = Path(path)
    mode = "wb" if isinstance(data, bytes) else "w"
    tmp = None
    try:
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
        with os.fdopen(fd, mode) as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        os.chmod(tmp, 0o644 & ~_UMASK)  # mkstemp creates 0600; give the usual permissions
        _fault_point()
        os.replace(tmp, path)
        fsync_directory(path.parent)
    except OSError as exc:
        raise WriteError(path, exc) from None
    finally:
        if tmp is not None and os.path.exists(tmp):
            os.unlink(tmp)


def json_text(obj: Any) -> str:
    """The exact text :func:`write_json` writes."""
    return json.dumps(obj, indent=2, sort_keys=False) + "\n"


def write_json(path: str | Path, obj: Any) -> None:
    atomic_write(path, json_text(obj))


#: the most bytes a file a command reads may hold (a checkpoint of CMA-ES on thousands of genes is a few MiB)
MAX_BYTES = 256 * 2**20
#: the deepest nesting of tables and lists a file may have (evobiped's own files nest at most 5 deep)
MAX_DEPTH = 32


def depth_error(obj: Any, limit: int = MAX_DEPTH) -> str | None:
    """Why ``obj`` (parsed JSON or TOML) nests too deeply, or None; iterative, so any depth is safe to check."""
    todo = [(obj, 1)]
    while todo:
        v, d = todo.pop()
        if isinstance(v, (dict, list)):
            if d > limit:
                return f"tables and lists nested more than {limit} deep"
            todo.extend((x, d + 1) for x in (v.values() if isinstance(v, dict) else v))
    return None


def what_is_there(path: str | Path) -> str:
    """What ``path`` is when it is no regular file, for a refusal: ``"is a directory, not a file"``, ``"is a FIFO (a
    named pipe), not a file"``, ``"is a symbolic link in a loop"``, ``"is a broken symbolic link (to X)"``,
    ``"not found"``, ..."""
    import errno
    import stat

    path = Path(path)
    try:
        mode = path.stat().st_mode
    except OSError as exc:
        if exc.errno == errno.ELOOP:
            return "is a symbolic link in a loop"
        if path.is_symlink():
            return f"is a broken symbolic link (to {os.readlink(path)})"
        if exc.errno == errno.ENOENT:
            return "not found"
        return f"cannot be read ({exc.strerror or exc})"
    kinds = ((stat.S_ISDIR, "a directory"), (stat.S_ISFIFO, "a FIFO (a named pipe)"), (stat.S_ISSOCK, "a socket"),
             (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"))
    kind = next((name for test, name in kinds if test(mode)), None)
    return "is a regular file" if kind is None else f"is {kind}, not a file"


def _parse_file(path: str | Path, what: str, loads, errors: tuple, form: str,
                error: type[UserError] = UserError) -> Any:
    """``loads(text)`` of the file at ``path``; a missing, oversized, malformed or too deeply nested file is one
    line naming ``what`` (every file a command reads comes through here)."""
    path = Path(path)
    if not path.is_file():
        there = what_is_there(path)
        raise UserError(f"{what} not found: {path}" if there == "not found" else f"{what} {path} {there}")
    try:
        size = path.stat().st_size
        if size > MAX_BYTES:
            raise error(f"{what} {path} is {size / 2**20:.0f} MiB; evobiped reads files of at most "
                        f"{MAX_BYTES // 2**20} MiB")
        obj = loads(path.read_text(encoding="utf-8-sig"))  # UTF-8, with or without a byte-order mark (Windows editors)
    except (*errors, UnicodeDecodeError) as exc:
        raise error(f"{what} {path} is not valid {form} "
                    f"({str(exc).splitlines()[0] if str(exc) else type(exc).__name__})") from None
    except RecursionError:
        raise error(f"{what} {path} is not valid {form} (tables and lists nested more than {MAX_DEPTH} deep)") from None
    except OSError as exc:
        raise error(f"cannot read {what} {path}: {exc.strerror or exc}") from None
    except ValueError:  # Python's limit on the digits of a whole number read from text
        raise error(f"{what} {path} is not valid {form} (a whole number of more than {sys.get_int_max_str_digits()} "
                    "digits)") from None
    deep = depth_error(obj)
    if deep:
        raise error(f"{what} {path} is not valid {form} ({deep})")
    return obj


def read_json(path: str | Path, *, what: str = "file", file_format: str | None = None) -> Any:
    """The JSON value in ``path``; UserError (one line naming the file) if it is missing or malformed, or if it is a
    table whose ``format`` is not ``file_format`` (a file without a format of its own must name none; a
    ``format`` is not required)."""
    obj = _parse_file(path, what, json.loads, (json.JSONDecodeError,), "JSON")
    if isinstance(obj, dict) and "format" in obj and (file_format is None or obj["format"] != file_format):
        reads = f"this evobiped reads {file_format}" if file_format else "evobiped writes no format there"
        raise UserError(f"{what} {path} is in format {obj['format']!r}; {reads}")
    return obj


def read_toml(path: str | Path, *, what: str = "config file") -> dict:
    return _parse_file(path, what, tomllib.loads, (tomllib.TOMLDecodeError,), "TOML", ConfigError)


def packed_floats(a: np.ndarray) -> dict:
    """A float array as a compact, exact JSON value: ``{"dtype": "<f8", "shape": [...], "b64": its little-endian
    float64 bytes in base64}`` (the vocabulary of the CMA-ES state's arrays), which :func:`unpacked_floats` reads back
    bit for bit.  A large state (a map-elites archive of network genomes: millions of numbers) written as JSON
    numbers costs about 0.4 us a number at every commit; this costs a twentieth of that, and two thirds of the bytes."""
    a = np.asarray(a, float)
    return {"dtype": "<f8", "shape": list(a.shape),
            "b64": base64.b64encode(np.ascontiguousarray(a, "<f8").tobytes()).decode("ascii")}


def unpacked_floats(value: Any, what: str) -> np.ndarray:
    """The array :func:`packed_floats` wrote; UserError (one line naming ``what``) for anything else."""
    shape = value.get("shape") if isinstance(value, dict) else None
    if not (isinstance(value, dict) and set(value) == {"dtype", "shape", "b64"} and value["dtype"] == "<f8"
            and isinstance(shape, list) and all(isinstance(n, int) and not isinstance(n, bool) and n >= 0
                                                for n in shape)):
        raise UserError(f"{what} must be a list of numbers or {{dtype: \"<f8\", shape, b64}}")
    try:
        raw = base64.b64decode(value["b64"], validate=True)
    except (binascii.Error, TypeError, ValueError):
        raise UserError(f"{what}: b64 is not base64") from None
    if len(raw) != 8 * int(np.prod(shape)):
        raise UserError(f"{what}: {len(raw)} bytes do not hold {' x '.join(map(str, shape)) or 'one'} float64 numbers")
    return np.frombuffer(raw, "<f8").astype(float).reshape(shape)
