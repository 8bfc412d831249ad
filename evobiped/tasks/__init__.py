"""Tasks (fitness and the sensors they add) and their registry."""

from .base import Task
from .steer import SteerTask
from .walk import WalkTask

TASKS: dict[str, type[Task]] = {
    WalkTask.name: WalkTask,
    SteerTask.name: SteerTask,
}

__all__ = ["TASKS", "SteerTask", "Task", "WalkTask"]
