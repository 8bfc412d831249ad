"""The testing hook of the evaluation backends: a worker that takes a marker file dies as a lost worker does.

With ``EVOBIPED_FAULT_KILL_WORKER=FILE`` in the environment of the process that makes an evaluator (read once, when
it is made: :meth:`FaultHook.from_environment`), the first batch whose worker finds FILE deletes it and dies: a
process or Ray actor SIGKILLs itself, a thread's batch raises MemoryError (the one way a thread's batch dies alone).
The hook is data (the marker's path), handed to the workers with their episode; a hook without a marker does nothing.
"""

from __future__ import annotations

import os
import signal
from dataclasses import dataclass
from typing import Mapping

#: the environment variable naming the marker file
ENVIRONMENT = "EVOBIPED_FAULT_KILL_WORKER"


@dataclass(frozen=True)
class FaultHook:
    """The marker file whose taker dies (None: no hook)."""

    marker: str | None = None

    @classmethod
    def from_environment(cls, environ: Mapping[str, str] = os.environ) -> "FaultHook":
        """The hook :data:`ENVIRONMENT` names (none where it is unset or empty)."""
        return cls(environ.get(ENVIRONMENT) or None)

    def taken(self) -> bool:
        """True for the first caller to find the marker (it deletes it)."""
        if not self.marker:
            return False
        try:
            os.unlink(self.marker)
        except FileNotFoundError:
            return False
        return True

    def kill_process(self) -> None:
        """A process pool's worker or a Ray actor: SIGKILL this process if it takes the marker."""
        if self.taken():
            os.kill(os.getpid(), signal.SIGKILL)

    def fail_batch(self) -> None:
        """A thread's batch: MemoryError if it takes the marker."""
        if self.taken():
            raise MemoryError("testing hook")
