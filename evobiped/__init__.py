"""evobiped: evolve neural controllers for bipedal walkers in MuJoCo.

Data flows one way: genome -> controller params -> episode (body + controller
+ task) -> fitness -> GA.  See README.md for the commands.
"""

from .core.glbackend import choose as _choose_gl

_choose_gl()  # before anything imports mujoco: MuJoCo reads MUJOCO_GL once, at its import

__version__ = "0.1.0"
