"""evobiped: evolve neural controllers for bipedal walkers in MuJoCo.

Data flows one way: genome -> controller params -> episode (body + controller
+ task) -> fitness -> GA.  See README.md for the commands.
"""

import _signal  # the C module: Python's signal module first imports enum, 30 ms
import os as _os
import sys as _sys


def _interrupted_while_starting(signum, frame) -> None:
    """The evobiped command's Ctrl-C before its ``main`` takes over (while Python imports it): one line, exit
    status 130, nothing written yet (``evobiped.cli.main`` puts Python's own handler back)."""
    _os.write(2, b"evobiped: interrupted\n")
    _os._exit(128 + signum)


# first thing, before any import: in the command's own process (the console script, or `python -m evobiped`)
if (_sys.argv[:1] == ["-m"] or _os.path.basename(_sys.argv[0] if _sys.argv else "") == "evobiped") and \
        _signal.getsignal(_signal.SIGINT) is _signal.default_int_handler:
    _signal.signal(_signal.SIGINT, _interrupted_while_starting)

from .core.glbackend import choose as _choose_gl  # noqa: E402

_choose_gl()  # before anything imports mujoco: MuJoCo reads MUJOCO_GL once, at its import

__version__ = "0.1.0"
