"""A replay's Rerun recording: made in memory and written whole at the end (a failed replay leaves nothing
half-written), or streamed to a viewer.  Its :attr:`~ReplayRecording.recorder` listens to the episode; what the
replay adds after it (the presentations' paths, the run's fitness history, the video's frames, the layout) goes in
with :meth:`~ReplayRecording.finish`."""

from __future__ import annotations

import uuid
from pathlib import Path

from ...core.fileio import atomic_write
from .rerun_recorder import RerunRecorder, blueprint, log_presentations
from ..trajectory import Trajectory


class ReplayRecording:
    """The recording of one replay: to the file ``target`` (None: a viewer, a new one with ``spawn``, else the one at
    ``connect``), named ``name`` in the viewer."""

    def __init__(self, target: Path | None, *, spawn: bool = False, connect: str | None = None, name: str = "evobiped"):
        import rerun as rr

        from .viewer import connect_url, require_viewer

        if connect is not None and target is None:
            require_viewer(connect_url(connect))
        self.target = target
        self.rec = rr.RecordingStream("evobiped_replay", recording_id=uuid.uuid4().hex)
        self._stream = None
        if target is not None:
            target.parent.mkdir(parents=True, exist_ok=True)
            self._stream = self.rec.binary_stream()
        elif spawn:
            self.rec.spawn()
        else:
            self.rec.connect_grpc(connect_url(connect))
        # a path's undecodable bytes
        self.rec.send_recording_name(name.encode(errors="surrogateescape").decode(errors="replace"))
        #: the episode's listener: the walker's trajectory, logged as it goes
        self.recorder = RerunRecorder(self.rec)

    def finish(self, trajectories: list[Trajectory], *, history: dict | None = None, frames=None, times=None,
               gait: dict | None = None) -> None:
        """Log the presentations (one trajectory each, when there are several), the run's fitness ``history``
        (``{column: (n_generations,)}``, or None), the video's ``frames`` at ``times`` (or None), the ``gait``
        (:func:`evobiped.analysis.gait_report.measured`: each foot's debounced stance beside its contacts, the measures
        as a text) and the layout; then write the file whole, or flush the stream."""
        from .evolution_log import log_history
        from .viewer import flush

        traj, several = trajectories[0], len(trajectories) > 1
        if several:
            log_presentations(self.rec, trajectories)
        if history is not None:
            log_history(self.rec, history)
        if gait is not None:
            log_gait(self.rec, gait, traj)
        if frames is not None:
            from ..video import log_frames

            log_frames(self.rec, frames, times)
        self.rec.send_blueprint(blueprint(traj, with_evolution=history is not None, with_presentations=several,
                                          with_video=frames is not None))
        if self._stream is None:
            flush(self.rec, streaming=True)
        else:
            data = self._stream.read(flush=True) or b""
            self.rec.disconnect()
            self._stream = None
            atomic_write(self.target, data)


    def discard(self) -> None:
        """Drop what was recorded (a replay stopped before :meth:`finish`): nothing is written, and Rerun has no data
        left in memory to warn about at exit."""
        self.rec.disconnect()
        if self._stream is not None:
            self._stream.read(flush=False)
            self._stream = None


def log_gait(rec, gait: dict, traj: Trajectory) -> None:
    """Each foot's debounced stance (0/1 at the trajectory's ticks) under ``contacts/stance_<foot>``, and the gait's
    measures and verdict as the text ``gait``."""
    import numpy as np
    import rerun as rr

    from ...analysis.gait_report import gait_line
    from .rerun_recorder import TIMELINE

    t = np.asarray(traj.tick_time, float)
    for foot, episodes in gait["stance"].items():
        on = np.zeros(len(t))
        for a, b in episodes:
            on[(t > a + 1e-9) & (t <= b + 1e-9)] = 1.0
        rec.send_columns(f"contacts/stance_{foot}", indexes=[rr.TimeColumn(TIMELINE, duration=t)],
                         columns=rr.Scalars.columns(scalars=on))
    verdict = "walks" if gait["walks"] else "does not walk: " + ", ".join(gait["failed"])
    rec.log("gait", rr.TextDocument(f"{verdict}\n\n{gait_line(gait)}"), static=True)
