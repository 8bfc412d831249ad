"""A commanded walker (a network evolved on the command task) followed through a schedule of commands, stretch by
stretch: what ``evobiped gait GENOME`` reports.

Each stretch holds one command (speed m/s, turning rad/s, + left).  The walker's speed and turning rate in a stretch
are measured after it settles: from ``settle`` s (3 s; half the stretch when that is shorter) after the stretch
begins to its end, as the pelvis's path along its facing (m) and its facing's turn (rad) over that time.  A command
beyond what the walker was evolved for (:func:`evobiped.tasks.command_schedule.trained_range`) is clipped to the
nearest command it met (:func:`~evobiped.tasks.command_schedule.clip_command`), and a one-line note says so.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..core.errors import UserError
from ..core.options import given
from ..episode import EpisodeConfig
from ..tasks.command_schedule import clip_command, schedule_of, trained_range

#: s after a stretch begins that its speed and turning rate are measured from
SETTLE = 3.0
#: the senses a commanded walker reads
COMMAND_SENSES = ("command_speed", "command_turning")


def is_commanded(config: EpisodeConfig) -> bool:
    """Whether ``config`` is a commanded walker's: the command task, a controller that reads both commands."""
    inputs = getattr(config.controller_options, "inputs", None) or ()
    return config.task == "command" and all(s in inputs for s in COMMAND_SENSES)


def check_commanded(config: EpisodeConfig, what: str) -> None:
    """UserError (one line) unless ``config`` is a commanded walker's."""
    if not is_commanded(config):
        inputs = getattr(config.controller_options, "inputs", None) or ()
        reads = "reads " + ", ".join(s for s in COMMAND_SENSES
                                     if s in inputs) if any(s in inputs for s in COMMAND_SENSES) else "reads no command"
        raise UserError(f"{what} is not a commanded walker (task {config.task!r}, its controller {reads}): "
                        "it cannot follow --speed/--turning; evobiped gait takes a commanded walker's genome or a "
                        "map-elites run")


def plan(config: EpisodeConfig, speeds: list[float],
         turnings: list[float]) -> tuple[list[float], list[float], list[str]]:
    """The commands (m/s, rad/s) clipped to what the walker of ``config`` was evolved for, and a note per clipped
    value; UserError for a non-finite value or lists of unequal lengths (one of length 1 goes with every stretch)."""
    for name, values in (("--speed", speeds), ("--turning", turnings)):
        if not values or not all(math.isfinite(v) for v in values):
            raise UserError(f"{name}: expected finite numbers, comma-separated, got {values}")
    if len(speeds) > 1 and len(turnings) > 1 and len(speeds) != len(turnings):
        raise UserError(
            f"--turning: {len(turnings)} turning rates for {len(speeds)} speeds; give one, or one per speed")
    n = max(len(speeds), len(turnings))
    speeds, turnings = (v * n if len(v) == 1 else list(v) for v in (speeds, turnings))
    o = config.task_options
    (lo, hi), stops, (wlo, whi) = trained_range(o)
    met = (f"{lo:g}-{hi:g} m/s{' or 0' if stops else ''}, turning {math.degrees(wlo):+.1f} to {math.degrees(whi):+.1f} "
           "deg/s")
    out_s, out_w, notes = [], [], []
    for v, w in zip(speeds, turnings):
        cv, cw = clip_command(o, v, w)
        if (cv, cw) != (v, w):
            notes.append(f"note: command {v:g} m/s, {math.degrees(w):+.1f} deg/s is beyond what this walker was "
                         f"evolved for ({met}): clipped to {cv:g} m/s, {math.degrees(cw):+.1f} deg/s")
        out_s.append(cv)
        out_w.append(cw)
    return out_s, out_w, notes


def nominal_plan(config: EpisodeConfig, hold: float) -> tuple[list[float], list[float], list[float], float]:
    """The walker's own nominal schedule as stretches: (start times s, speeds, turnings, episode length s); its last
    value lasts ``hold`` s."""
    s = schedule_of(config.task_options)
    return [float(t) for t in s.times], [float(v) for v in s.speed], [float(w)
                                                                      for w in s.turning], float(s.times[-1]) + hold


class _Trace:
    """Listener: row 0's time (s), planar position (m), facing and whether both feet are down, per tick."""

    def __init__(self):
        self.t, self.xy, self.f, self.both = [], [], [], []

    def start(self, episode, sims):
        self.body = episode.body
        self.t.append(0.0)
        self.xy.append(self.body.planar_position(sims)[0].copy())
        self.f.append(self.body.heading(sims)[0].copy())

    def tick(self, t, sims, ids, neurons, action, task_state):
        if 0 in ids:
            self.t.append(float(t))
            self.xy.append(self.body.planar_position(sims)[0].copy())
            self.f.append(self.body.heading(sims)[0].copy())
            self.both.append(bool(self.body.contacts(sims)[0].all()))

    def end(self, result):
        pass


def follow_commands(config: EpisodeConfig, genome: np.ndarray, times: list[float], speeds: list[float],
                    turnings: list[float], seconds: float, *, settle: float = SETTLE) -> dict:
    """``genome`` of the commanded walker ``config`` alone in a nominal episode of ``seconds`` s whose commands switch
    at ``times`` (s) to ``speeds`` (m/s) and ``turnings`` (rad/s): a dict with ``stretches`` (per stretch: start, end,
    commanded and walked speed and turning, errors, fell), ``fell``, ``end_time`` and ``trace`` (per tick: time,
    the tick's start, its commands, the walked speed and turning rate over it, and ``both_down``: both feet on the
    ground at its end)."""
    options = {**given(config.task_options), "schedule": "piecewise", "times": [float(t) for t in times],
               "speed": [float(v) for v in speeds], "turning": [float(w) for w in turnings]}
    cfg = dataclasses.replace(config.nominal(), task_options=options, seconds=float(seconds))
    episode = cfg.build()
    trace = _Trace()
    result = episode.run(np.asarray(genome, float)[None], listener=trace)
    t, xy, f = np.array(trace.t), np.array(trace.xy), np.array(trace.f)
    dt = np.diff(t)
    along = np.einsum("ki,ki->k", np.diff(xy, axis=0), f[1:])  # m along the facing, per tick
    turn = np.arctan2(f[:-1, 0] * f[1:, 1] - f[:-1, 1] * f[1:, 0], np.einsum("ki,ki->k", f[:-1], f[1:]))
    fell, end = bool(result.fell[0]), float(result.end_time[0])
    bounds = list(times) + [float(seconds)]
    stretches = []
    for i, (v, w) in enumerate(zip(speeds, turnings)):
        a, b = bounds[i], bounds[i + 1]
        first = a + min(settle, (b - a) / 2)
        ticks = (t[1:] > first + 1e-9) & (t[1:] <= b + 1e-9)
        span = float(dt[ticks].sum())
        walked = float(along[ticks].sum() / span) if span > 0 else None  # None: down before it settled
        turned = float(turn[ticks].sum() / span) if span > 0 else None
        stretches.append({
            "start": a, "end": b, "measured_from": first, "commanded_speed": v, "commanded_turning": w,
            "walked_speed": walked,
            "walked_turning": turned, "speed_error_pct": 100 * abs(walked - v) / v if v > 0 and span > 0 else None,
            "turning_error_pct": 100 * abs(turned - w) / abs(w) if w != 0 and span > 0 else None,
            "fell": fell and a < end <= b + 1e-9, "down": fell and end <= a})
    k = np.searchsorted(np.asarray(times) + 1e-6, t[:-1], side="right") - 1
    return {"stretches": stretches, "fell": fell, "end_time": end, "seconds": float(seconds),
            "trace": {"time": t[:-1].tolist(), "commanded_speed": np.asarray(speeds)[np.maximum(k, 0)].tolist(),
                      "commanded_turning": np.asarray(turnings)[np.maximum(k, 0)].tolist(),
                      "walked_speed": (along / np.maximum(dt, 1e-12)).tolist(),
                      "walked_turning": (turn / np.maximum(dt, 1e-12)).tolist(), "both_down": trace.both}}


def stretch_line(s: dict) -> str:
    """One stretch of :func:`follow_commands` in words (turning in deg/s)."""
    head = (f"{s['start']:6.1f}-{s['end']:6.1f} s: commanded {s['commanded_speed']:.3f} m/s, "
            f"{math.degrees(s['commanded_turning']):+6.1f} deg/s -> ")
    if s["down"]:
        return head + "down (fell before this stretch)"
    if s["walked_speed"] is None:
        return head + "not measured (fell before it settled)" + (", FELL" if s["fell"] else "")
    err = [f"speed {s['speed_error_pct']:.1f} % off" if s["speed_error_pct"] is not None
           else f"speed {abs(s['walked_speed']):.3f} m/s off 0",
           f"turning {s['turning_error_pct']:.1f} % off" if s["turning_error_pct"] is not None
           else f"turning {abs(math.degrees(s['walked_turning'])):.1f} deg/s off 0"]
    return (head + f"walked {s['walked_speed']:.3f} m/s, {math.degrees(s['walked_turning']):+6.1f} deg/s "
                   f"({', '.join(err)})"
            + (", FELL" if s["fell"] else ""))


def nominal_words(config: EpisodeConfig) -> str:
    """One line: the commands a commanded walker's replay follows (its nominal schedule) and how to give others."""
    s = schedule_of(config.task_options)
    steps = ", ".join(f"{v:g} m/s {math.degrees(w):+.0f} deg/s from {t:g} s" for t, v,
                      w in zip(s.times, s.speed, s.turning))
    kind = ("the fixed tour of its drawn range" if config.task_options.schedule == "drawn"
            else f"its {config.task_options.schedule} schedule")
    return f"commands: {kind} ({steps}); evobiped gait SOURCE --speed ... --turning ... follows others"
