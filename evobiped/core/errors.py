"""Errors a user can cause (bad config, genome, argument, model).

The CLI turns a :class:`UserError` into one line on stderr and exit status 2,
and an :class:`Interrupted` (SIGINT, SIGTERM, SIGHUP) into exit status 128 + n.
"""

from __future__ import annotations

import contextlib
import signal
import threading
from typing import Callable


class UserError(Exception):
    """Bad input from the user: reported as one line, exit status 2."""


class ConfigError(UserError):
    """A configuration value is missing, of the wrong type or out of range."""


class GenomeError(UserError):
    """A genome does not fit its controller's layout (length, NaN, range)."""


class Interrupted(KeyboardInterrupt):
    """SIGTERM or SIGHUP (or Ctrl-C): the command stops as on Ctrl-C; its exit status is 128 + the signal number."""

    def __init__(self, signum: int = signal.SIGINT):
        self.signum = int(signum)
        super().__init__(signal.Signals(self.signum).name)

    def __reduce__(self):  # pickled as its signal number, as it is made
        return type(self), (self.signum,)


#: the signals that stop a command as Ctrl-C does (a shell's ``kill``, a closed terminal)
STOP_SIGNALS = (signal.SIGTERM, signal.SIGHUP)


def raise_interrupted(signum: int, frame) -> None:
    """The handler :func:`stop_on_signals` installs: raise :class:`Interrupted` in the main thread."""
    raise Interrupted(signum)


def stop_on_signals() -> Callable[[], None]:
    """Make SIGTERM and SIGHUP raise :class:`Interrupted` (as SIGINT raises KeyboardInterrupt); a signal this
    process ignores (``nohup``) stays ignored.  Returns the function that restores the previous handlers."""
    if threading.current_thread() is not threading.main_thread():
        return lambda: None
    old = {s: signal.getsignal(s) for s in STOP_SIGNALS if signal.getsignal(s) is signal.SIG_DFL}
    for s in old:
        signal.signal(s, raise_interrupted)

    def restore() -> None:
        for s, h in old.items():
            signal.signal(s, h)

    return restore


def exit_status(exc: KeyboardInterrupt) -> int:
    """128 + the number of the signal that interrupted the command (130 for Ctrl-C)."""
    return 128 + getattr(exc, "signum", int(signal.SIGINT))


#: a duplicate of the real standard error, kept by :func:`keep_stderr` (None: not kept)
_STDERR_FD: int | None = None


def keep_stderr() -> None:
    """Keep a duplicate of file descriptor 2 as it is now (a command's start), for :func:`last_line`."""
    global _STDERR_FD
    import os

    if _STDERR_FD is not None:  # a command run again in this process: descriptor 2 as it is now
        os.close(_STDERR_FD)
    try:
        _STDERR_FD = os.dup(2)
    except OSError:
        _STDERR_FD = None


def last_line(message: str) -> None:
    """Print ``message`` (a command's last word: an error, an interruption) on the real standard error, even at an
    instant when another thread has sent descriptor 2 to /dev/null (the process pool does while it relaunches
    multiprocessing's resource tracker)."""
    import os
    import sys

    if _STDERR_FD is None or sys.stderr is not sys.__stderr__:  # none kept, or stderr replaced (a caller captures it)
        print(message, file=sys.stderr, flush=True)
        return
    sys.stderr.flush()
    data = (message + "\n").encode(errors="replace")
    while data:
        data = data[os.write(_STDERR_FD, data):]


@contextlib.contextmanager
def signals_deferred():
    """Hold Ctrl-C (and SIGTERM/SIGHUP where they stop the command, see :func:`~evobiped.core.errors.stop_on_signals`)
    back for the duration and raise it right after (main thread only).

    A Python-level handler, not a signal mask: the signal may be delivered to
    any thread (Rerun's, for one), but Python handlers always run in the main thread.
    Signals this process ignores or handles otherwise (pool workers) are left alone.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    raising = {signal.SIGINT: signal.default_int_handler, **{s: raise_interrupted for s in STOP_SIGNALS}}
    caught = []
    old = {s: signal.signal(s, lambda signum, frame: caught.append(signum)) for s, h in raising.items()
           if signal.getsignal(s) is h}
    try:
        yield
    finally:
        for s, h in old.items():
            signal.signal(s, h)
    if caught:
        raise Interrupted(caught[0])
