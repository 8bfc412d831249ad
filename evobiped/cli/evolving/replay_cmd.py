"""``evobiped replay``: a stored genome re-simulated into a Rerun recording, figures and a video; the stored outcome
checked."""

from __future__ import annotations

import sys

from ...flags import (add_source_flag, add_stored_walker, finite_float, positive_float, positive_int, refuse,
                      unfinished_note, walk_line)
from ...core.progress import Progress


def add_replay(sub) -> None:
    p = sub.add_parser("replay", help="re-simulate a stored genome into a Rerun recording (and figures)")
    add_stored_walker(p, generation="replay the best of generation N of a run directory")
    p.add_argument("--cell", metavar="I,J", help="replay the elite of cell I,J of a map-elites run's archive (evobiped "
                                                 "repertoire)")
    p.add_argument("--seconds", type=positive_float, metavar="S", help="episode length in s (default: the stored one)")
    where = p.add_mutually_exclusive_group()
    where.add_argument("--out", metavar="FILE.rrd", help="recording file (default RUN/replay_best.rrd, "
                                                         "RUN/replay_best_video.rrd with --video; for a genome file in "
                                                         "a run directory or under runs/ its folder's "
                                                         "replay_<stem>.rrd, else runs/<stem>/replay_<stem>.rrd)")
    where.add_argument("--spawn", action="store_true", help="stream to a newly spawned Rerun viewer instead of a file")
    where.add_argument("--connect", nargs="?", const="", metavar="ADDR",
                       help="stream to a running viewer (default 127.0.0.1:9876)")
    p.add_argument("--figures", nargs="?", const="", metavar="DIR",
                   help="also write the figures as PNG (default: beside the recording)")
    p.add_argument("--video", metavar="FILE", help="also render a video, MP4 or GIF by the suffix, without a display "
                   "(MuJoCo's offscreen renderer; MUJOCO_GL unset: a display's GLFW, else EGL, else OSMesa); "
                   "the frames go into the recording too")
    p.add_argument("--video-size", nargs=2, type=positive_int, metavar=("W", "H"), default=[480, 360],
                   help="size of each panel in pixels, even numbers (default 480 360; a steering walker gets one panel "
                        "per source)")
    p.add_argument("--video-fps", type=positive_float, default=25.0, metavar="FPS",
                   help="frames per simulated second (default 25: real time)")
    p.add_argument("--video-window", nargs=2, type=finite_float, metavar=("T0", "T1"),
                   help="only simulated times T0..T1 s (default: all)")
    add_source_flag(p)
    p.add_argument("--quiet", action="store_true", help="no progress lines")
    p.set_defaults(func=run_replay_cmd)


def run_replay_cmd(args) -> int:
    from pathlib import Path

    from ...usecases.replaying import replay, stored_walker
    from ...files.rundir import figures_dir

    video_flags = args.video_window is not None or args.video_size != [480, 360] or args.video_fps != 25.0
    if args.video is None and video_flags:
        refuse("--video-size/--video-fps/--video-window", "they shape the video: give --video FILE too")
    if any(v % 2 for v in args.video_size):
        refuse("--video-size", f"width and height must be even (H.264), got {args.video_size[0]} {args.video_size[1]}")
    if args.video_window is not None and not 0 <= args.video_window[0] < args.video_window[1]:
        refuse("--video-window", f"needs 0 <= T0 < T1, got {args.video_window[0]:g} {args.video_window[1]:g}")
    source = stored_walker(args.source, args.generation, args.cell, args.allow_unfinished)
    unfinished_note(source)
    if source.config.env is not None:
        return _replay_env(args, source)
    figures = args.figures
    if figures == "":
        base = Path(args.out).parent if args.out else source.outputs
        figures = figures_dir(base, source.label)
    seconds = args.seconds or source.config.seconds
    if args.video is not None:  # before anything is written: the longest the video can be
        from ...record.video import check_frames

        if args.video_window is not None and args.video_window[0] > seconds:
            refuse("--video-window", f"{args.video_window[0]:g} {args.video_window[1]:g}: the episode ends at "
                                     f"{seconds:g} s at the latest")
        span = seconds if args.video_window is None else min(seconds, args.video_window[1]) - args.video_window[0]
        check_frames(span, args.video_fps, args.video_size[0] * args.video_size[1] * 3)
    progress = Progress("replay", seconds, "s simulated", quiet=args.quiet)
    frames = Progress("replay video", 1.0, "frames rendered", quiet=args.quiet)
    r = replay(source, seconds=args.seconds, out=args.out, spawn=args.spawn, connect=args.connect, figures_dir=figures,
               listener=progress.listener(), sources=args.sources, video=args.video,
               video_options=dict(fps=args.video_fps, size=tuple(args.video_size), window=args.video_window,
                                  progress=frames),
               note=lambda line: print(f"evobiped: note: {line}", file=sys.stderr))
    progress.finish()
    if args.video:
        frames.finish()
    state = f"fell at t = {r.end_time:.2f} s" if r.fell else f"stayed up for {r.end_time:.1f} s"
    print(f"replayed fitness = {r.fitness!r}; {state}; {walk_line(r.walk)}")
    if source.config.task == "command" and args.sources:
        print("commands: from its ears (the steering rule of evobiped.tasks.steer_command), towards the --source given")
    elif source.config.task == "command":  # a commanded walker replays its nominal schedule: say which
        from ...analysis.commanded import nominal_words

        print(nominal_words(source.config))
    if r.gait is not None:
        from ...analysis.gait_report import criteria_words, gait_line

        print(f"gait: {gait_line(r.gait)}; "
              f"{'walks' if r.gait['walks'] else 'does not walk: ' + criteria_words(r.gait['failed'])}")
    if not r.compared:
        print(f"stored fitness not compared: {r.not_compared}")
    elif r.stored_fitness is None:
        print("stored fitness: none in the genome file")
    elif not r.environment_differences:
        verdict = "equals it bit for bit" if r.matches else f"DIFFERS by {r.fitness - r.stored_fitness:.3g}"
        print(f"stored fitness   = {r.stored_fitness!r}: the replay {verdict} (same numerical environment)")
    else:
        print(f"numerical environment differs from the stored one: {'; '.join(r.environment_differences)}")
        print(f"stored fitness   = {r.stored_fitness!r}: "
              + ("the replay equals it bit for bit all the same" if r.matches
                 else f"drift {drift_text(r.fitness, r.stored_fitness)}"))
    if r.outcome_checked:
        if r.environment_differences and not r.compared:
            print(f"numerical environment differs from the stored one: {'; '.join(r.environment_differences)}")
        print("outcome drift: " + "; ".join(r.drift))
        print("outcome holds within the declared tolerance" if not r.outcome_failures
              else "outcome DIFFERS: " + "; ".join(r.outcome_failures))
    elif source.stored_outcome() is None and (not r.compared or r.environment_differences):  # nothing at all checked
        print("outcome not checked: the file records none (nothing of this replay is compared with the stored walker)")
    print(f"recording: {r.recording}" if r.recording else "recording streamed to the viewer")
    for f in r.figures:
        print(f"figure: {f}")
    if r.video is not None:
        print(f"video: {r.video}")
    return 0 if r.reproduced else 1


def _replay_env(args, source) -> int:
    """The replay of a genome evolved in a Gymnasium environment: its recording, its return against the stored one."""
    from pathlib import Path

    from ...usecases.gym_replaying import replay_env
    from ...usecases.replaying import default_out

    given = [f for f, v in (("--video", args.video), ("--spawn", args.spawn), ("--connect", args.connect),
                            ("--figures", args.figures), ("--seconds", args.seconds), ("--source", args.sources)) if v]
    if given:
        refuse(given[0], f"not for an environment's episode ({source.config.env}): it records to a file")
    r = replay_env(source, Path(args.out) if args.out else default_out(source))
    ended = "ended by the environment" if r.terminated else "to its time limit"
    print(f"replayed return = {r.fitness!r}; {r.steps} steps, {ended}")
    if r.stored_fitness is not None:
        same = "equals it bit for bit" if r.matches else f"DIFFERS by {r.fitness - r.stored_fitness:.3g}"
        differs = "; ".join(r.environment_differences)
        other = f" (numerical environment differs: {differs})" if differs else ""
        print(f"stored fitness  = {r.stored_fitness!r}: the replay {same}{other}")
    print(f"recording: {r.recording}")
    return 0 if r.matches or r.stored_fitness is None or r.environment_differences else 1


def drift_text(value: float, stored: float) -> str:
    """``+3.4e-06 (8.2e-05 relative)``: how far a replayed fitness drifted from the stored one."""
    d = value - stored
    rel = f" ({abs(d) / abs(stored):.2g} relative)" if stored else ""
    return f"{d:+.3g}{rel}"


SUBCOMMANDS = (add_replay,)
