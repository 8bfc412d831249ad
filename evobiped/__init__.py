"""evobiped: evolve neural controllers for bipedal walkers in MuJoCo.

Data flows one way: genome -> controller params -> episode (body + controller
+ task) -> fitness -> GA.  See README.md for the commands.
"""

__version__ = "0.1.0"
