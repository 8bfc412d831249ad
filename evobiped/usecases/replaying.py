"""The replay use case: re-simulate a stored genome deterministically, record it, compare fitness.

The replay is the same episode the GA ran (``EpisodeConfig(**stored).build()``
with the genome alone; batch size does not change results) with its recording
(:class:`~evobiped.record.recordings.replay_recording.ReplayRecording`) listening, so in the numerical environment
the genome was stored in (:mod:`evobiped.core.provenance`) the replayed fitness
equals the stored one to the last bit; in another, the report says what differs
and how far the outcome drifted (:mod:`evobiped.files.outcome`).  The ``.rrd`` is made in memory and
written whole by :func:`~evobiped.core.fileio.atomic_write` at the end: a failed
replay leaves nothing half-written.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path

from ..core.errors import UserError
from ..files import rundir
from ..files.outcome import compare, outcome
from ..files.rundir.output_set import output_set
from ..core.provenance import differences
from ..record.source import Source
from ..record.trajectory import Trajectory, TrajectoryRecorder
from ..tasks.sound import with_sources


@dataclass
class ReplayReport:
    """What a replay did."""

    fitness: float
    stored_fitness: float | None  # None if the source has none
    #: why the stored fitness was not compared (--seconds or --source changed the episode, or it is the aggregate over
    #: perturbed presentations); None: it was
    not_compared: str | None
    fell: bool
    end_time: float
    #: distance and walking direction (``EpisodeResult.walk``)
    walk: dict
    recording: Path | None
    figures: list[Path]
    trajectory: Trajectory
    #: what the walker did (:func:`evobiped.files.outcome.outcome`)
    outcome: dict
    # : how this process's numerical environment differs from the recorded one
    # (:func:`evobiped.core.provenance.differences`);
    #: empty: the replay must be bit-identical
    environment_differences: list[str]
    # : how far the outcome drifted from the stored one, and what lies outside the tolerance
    # (:func:`evobiped.files.outcome.compare`)
    drift: list[str]
    outcome_failures: list[str]
    video: Path | None = None
    #: the walker's gait (:func:`evobiped.analysis.gait_report.measured`); None for a body without feet
    gait: dict | None = None

    @property
    def compared(self) -> bool:
        """The replayed episode is the one the stored fitness was scored on (see :attr:`not_compared`)."""
        return self.not_compared is None

    @property
    def matches(self) -> bool:
        """Replayed fitness equals the stored one bit for bit."""
        return self.compared and self.stored_fitness is not None and self.fitness == self.stored_fitness

    @property
    def outcome_checked(self) -> bool:
        """The outcome was checked against the stored one: in another numerical environment, or where the stored
        fitness cannot be compared (a run under perturbations; its file's ``outcome`` is the nominal episode's)."""
        return bool(self.drift or self.outcome_failures) and (bool(self.environment_differences) or not self.compared)

    @property
    def reproduced(self) -> bool:
        """What the reproducibility contract promises holds: bit for bit in the recorded numerical environment,
        the same outcome within :data:`evobiped.files.outcome.TOLERANCE` in another (True when nothing is compared)."""
        bits = self.matches or not self.compared or self.stored_fitness is None or bool(self.environment_differences)
        return bits and not (self.outcome_checked and self.outcome_failures)


def stored_walker(path: str | Path, generation: int | None = None, cell: str | None = None,
                  allow_unfinished: bool = False) -> Source:
    """What a replay re-simulates: the best of a run directory (of its generation ``generation``), a genome file,
    or the elite of grid cell ``cell`` (``"I,J"``) of a map-elites run's archive; UserError, one line, otherwise."""
    if cell is None:
        from ..record.source import resolve

        return resolve(path, generation, allow_unfinished)
    from ..repertoire.elites import load_repertoire, parse_cell

    if generation is not None:
        raise UserError("--cell: an archive's elite is of no generation: give --cell or --generation")
    return load_repertoire(path).source(parse_cell(cell))


def default_out(source: Source, video: bool = False) -> Path:
    """``RUN/replay_best.rrd``, ``RUN/replay_gen_0007.rrd``, ``RUN/replay_selected.rrd`` for a run's
    ``selected.json``, or ``runs/<stem>/replay_<stem>.rrd`` for a lone genome file (:attr:`Source.outputs`:
    never beside a file outside ``runs/``); ``replay_<label>_video.rrd`` for a recording with the video's frames,
    so a replay without them never overwrites one with them (nor the other way round)."""
    path = rundir.replay_file(source.outputs, source.label)
    return path.with_name(f"{path.stem}_video{path.suffix}") if video else path


def replay(
    source: Source,
    *,
    seconds: float | None = None,
    out: str | Path | None = None,
    spawn: bool = False,
    connect: str | None = None,
    figures_dir: str | Path | None = None,
    listener=None,
    sources=None,
    video: str | Path | None = None,
    video_options: dict | None = None,
    note=None,
) -> ReplayReport:
    """Re-simulate ``source``; record to ``out`` (default :func:`default_out`, ``_video`` with ``video``) or a viewer
    (``spawn``/``connect``). ``listener`` (optional) also watches the episode, e.g.
    :meth:`evobiped.core.progress.Progress.listener`; ``sources`` (``[[x, y], ...]`` m, optional) replaces a steering
    walker's sound sources; ``video`` (optional, ``.mp4`` or ``.gif``) also renders the episode there and into the
    recording (``video_options``: :func:`~evobiped.record.video.render_frames`'s ``fps``, ``size``, ``window``,
    ``progress``). The recording, video and figures are one set (:func:`~evobiped.files.rundir.output_set.output_set`):
    ``note(line)`` hears that the previous replay there was cut short."""
    from ..record.recordings.viewer import require_display

    if spawn:
        require_display()
    if video is not None:
        from ..record.video import check_video_path

        video = check_video_path(video)
    cfg = source.config
    if seconds is not None:
        cfg = dataclasses.replace(cfg, seconds=float(seconds))
    cfg = with_sources(cfg, sources)
    episode = cfg.build()
    history = _history(source)
    opts = dict(video_options or {})
    if video is not None:  # an OpenGL context first: without one, the one line comes before anything is recorded
        from ..record.video import SIZE, FrameRenderer

        opts["renderer"] = FrameRenderer(episode.model, *opts.get("size", SIZE))
    streaming = spawn or connect is not None
    target = None if streaming and out is None else Path(out) if out is not None else default_out(
        source, video is not None)
    owned = [Path(figures_dir)] if figures_dir is not None and Path(figures_dir).name.startswith("figures_") else []
    try:  # one set: the previous replay's outputs go first, a cut-short one is said (``note``)
        with output_set("replay", [p for p in (target, video) if p is not None], owned, say=note):
            return _replay(source, cfg, episode, history, out=out, spawn=spawn, connect=connect,
                           figures_dir=figures_dir, listener=listener, video=video, video_options=opts,
                           not_compared=_not_compared(source, cfg, seconds is not None, bool(sources)))
    finally:
        if video is not None:
            opts["renderer"].close()


def _replay(source, cfg, episode, history, *, out, spawn, connect, figures_dir, listener, video, video_options,
            not_compared):
    from ..analysis.gait_report import FootRecorder, has_feet
    from ..record.recordings.replay_recording import ReplayRecording

    streaming = spawn or connect is not None
    target = None if streaming and out is None else Path(out) if out is not None else default_out(
        source, video is not None)
    recording = ReplayRecording(target, spawn=spawn, connect=connect,
                                name=f"{cfg.body}/{cfg.controller}: {source.genome_path}")
    recorder = recording.recorder
    # one walker per presentation when the task names each one's target (a steering walker's sound sources)
    steering = episode.task.targets() is not None
    others = [TrajectoryRecorder(j) for j in range(1, episode.task.presentations)] if steering else []
    feet = FootRecorder() if has_feet(episode.body) else None
    watchers = [recorder, *others] + ([feet] if feet is not None else []) + ([listener] if listener is not None else [])
    try:
        return _recorded(source, cfg, episode, history, recording, recorder, others, feet, watchers,
                         figures_dir=figures_dir, video=video, video_options=video_options, not_compared=not_compared)
    except BaseException:  # a stop signal, an error: the recording is dropped, with nothing said by Rerun at exit
        recording.discard()
        raise


def _recorded(source, cfg, episode, history, recording, recorder, others, feet, watchers, *, figures_dir, video,
              video_options, not_compared):
    from ..analysis.gait_report import measured
    from ..episode import Listeners
    from ..record.png.figures import fitness_label, replay_figures
    from ..record.png.steering_figures import steering_figures

    result = episode.run(source.genome[None, :], listener=Listeners(*watchers) if len(watchers) > 1 else recorder)
    first = result.rows if result.rows is not None else result  # the first presentation's row, as the recorder's
    gait = None if feet is None else measured(feet, episode, start=first.start_position[:1], end=first.end_position[:1],
                                              facing=first.start_facing[:1], time_up=float(first.end_time[0]),
                                              seconds=cfg.seconds, up=not bool(first.fell[0]))
    traj = recorder.trajectory
    trajs = [traj] + [o.trajectory for o in others]
    frames = times = None
    if video is not None:
        from ..record.video import render_frames

        names = [source.name] if not others else [f"{source.name}, source ({q[0]:g}, {q[1]:g}) m" for q in traj.sources]
        frames, times = render_frames(trajs, names, **video_options)
    recording.finish(trajs, history=history, frames=frames, times=times, gait=gait)
    if video is not None:
        from ..record.video import FPS, write_video

        write_video(video, frames, video_options.get("fps", FPS))
    figs = []
    if figures_dir is not None:
        seed = source.meta.get("seed")
        who = f"{source.name}: {cfg.body}/{cfg.controller}" + (f", run seed {seed}" if seed is not None else "")
        figs = replay_figures(traj, figures_dir, history=history, fitness_ylabel=fitness_label(cfg), who=who)
        if others:
            figs += steering_figures(trajs, figures_dir, who=who)
        if gait is not None:
            from ..record.png.footfall_figure import footfall_figure

            figs.append(Path(figures_dir) / "footfalls.png")
            footfall_figure(gait, figs[-1], title=who)
    stored = source.meta.get("fitness")
    done = outcome(result, episode.task.targets())
    unchanged = cfg.seconds == source.config.seconds and cfg.task_options == source.config.task_options
    stored_outcome = source.stored_outcome() if unchanged else None
    drift, failures = compare(stored_outcome, done) if stored_outcome is not None else ([], [])
    return ReplayReport(
        fitness=float(result.fitness[0]),
        stored_fitness=float(stored) if isinstance(stored, (int, float)) else None,
        not_compared=not_compared,
        fell=bool(result.fell[0]),
        end_time=float(result.end_time[0]),
        walk=result.walk(),
        recording=recording.target,
        figures=figs,
        trajectory=traj,
        outcome=done,
        environment_differences=differences(source.environment),
        drift=drift,
        outcome_failures=failures,
        video=video,
        gait=gait,
    )


def _not_compared(source: Source, cfg, seconds_given: bool, sources_given: bool) -> str | None:
    """Why the stored fitness of ``source`` cannot be compared with a replay of episode ``cfg`` (None: it can)."""
    if (cfg.seconds == source.config.seconds and cfg.task_options == source.config.task_options
            and not source.config.perturbed):
        return None
    if source.config.perturbed:
        return "it is the aggregate over the perturbed presentations the run evolved on; the replay is nominal"
    return ("--source changed the sources" if sources_given and not seconds_given
            else "--seconds changed the episode length")


def _history(source: Source):
    if source.run_dir is None or not (source.run_dir / rundir.HISTORY).is_file():
        return None
    return rundir.read_history(source.run_dir / rundir.HISTORY)
