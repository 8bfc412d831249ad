"""The ``evobiped`` command: parse, build configs, call the package, print.

One module per subcommand, ``<name>_cmd.py``, with ``add_<name>(subparsers)`` (its parser and flags),
``run_<name>_cmd(args)`` (the handler) and ``SUBCOMMANDS`` (the ``add_`` functions it registers): the
core's in this package's folders by what they are about (:data:`CORE`: ``evolving/``, evolving and what a run holds;
``walkers/``, one walker's episode and analysis; ``gaits/``, a MAP-Elites archive used as gaits), and each experiment's
own, which it registers by providing ``evobiped/experiments/<experiment>/<name>_cmd.py`` (found by
:func:`experiment_commands`).  What the commands share is :mod:`evobiped.flags`.  A
:class:`~evobiped.core.errors.UserError` (or a bad argument) becomes one line on stderr and exit status 2.
"""

from __future__ import annotations

import argparse
import errno
import importlib
import os
import pkgutil
import re
import signal
import sys
import threading
from types import ModuleType

from .. import __version__
from ..core.errors import STOP_SIGNALS, UserError, exit_status, keep_stderr, last_line, stop_on_signals

#: how every refusal begins, a bad argument's and a UserError's alike
ERROR = "evobiped: error: "
# : the core's subcommand modules (``<folder>.<name>_cmd``), in the order ``evobiped --help`` lists them (the
# experiments' follow)
CORE = ("walkers.episode_cmd", "evolving.evolve_cmd", "evolving.compare_cmd", "evolving.presets_cmd",
        "walkers.robustness_cmd", "walkers.bench_cmd",
        "evolving.replay_cmd", "walkers.distill_cmd", "evolving.genome_cmd", "evolving.select_cmd",
        "gaits.repertoire_cmd", "gaits.adapt_cmd", "gaits.gait_cmd", "walkers.gait_report_cmd")


#: what argparse reads as a negative number, a value and not a flag: -1, -.5, -1e308, -1.5E-3, -inf, -nan
NEGATIVE_NUMBER = re.compile(r"^-(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$|^-(inf|infinity|nan)$", re.IGNORECASE)


class _Parser(argparse.ArgumentParser):
    def __init__(self, *args, **kw):
        super().__init__(*args, **kw)
        self._negative_number_matcher = NEGATIVE_NUMBER  # argparse's own misses exponents: -1e308 read as a flag

    def error(self, message):  # one line, exit 2, no usage dump; one prefix for every refusal (UserError's too)
        self.exit(2, f"{ERROR}{message}\n")

    def _get_values(self, action, arg_strings):  # every flag's and argument's value, in groups too
        # an empty path or name: not "not given"
        if "" in arg_strings and action.nargs not in (argparse.PARSER, argparse.REMAINDER):
            self.error(
                f"argument {'/'.join(action.option_strings) or action.metavar or action.dest}: must not be empty")
        return super()._get_values(action, arg_strings)


def experiment_commands() -> list[ModuleType]:
    """The experiments' subcommand modules, ``evobiped.experiments.<experiment>.<name>_cmd``, by experiment and name."""
    from .. import experiments

    found = []
    for package in sorted(m.name for m in pkgutil.iter_modules(experiments.__path__) if m.ispkg):
        where = importlib.import_module(f"{experiments.__name__}.{package}")
        for name in sorted(m.name for m in pkgutil.iter_modules(where.__path__) if m.name.endswith("_cmd")):
            found.append(importlib.import_module(f"{where.__name__}.{name}"))
    return found


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="evobiped", description="Evolve neural controllers for bipedal walkers in MuJoCo.")
    parser.add_argument("--version", action="version", version=f"evobiped {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    for module in [importlib.import_module(f"{__name__}.{name}") for name in CORE] + experiment_commands():
        for add in module.SUBCOMMANDS:
            add(sub)
    return parser


def quiet_interrupts(unraisable) -> None:
    """``sys.unraisablehook`` of the command's own process: a stop signal that strikes where Python cannot raise it
    (a callback of the pool being torn down after the command's last line, a second Ctrl-C) is not a traceback;
    anything else is reported as Python does."""
    if not isinstance(unraisable.exc_value, KeyboardInterrupt):
        sys.__unraisablehook__(unraisable)


def _interrupted(exc: BaseException) -> bool:
    """Whether a KeyboardInterrupt is among the causes of ``exc``."""
    seen = set()
    while exc is not None and id(exc) not in seen:
        if isinstance(exc, KeyboardInterrupt):
            return True
        seen.add(id(exc))
        exc = exc.__cause__ or exc.__context__
    return False


def descriptors_line() -> str:
    """What a command that ran out of file descriptors says: this process's limit and how to raise it."""
    import resource

    soft = resource.getrlimit(resource.RLIMIT_NOFILE)[0]
    limit = "unlimited" if soft == resource.RLIM_INFINITY else f"{soft}"
    return (f"too many open files: this process may open {limit} (ulimit -n); raise the limit (ulimit -n 1024) or give "
            "fewer --workers")


#: what a library that ran out of address space raises (NumPy's, MuJoCo's, numba's LLVM, Rerun's, Arrow's loaders)
NO_SPACE = ("failed to map segment", "could not allocate memory", "cannot allocate memory",
            "could not find/load shared object")


def out_of_address_space(exc: BaseException) -> str | None:
    """The line for ``exc`` when it is a library's failure to load or allocate under an address-space limit
    (``ulimit -v``), else None: the limit and its fix."""
    import resource

    soft = resource.getrlimit(resource.RLIMIT_AS)[0]
    said = isinstance(exc, MemoryError) or any(w in str(exc).lower() for w in NO_SPACE)
    if soft == resource.RLIM_INFINITY or not said:
        return None
    return (f"out of address space: this process may take {soft // 1024:,} KiB (ulimit -v {soft // 1024}), too little "
            "for this command's libraries; raise the limit (ulimit -v unlimited)")


def main(argv: list[str] | None = None) -> int:
    restore = lambda: None  # noqa: E731
    try:
        args = build_parser().parse_args(argv)  # Ctrl-C while it imports the subcommands: evobiped's first handler
        # evobiped's
        starting = getattr(signal.getsignal(signal.SIGINT), "__qualname__", None) == "_interrupted_while_starting"
        if starting and threading.current_thread() is threading.main_thread():
            signal.signal(signal.SIGINT, signal.default_int_handler)  # from here on: the "interrupted" line below
        if argv is None:
            sys.unraisablehook = quiet_interrupts
            # a path's bytes that are not UTF-8 are printed as they are, as ls does
            for stream in (sys.stdout, sys.stderr):
                if hasattr(stream, "reconfigure"):
                    stream.reconfigure(errors="surrogateescape")
        keep_stderr()  # the last line reaches the user whatever a pool's thread does with descriptor 2 at that instant
        restore = stop_on_signals()  # SIGTERM, SIGHUP: as Ctrl-C
        return int(args.func(args) or 0)
    except UserError as exc:
        last_line(f"{ERROR}{exc}")
        return 2
    except BrokenPipeError:  # the reader went away (`evobiped presets | head -1`): stop quietly, as cat does
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())  # no second error when Python flushes stdout
        return 141
    except OSError as exc:  # a file or directory that cannot be read or written: one line, not a traceback
        if exc.errno in (errno.EMFILE, errno.ENFILE):  # a pool's pipes and semaphores, past the limit
            last_line(f"{ERROR}{descriptors_line()}")
            return 2
        if exc.filename is None:
            if line := out_of_address_space(exc):
                last_line(f"{ERROR}{line}")
                return 2
            raise
        from pathlib import Path

        where = Path(exc.filename)
        # an atomic write's temporary file: name its folder
        if where.name.startswith(".") and where.name.endswith(".tmp"):
            where = where.parent
        last_line(f"{ERROR}cannot access {where}: {exc.strerror or exc}")
        return 2
    except KeyboardInterrupt as exc:
        last_line("evobiped: interrupted")
        return exit_status(exc)
    # Ctrl-C inside an extension module's import (NumPy's, MuJoCo's) arrives as an ImportError
    except ImportError as exc:
        if not _interrupted(exc):
            if line := out_of_address_space(exc):
                last_line(f"{ERROR}{line}")
                return 2
            raise
        last_line("evobiped: interrupted")
        return 130
    except Exception as exc:  # a library out of memory under ulimit -v (MuJoCo's FatalError, a MemoryError)
        if line := out_of_address_space(exc):
            last_line(f"{ERROR}{line}")
            return 2
        raise
    finally:
        restore()
        if argv is None:  # the command's own process: its work is done and said; a stop signal now would only cut
            for s in (signal.SIGINT, *STOP_SIGNALS):  # the interpreter's teardown short and hide the exit status
                signal.signal(s, signal.SIG_IGN)
