"""Tasks (fitness and the sensors they add) and their registry."""

from .base import Task
from .walk import WalkTask

TASKS: dict[str, type[Task]] = {
    WalkTask.name: WalkTask,
}

__all__ = ["TASKS", "Task", "WalkTask"]
