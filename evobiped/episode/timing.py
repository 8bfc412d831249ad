"""An episode's timing checked: its control period, the physics steps per control tick, and the most ticks and steps
one walker's episode may take."""

from __future__ import annotations

from ..bodies.base import Body
from ..controllers.base import Controller
from ..core.errors import ConfigError
from ..core.validate import number
from ..interface.mapping import MAPS

#: the most control ticks, and physics steps, one walker's episode may take
MAX_TICKS = 10**7
MAX_STEPS = 10**8


def check_timing(body: Body, controller: Controller | None, seconds: float, *,
                 control_dt: float | None = None) -> tuple[float, int]:
    """``(control period in s, physics steps per control tick)`` of an episode of ``seconds`` s; ConfigError
    when the controller's outputs do not map onto the body's actions, the period is no multiple of the
    physics step, or the episode is not 1 to MAX_TICKS ticks and at most MAX_STEPS physics steps per walker.
    Without a controller (actions from outside) the period is ``control_dt``."""
    if controller is None:
        if control_dt is None:
            raise ConfigError("an episode without a controller needs its control period (control_dt)")
        number(control_dt, "control_dt:", above=0, unit="s")
        dt = float(control_dt)
    else:
        if (controller.output_kind, body.action_kind) not in MAPS:
            raise ConfigError(
                f"controller {controller.name!r} gives {controller.output_kind} outputs, which body {body.name!r} "
                f"cannot take as {body.action_kind}s"
            )
        dt = controller.dt if controller.dt is not None else body.timestep
    ratio = dt / body.timestep
    if abs(ratio - round(ratio)) > 1e-9 or round(ratio) < 1:
        raise ConfigError(f"control period {dt} s is not a multiple of the physics step {body.timestep} s")
    ticks = seconds / dt
    if not 1 <= round(ticks) <= MAX_TICKS:
        raise ConfigError(f"episode seconds = {seconds!r} gives {ticks:.3g} control ticks of {dt:g} s; "
                          f"an episode needs 1 to {MAX_TICKS:.0e}")
    if round(ticks) * round(ratio) > MAX_STEPS:
        raise ConfigError(f"an episode of {seconds:g} s at a physics step of {body.timestep:g} s takes "
                          f"{round(ticks) * round(ratio):.3g} steps per walker, more than {MAX_STEPS:.0e}")
    return dt, int(round(ratio))
