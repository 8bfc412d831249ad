"""Evolution progress on a ``generation`` timeline in Rerun: watch a run live or afterwards.

The GA loop calls :meth:`EvolutionLog.log_generation` once per generation::

    log = EvolutionLog(path=run_dir / "evolution.rrd")   # and/or spawn=True / connect="HOST:PORT"
    log.log_generation(gen, best=..., mean=..., worst=..., median=..., evaluations=..., falls=...)
    log.close()

Entities: ``evolution/best``, ``evolution/mean``, ``evolution/median``,
``evolution/worst`` (fitness) and ``evolution/counts/<name>`` for any extra
numbers (evaluations, falls, wall seconds).  The file is streamed as the run
goes (a killed run leaves a readable recording without its footer).
"""

from __future__ import annotations

import uuid
from pathlib import Path

import numpy as np

from .viewer import connect_url, flush, require_viewer

TIMELINE = "generation"
_STYLE = {"best": ((0, 0, 0), 2.5), "mean": ((150, 150, 150), 2.0), "median": ((90, 140, 200), 1.0), "worst": ((220, 120, 120), 1.0)}


def declare_series(rec) -> None:
    """Static line names and colours of the ``evolution/*`` series."""
    import rerun as rr

    for name, (color, width) in _STYLE.items():
        rec.log(f"evolution/{name}", rr.SeriesLines(names=[f"{name} fitness"], colors=[color], widths=[width]), static=True)


def log_history(rec, history: dict[str, np.ndarray]) -> None:
    """A whole ``history.csv`` (see :func:`evobiped.record.source.read_history`) in one go."""
    import rerun as rr

    declare_series(rec)
    idx = [rr.TimeColumn(TIMELINE, sequence=history["generation"].astype(np.int64))]
    for name, vals in history.items():
        if name == "generation":
            continue
        path = f"evolution/{name}" if name in _STYLE else f"evolution/counts/{name}"
        rec.send_columns(path, indexes=idx, columns=rr.Scalars.columns(scalars=np.asarray(vals, float)))


class EvolutionLog:
    """Best/mean/worst fitness per generation to a ``.rrd`` file and/or a live viewer."""

    def __init__(self, *, path: str | Path | None = None, spawn: bool = False, connect: str | None = None, application_id: str = "evobiped_evolve", recording_id: str | None = None):
        import rerun as rr
        import rerun.blueprint as rrb

        self.rec = rr.RecordingStream(application_id, recording_id=recording_id or uuid.uuid4().hex)
        bp = rrb.Blueprint(
            rrb.Vertical(
                rrb.TimeSeriesView(origin="evolution", contents=["evolution/best", "evolution/mean", "evolution/median", "evolution/worst"], name="fitness per generation"),
                rrb.TimeSeriesView(origin="evolution/counts", name="evaluations, falls, time"),
                row_shares=[3, 1],
            ),
            collapse_panels=True,
        )
        sinks = []
        if path is not None:
            sinks.append(rr.FileSink(str(path)))
        self.streaming = spawn or connect is not None
        if spawn:
            self.rec.spawn(connect=False)
            sinks.append(rr.GrpcSink())
        elif connect is not None:
            url = connect_url(connect)
            require_viewer(url)
            sinks.append(rr.GrpcSink(url))
        if not sinks:
            raise ValueError("EvolutionLog needs a path, spawn=True or a connect address")
        self.rec.set_sinks(*sinks, default_blueprint=bp)
        declare_series(self.rec)

    def log_generation(self, generation: int, *, best: float, mean: float, worst: float, median: float | None = None, **counts: float) -> None:
        """One generation's fitness summary; ``counts`` (e.g. evaluations=50, falls=12) go to ``evolution/counts``."""
        import rerun as rr

        self.rec.set_time(TIMELINE, sequence=int(generation))
        values = {"best": best, "mean": mean, "worst": worst, "median": median}
        for name, v in values.items():
            if v is not None:
                self.rec.log(f"evolution/{name}", rr.Scalars(float(v)))
        for name, v in counts.items():
            if v is not None:
                self.rec.log(f"evolution/counts/{name}", rr.Scalars(float(v)))

    def log_history(self, history: dict[str, np.ndarray]) -> None:
        """Every generation so far at once, e.g. from ``history.csv`` when a run resumes."""
        log_history(self.rec, history)

    def close(self) -> None:
        """Flush everything and finish the file."""
        flush(self.rec, streaming=self.streaming)

    def __enter__(self) -> "EvolutionLog":
        return self

    def __exit__(self, *exc) -> None:
        self.close()
