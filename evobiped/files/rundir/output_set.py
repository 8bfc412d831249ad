"""A command's outputs as one set (a replay's recording, video and figures; select's two files): never a new
file beside an old one of the previous run of the command.

:func:`output_set` removes the previous set first (the files it lists, any temporaries a killed write left
beside them), marks the set incomplete (``.NAME.incomplete`` beside its first file, listing its files) while the
command writes, and removes the mark when all are written.  A command killed meanwhile leaves the mark: its next
run says the previous one was cut short and removes what it wrote.
"""

from __future__ import annotations

import contextlib
import os
import shutil
from pathlib import Path

from ...core.fileio import atomic_write


def _marker(files: list[Path], name: str) -> Path:
    return files[0].parent / f".{name}.incomplete"


def _remove(path: Path) -> bool:
    """Remove a file, or a folder this set owns whole; True if there was one."""
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path)
        return True
    if path.exists() or path.is_symlink():
        path.unlink()
        return True
    return False


def _temporaries(path: Path) -> list[Path]:
    """What a killed atomic write of ``path`` (or, in a folder the set owns, of any file in it) leaves."""
    if not path.parent.is_dir():
        return []
    return list(path.parent.glob(f".{path.name}.*.tmp*"))


@contextlib.contextmanager
def output_set(name: str, files: list[Path], folders: list[Path] = (), say=None):
    """Write the set ``name``: ``files`` (each replaced whole) and ``folders`` (owned whole by the set: emptied
    first); ``say(line)`` hears that the previous run of the command was cut short."""
    files, folders = [Path(p) for p in files], [Path(p) for p in folders]
    everything = files + folders
    if not everything:
        yield
        return
    marker = _marker(everything, name)
    if marker.exists() and say is not None:
        say(f"the previous {name} was cut short before all its outputs were written; they are written again")
    for p in everything:
        _remove(p)
        for t in _temporaries(p):
            t.unlink(missing_ok=True)
    for t in _temporaries(marker):  # the mark's own write, cut short
        t.unlink(missing_ok=True)
    made = not marker.parent.exists()
    marker.parent.mkdir(parents=True, exist_ok=True)
    atomic_write(marker, b"".join(os.fsencode(p) + b"\n" for p in everything))  # a name's bytes, UTF-8 or not
    try:
        yield
    except BaseException:
        if not any(p.exists() for p in everything):  # refused before it wrote anything: nothing to say next time
            marker.unlink(missing_ok=True)
            if made:
                with contextlib.suppress(OSError):
                    marker.parent.rmdir()
        raise
    marker.unlink(missing_ok=True)
