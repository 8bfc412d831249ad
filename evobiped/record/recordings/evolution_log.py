"""Evolution progress on a ``generation`` timeline in Rerun: a run's ``evolution.rrd`` and a live viewer.

A run's listener, :class:`RecordingFile`, writes its ``evolution.rrd`` whole at
every commit, from the checkpoint's history (:func:`write_recording`, atomic: a
killed run leaves a complete recording of its last committed generation, never
a cut one).  A live
viewer gets each generation as it ends through :class:`EvolutionLog`::

    log = EvolutionLog(spawn=True)          # or connect="HOST:PORT", or path=FILE.rrd
    log.log_generation(gen, best=..., mean=..., worst=..., median=..., evaluations=..., falls=...)
    log.close()

Entities: ``evolution/best``, ``evolution/mean``, ``evolution/median``,
``evolution/worst`` (fitness), ``evolution/counts/<name>`` for any extra
numbers (evaluations, falls, wall seconds), and ``evolution/optimizer/<name>``
for an optimizer's own series (MAP-Elites: the archive's cells, coverage and
QD score per generation).
"""

from __future__ import annotations

import os
import uuid
from pathlib import Path

import numpy as np

from ...core.fileio import atomic_write
from ...files.rundir import RECORDING, TERM_PREFIX, sync_file
from .viewer import connect_url, flush, require_viewer

TIMELINE = "generation"
_STYLE = {"best": ((0, 0, 0), 2.5), "mean": ((150, 150, 150), 2.0), "median": ((90, 140, 200), 1.0),
          "worst": ((220, 120, 120), 1.0)}
#: the last bytes of a complete .rrd file start with this
_FOOTER = b"RRF2FOOT"


def declare_series(rec) -> None:
    """Static line names and colours of the ``evolution/*`` series."""
    import rerun as rr

    for name, (color, width) in _STYLE.items():
        rec.log(f"evolution/{name}", rr.SeriesLines(names=[f"{name} fitness"], colors=[color], widths=[width]),
                static=True)


def log_history(rec, history: dict[str, np.ndarray]) -> None:
    """A whole ``history.csv`` (see :func:`evobiped.files.rundir.read_history`) in one go."""
    import rerun as rr

    declare_series(rec)
    idx = [rr.TimeColumn(TIMELINE, sequence=np.asarray(history["generation"]).astype(np.int64))]
    for name, vals in history.items():
        if name == "generation":
            continue
        path = f"evolution/{name}" if name in _STYLE else f"evolution/terms/{name}" if name.startswith(
            TERM_PREFIX) else f"evolution/counts/{name}"
        rec.send_columns(path, indexes=idx, columns=rr.Scalars.columns(scalars=np.asarray(vals, float)))


def log_series(rec, series: dict[str, np.ndarray]) -> None:
    """An optimizer's own series (name -> ``(generations,)``, generation 0 first) under ``evolution/optimizer``."""
    import rerun as rr

    for name, vals in series.items():
        idx = [rr.TimeColumn(TIMELINE, sequence=np.arange(len(vals), dtype=np.int64))]
        rec.send_columns(f"evolution/optimizer/{name}", indexes=idx,
                         columns=rr.Scalars.columns(scalars=np.asarray(vals, float)))


def _blueprint(optimizer_series: bool = False):
    import rerun.blueprint as rrb

    views = [rrb.TimeSeriesView(origin="evolution",
                                contents=["evolution/best", "evolution/mean", "evolution/median", "evolution/worst"],
                                name="fitness per generation"),
             rrb.TimeSeriesView(origin="evolution/terms", name="the best individual's terms"),
             rrb.TimeSeriesView(origin="evolution/counts", name="evaluations, falls, time")]
    if optimizer_series:
        views.append(rrb.TimeSeriesView(origin="evolution/optimizer",
                                        name="the optimizer's own (MAP-Elites: the archive's growth)"))
    return rrb.Blueprint(rrb.Vertical(*views, row_shares=[3, 1, 1, 2][: len(views)]), collapse_panels=True)


def recording_bytes(history: dict[str, np.ndarray], recording_id: str, series: dict[str, np.ndarray] | None = None,
                    application_id: str = "evobiped_evolve") -> bytes:
    """A complete ``.rrd`` (footer included) of a whole history, and an optimizer's own ``series``, made in memory."""
    import rerun as rr

    rec = rr.RecordingStream(application_id, recording_id=recording_id)
    stream = rec.binary_stream()
    rec.send_blueprint(_blueprint(bool(series)))
    log_history(rec, history)
    log_series(rec, series or {})
    data = stream.read(flush=True) or b""
    rec.disconnect()
    return data


def write_recording(path: str | Path, history: dict[str, np.ndarray], recording_id: str,
                    series: dict[str, np.ndarray] | None = None) -> None:
    """(Re)write ``path`` from a whole history and an optimizer's own series, atomically (WriteError: which file, which
    error)."""
    atomic_write(path, recording_bytes(history, recording_id, series))


def recording_series(path: str | Path, entity: str = "/evolution/best") -> dict[int, float]:
    """``{generation: value}`` of one series of an evolution recording (exceptions if unreadable)."""
    import rerun as rr

    out: dict[int, float] = {}
    try:
        os.fsdecode(os.fsencode(path)).encode()
        name, fd = Path(path), None
    except UnicodeEncodeError:  # Rerun takes UTF-8 names only: the open file's own name on Linux
        fd = os.open(path, os.O_RDONLY)
        name = Path(f"/proc/self/fd/{fd}")
    try:
        chunks = list(rr.chunk.RrdReader(name).stream())
    finally:
        if fd is not None:
            os.close(fd)
    for c in chunks:
        if c.entity_path == entity and not c.is_static:
            rb = c.to_record_batch()
            out.update(zip(rb.column(TIMELINE).to_pylist(), (v[0] for v in rb.column("Scalars:scalars").to_pylist())))
    return out


def recording_matches(path: str | Path, history: dict[str, np.ndarray]) -> bool:
    """Whether ``path`` is a complete recording of exactly this history (best and mean per generation)."""
    path = Path(path)
    try:
        if not path.is_file():
            return False
        with path.open("rb") as f:
            f.seek(max(0, path.stat().st_size - 64))
            if _FOOTER not in f.read():
                return False
        for name in ("best", "mean"):
            want = {int(g): float(v) for g, v in zip(history["generation"], history[name])}
            if recording_series(path, f"/evolution/{name}") != want:
                return False
        return True
    except Exception:  # any damage: not a match, rebuild it
        return False


class EvolutionLog:
    """Best/mean/worst fitness per generation to a live viewer and/or a ``.rrd`` file.

    The file (``path``) is made in memory and written whole and atomically by :meth:`close`.
    """

    def __init__(self, *, path: str | Path | None = None, spawn: bool = False, connect: str | None = None,
                 application_id: str = "evobiped_evolve", recording_id: str | None = None):
        import rerun as rr

        if not (spawn or connect is not None or path is not None):
            raise ValueError("EvolutionLog needs a path, spawn=True or a connect address")
        recording_id = recording_id or uuid.uuid4().hex
        self.path = None if path is None else Path(path)
        #: (recording, its binary stream or None for a viewer)
        self._targets = []
        if spawn or connect is not None:
            viewer = rr.RecordingStream(application_id, recording_id=recording_id)
            if spawn:
                viewer.spawn(connect=False)
                viewer.set_sinks(rr.GrpcSink(), default_blueprint=_blueprint())
            else:
                url = connect_url(connect)
                require_viewer(url)
                viewer.set_sinks(rr.GrpcSink(url), default_blueprint=_blueprint())
            self._targets.append((viewer, None))
        if self.path is not None:
            rec = rr.RecordingStream(application_id, recording_id=recording_id)
            stream = rec.binary_stream()
            rec.send_blueprint(_blueprint())
            self._targets.append((rec, stream))
        for rec, _ in self._targets:
            declare_series(rec)

    def log_generation(self, generation: int, *, best: float, mean: float, worst: float, median: float | None = None,
                       **counts: float) -> None:
        """One generation's fitness summary; ``counts`` (e.g. evaluations=50, falls=12) go to ``evolution/counts``."""
        import rerun as rr

        values = {"best": best, "mean": mean, "worst": worst, "median": median}
        for rec, _ in self._targets:
            rec.set_time(TIMELINE, sequence=int(generation))
            for name, v in values.items():
                if v is not None:
                    rec.log(f"evolution/{name}", rr.Scalars(float(v)))
            for name, v in counts.items():
                if v is not None:
                    rec.log(f"evolution/counts/{name}", rr.Scalars(float(v)))

    def log_history(self, history: dict[str, np.ndarray]) -> None:
        """Every generation so far at once, e.g. the checkpoint's history when a run resumes."""
        for rec, _ in self._targets:
            log_history(rec, history)

    def close(self) -> None:
        """Write the file whole, then flush the viewer stream (bounded)."""
        targets, self._targets = self._targets, []
        for rec, stream in targets:
            if stream is not None:
                data = stream.read(flush=True) or b""
                rec.disconnect()
                atomic_write(self.path, data)
            else:
                flush(rec, streaming=True)

    def __enter__(self) -> "EvolutionLog":
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc_type is None:
            self.close()
            return
        try:  # an error is on its way out already: do not mask it with another
            self.close()
        except Exception:
            pass


class RecordingFile:
    """A run's listener (:class:`evobiped.run.listeners.RunListener`) that keeps the run directory's evolution.rrd:
    the whole history and the optimizer's own series rewritten at each commit; a resume's rebuild rewrites it only
    when it disagrees with the checkpoint (noting the repair) and removes it while no generation is committed."""

    def committed(self, commit) -> None:
        path = commit.directory / RECORDING
        if commit.columns is None:
            if path.exists():
                sync_file(commit.directory, RECORDING, None, commit.repairs)
            return
        if commit.repairs is not None:
            if recording_matches(path, commit.columns):
                return
            commit.repairs.append(f"{RECORDING} rebuilt from the checkpoint")
        write_recording(path, commit.columns, commit.recording_id, commit.series)
