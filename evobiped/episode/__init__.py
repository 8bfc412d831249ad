"""One episode = body + controller + task, run for a whole population at once.

Control ticks at the controller's period (0.02 s for the CTRNN) over finer
physics steps stepped in C (``mujoco.batch``); bodies with custom forces (the
Taga ground) get them before every physics step.  A walker's episode ends at
``seconds`` or when it falls; a simulation that blows up counts as a fall.
Row p of every result depends only on genome p: the same genome gives the
bit-identical fitness alone or inside any batch.

The package's modules, one concept each: :mod:`.config` (what to simulate, the one way to build it), :mod:`.parts`
(its parsed tables, body, task and wired controller, built once per process), :mod:`.timing` (its control period
checked), :mod:`.state` (an episode in progress as a value, a run's per-generation context), :mod:`.listener` (who
may watch one), :mod:`.loop` (the one loop, :class:`Episode`), :mod:`.grounds` (the model on a trial's ground),
:mod:`.disturbances` (what a trial applies while it runs), :mod:`.senses` (what a controller reads each tick, planned
once), :mod:`.result` (what an episode gives back), :mod:`.remap` (a genome moved onto other inputs).
"""

from .config import EpisodeConfig, build_episode
from .listener import Listener, Listeners
from .loop import Episode
from .state import Context, EpisodeState, Pose, sense_sums
from .timing import MAX_STEPS, MAX_TICKS, check_timing

__all__ = ["MAX_STEPS", "MAX_TICKS", "Context", "Episode", "EpisodeConfig", "EpisodeState", "Listener", "Listeners",
           "Pose", "build_episode", "check_timing", "sense_sums"]
