"""The run directory's lock: one process evolves a run (``flock`` on ``DIR/.lock``, which holds the owner's pid)."""

from __future__ import annotations

import errno
import fcntl
import os
from pathlib import Path

from ...core.errors import UserError
from ...core.fileio import WriteError
from .layout import LOCK

_held: dict[Path, list] = {}  # resolved run directory -> [fd, count] (re-entrant within a process)


def lock(directory: str | Path) -> None:
    """Take the exclusive lock of a run directory (``flock`` on ``DIR/.lock``, which holds the owner's pid).

    The kernel releases it when the process ends, however it ends, so a lock is
    never stale.  A second process gets a UserError; the same process may lock again.
    A pid that cannot be written (disk full) is a WriteError, and an empty lock file
    is removed again: a lock file is never left empty.
    """
    key = Path(directory).resolve()
    if key in _held:
        _held[key][1] += 1
        return
    path = key / LOCK
    while True:
        try:
            fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
        except OSError as exc:
            raise WriteError(path, exc) from None
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as exc:
            owner = os.pread(fd, 32, 0).decode(errors="replace").strip() or "unknown"
            os.close(fd)
            if exc.errno in (errno.EWOULDBLOCK, errno.EAGAIN, errno.EACCES):
                raise UserError(f"run directory {directory} is in use by process {owner}") from None
            raise WriteError(path, exc) from None
        if _same_file(fd, path):
            break
        os.close(fd)  # the file was removed (by a writer that failed) after we opened it: lock the one there now
    pid = f"{os.getpid()}\n".encode()
    try:
        if os.pread(fd, 32, 0) != pid:  # the owner's pid, for the message a second writer gets
            os.pwrite(fd, pid, 0)  # over the old pid, then cut: the file is never empty
            os.ftruncate(fd, len(pid))
    except OSError as exc:
        if os.fstat(fd).st_size == 0:
            path.unlink(missing_ok=True)  # still holding the lock: nobody else can be using it
        os.close(fd)
        raise WriteError(path, exc) from None
    _held[key] = [fd, 1]


def writer(directory: str | Path) -> int | None:
    """The pid of another live process that holds the lock of run directory ``directory`` (an evolve writing it);
    None when none does.  Read from the kernel's table of locks (``/proc/locks``) where there is one, so a reader
    never takes the lock itself; elsewhere a shared lock is tried for an instant."""
    path = Path(directory) / LOCK
    try:
        inode = os.stat(path).st_ino
    except OSError:
        return None
    try:
        table = Path("/proc/locks").read_text()
    except OSError:
        table = None
    if table is not None:
        for line in table.splitlines():  # "1: FLOCK  ADVISORY  WRITE 4242 08:01:1311 0 EOF"
            parts = line.split()
            if len(parts) > 5 and parts[1] == "FLOCK" and parts[5].rsplit(":", 1)[-1] == str(inode):
                pid = int(parts[4]) if parts[4].isdigit() else None
                return None if pid == os.getpid() else pid
        return None
    fd = os.open(path, os.O_RDONLY)
    try:
        fcntl.flock(fd, fcntl.LOCK_SH | fcntl.LOCK_NB)
    except OSError:
        owner = os.pread(fd, 32, 0).decode(errors="replace").strip()
        return int(owner) if owner.isdigit() else -1
    finally:
        os.close(fd)  # a shared lock taken goes with it
    return None


def _same_file(fd: int, path: Path) -> bool:
    """True while ``path`` still names the open file ``fd``."""
    try:
        a, b = os.fstat(fd), os.stat(path)
    except OSError:
        return False
    return (a.st_dev, a.st_ino) == (b.st_dev, b.st_ino)


def unlock(directory: str | Path) -> None:
    """Release one :func:`lock` of this process (the last one frees the directory)."""
    key = Path(directory).resolve()
    if key not in _held:
        return
    _held[key][1] -= 1
    if _held[key][1] == 0:
        os.close(_held.pop(key)[0])

