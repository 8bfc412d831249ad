"""Tasks (fitness and the sensors they add) and their registry."""

from .base import Task
from .command import CommandTask
from .steer import SteerTask
from .steer_command import SteerCommandTask
from .walk import WalkTask

TASKS: dict[str, type[Task]] = {
    WalkTask.name: WalkTask,
    SteerTask.name: SteerTask,
    CommandTask.name: CommandTask,
    SteerCommandTask.name: SteerCommandTask,
}

__all__ = ["TASKS", "CommandTask", "SteerCommandTask", "SteerTask", "Task", "WalkTask"]
