"""A rhythm generator's one command as a walker's speed command: what ``evobiped gait GENOME --u0/--go`` reports.

The matsuoka controller's tonic input ``u0`` (Taga et al. 1991 change the speed with it) and the g3 controller's GO
signal ``go`` (Pribe et al. 1997's) are each one number the papers turn to change the gait.  :func:`command_sweep`
runs a walker's genome through levels of that command, ``hold`` s each, in one episode (the command a schedule of
the controller, :func:`evobiped.core.schedule.timed_levels`; a fall ends the episode, nothing restarts it), and
measures each stretch from ``settle`` s (3 s; half the stretch when that is shorter) after it begins to its end, the
first seconds being the transition to the new level: the mean forward speed (m/s, along the facing at the start),
the gait lab's measures over that time (:func:`evobiped.analysis.gait_report.measured`: duty factors, flight, slip,
step length, cadence, whether it walks) and the rhythm's period (s: the first strong peak of the autocorrelation of
the first actuator's command).  :func:`speed_line` fits speed = a + b * command by least squares over
the measured levels, with each level's deviation from the line (% of the line's value), whether the speeds are
monotone in the command, and the ratio fastest / slowest.

A level far beyond the walker's experience is clipped (:func:`clip_levels`): when its genome file records the
level or schedule it was evolved with, levels outside [min, max] of it widened by :data:`MARGIN` (a fraction of each
end: 50 %, so a walker evolved at 5.5 takes 2.75-8.25) are clipped to that range, with one note line; a walker that
records none (its controller's default) is not clipped.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..core.errors import UserError
from ..core.options import given
from ..core.schedule import timed_levels
from ..episode import EpisodeConfig
from .commanded import SETTLE
from .gait_report import FootRecorder, has_feet, measured

#: controller -> the option that is its command
COMMAND_OPTION = {"matsuoka": "u0", "g3": "go"}
#: the evolved range is widened by this fraction of each end before a level is clipped
MARGIN = 0.5
#: the gait lab's measures a stretch reports
GAIT_KEYS = ("duty_min", "duty_asymmetry", "airborne", "double_support", "steps_per_s", "step_length", "slip",
             "slip_share", "sliding", "clearance", "power", "cost_of_transport", "froude")


def check_command(config: EpisodeConfig, option: str, what: str) -> None:
    """UserError (one line) unless ``config``'s controller takes the command ``option`` (``u0``: matsuoka, ``go``:
    g3)."""
    if COMMAND_OPTION.get(config.controller) != option:
        owner = next(c for c, o in COMMAND_OPTION.items() if o == option)
        raise UserError(f"--{option}: {what} is driven by controller {config.controller!r}, not {owner!r}: --{option} "
                        f"is the {owner} controller's command")


def evolved_range(config: EpisodeConfig, option: str) -> tuple[float, float] | None:
    """The smallest and largest level of the command ``option`` that ``config`` records (a level or a schedule's
    levels); None when it records none (the controller's default)."""
    values = given(config.controller_options)
    if option not in values:
        return None
    levels = timed_levels(values[option])[1]
    return float(levels.min()), float(levels.max())


def clip_levels(config: EpisodeConfig, option: str, levels: list[float]) -> tuple[list[float], list[str]]:
    """``levels`` clipped to the walker's evolved range widened by :data:`MARGIN` (module docstring), and the note:
    one line naming every clipped level, or none.  UserError for a non-finite or negative level."""
    if not levels or not all(math.isfinite(v) and v >= 0 for v in levels):
        raise UserError(f"--{option}: expected finite levels >= 0, comma-separated, got {levels}")
    span = evolved_range(config, option)
    if span is None:
        return list(levels), []
    lo, hi = span[0] * (1 - MARGIN), span[1] * (1 + MARGIN)
    out = [min(max(v, lo), hi) for v in levels]
    clipped = [(v, c) for v, c in zip(levels, out) if c != v]
    if not clipped:
        return out, []
    met = f"{span[0]:g}" if span[0] == span[1] else f"{span[0]:g}-{span[1]:g}"
    return out, [f"note: {option} {', '.join(f'{v:g}' for v, _ in clipped)} "
                 f"{'is' if len(clipped) == 1 else 'are'} beyond what this walker was evolved for ({option} {met}, "
                 f"widened by {100 * MARGIN:g} %: {lo:g}-{hi:g}): clipped to {', '.join(f'{c:g}' for _, c in clipped)}"]


class _LevelTrace:
    """Listener: row 0's time (s), planar position (m) and first command, per tick; its facing at the start."""

    def __init__(self):
        self.t, self.xy, self.action = [], [], []

    def start(self, episode, sims):
        self.body = episode.body
        self.t.append(0.0)
        self.xy.append(self.body.planar_position(sims)[0].copy())
        self.facing = self.body.heading(sims)[0].copy()

    def tick(self, t, sims, ids, neurons, action, task_state):
        if 0 in ids:
            self.t.append(float(t))
            self.xy.append(self.body.planar_position(sims)[0].copy())
            self.action.append(float(action[list(ids).index(0), 0]))

    def end(self, result):
        pass


def _period(t: np.ndarray, x: np.ndarray) -> float | None:
    """The period (s) of ``x`` sampled at the evenly spaced times ``t``: the first lag at which its autocorrelation
    has a peak of at least 0.8 of its highest one (so a cycle with two bumps counts once), searched up to half the
    record; None for a record too short or flat to show one."""
    n = len(x)
    c = x - x.mean()
    if n < 8 or not np.any(c):
        return None
    f = np.fft.rfft(c, 2 * n)
    r = np.fft.irfft(f * np.conj(f))[: n // 2]
    r = r / r[0]
    peaks = np.flatnonzero((r[1:-1] > r[:-2]) & (r[1:-1] >= r[2:]) & (r[1:-1] > 0)) + 1
    if not len(peaks):
        return None
    best = r[peaks].max()
    return float(peaks[np.argmax(r[peaks] >= 0.8 * best)] * (t[-1] - t[0]) / (n - 1))


def _finite(v):
    return float(v) if v is not None and np.isfinite(v) else None


def command_sweep(config: EpisodeConfig, genome: np.ndarray, option: str, levels: list[float], hold: float, *,
                  settle: float = SETTLE) -> dict:
    """``genome`` ``(G,)`` of ``config`` through the command ``option``'s ``levels``, ``hold`` s each, in one nominal
    episode (module docstring): a dict with ``stretches`` (per level: ``level``, ``start``, ``end``,
    ``measured_from`` s, ``speed`` m/s, ``fell`` (in this stretch), ``down`` (before it), ``period`` s, ``gait``:
    the gait lab's measures, ``walks`` and ``failed``), ``fit`` (:func:`speed_line`), ``fell``, ``end_time`` s,
    ``seconds`` and ``trace`` (``time`` s and ``forward`` m along the initial facing, every 0.02 s or tick)."""
    schedule = [[i * float(hold), float(v)] for i, v in enumerate(levels)]
    seconds = float(hold) * len(levels)
    options = {**given(config.controller_options), option: schedule}
    cfg = dataclasses.replace(config.nominal(), controller_options=options, seconds=seconds)
    episode = cfg.build()
    if not has_feet(episode.body):
        raise UserError(f"body {episode.body.name!r} declares no feet: its gait cannot be measured")
    from ..episode.listener import Listeners

    trace, feet = _LevelTrace(), FootRecorder()
    result = episode.run(np.asarray(genome, float)[None], listener=Listeners(trace, feet))
    t, facing = np.array(trace.t), trace.facing
    forward = (np.array(trace.xy) - trace.xy[0]) @ facing
    action = np.array(trace.action)
    fell, end = bool(result.fell[0]), float(result.end_time[0])
    stretches = []
    for i, v in enumerate(levels):
        a, b = i * float(hold), (i + 1) * float(hold)
        first = a + min(settle, (b - a) / 2)
        ticks = np.flatnonzero((t > first + 1e-9) & (t <= b + 1e-9))
        row = {"level": float(v), "start": a, "end": b, "measured_from": first, "fell": fell and a < end <= b + 1e-9,
               "down": fell and end <= first + 1e-9, "speed": None, "period": None, "gait": None, "walks": False,
               "failed": ["up"]}
        if len(ticks) >= 2 and not row["down"]:
            k0, k1 = ticks[0] - 1, ticks[-1]  # from the position at `first` to the last tick's
            span = t[k1] - t[k0]
            row["speed"] = float((forward[k1] - forward[k0]) / span)
            row["period"] = _period(t[ticks], action[ticks - 1])
            g = measured(feet.between(first, b), episode, start=np.array(trace.xy)[None, k0],
                         end=np.array(trace.xy)[None, k1], facing=facing[None], time_up=float(span),
                         seconds=b - first, up=not row["fell"])
            row["gait"] = {**{f"duty_{f}": _finite(g[f"duty_{f}"]) for f in g["feet"]},
                           **{k: _finite(g[k]) for k in GAIT_KEYS}}
            row["walks"], row["failed"] = g["walks"], g["failed"]
        stretches.append(row)
    fit = speed_line(stretches)
    deviation = dict(zip(fit["stretches"], fit["deviation_pct"]))
    for i, row in enumerate(stretches):
        row["deviation_pct"] = deviation.get(i)
    every = max(1, int(round(0.02 / episode.control_dt)))
    return {"command": option, "hold": float(hold), "settle": float(settle),
            "feet": list(episode.body.contact_sensor[1]), "stretches": stretches, "fit": fit, "fell": fell,
            "end_time": end, "seconds": seconds,
            "trace": {"time": t[::every].tolist(), "forward": forward[::every].tolist()}}


def speed_line(stretches: list[dict]) -> dict:
    """The least-squares line speed = ``intercept`` + ``slope`` * level over the stretches with a measured speed and
    no fall (``stretches``: their indices), each one's ``deviation_pct`` from it (% of the line's value; None where
    the line is within 1 mm/s of 0), ``monotone`` (``"rising"``, ``"falling"`` or None: the speeds order as the
    levels do, for every two distinct levels) and ``ratio`` (fastest over slowest; None unless every speed is above
    0).  Fewer than two distinct levels: no line (``slope`` None)."""
    done = [i for i, s in enumerate(stretches) if s["speed"] is not None and not s["fell"]]
    c = np.array([stretches[i]["level"] for i in done])
    v = np.array([stretches[i]["speed"] for i in done])
    out = {"stretches": done, "levels": c.tolist(), "speeds": v.tolist(), "intercept": None, "slope": None,
           "deviation_pct": [], "monotone": None, "ratio": float(v.max() / v.min()) if len(v) and v.min() > 0 else None}
    if len(set(c.tolist())) < 2:
        return out
    b, a = np.polyfit(c, v, 1)
    line = a + b * c
    out.update(intercept=float(a), slope=float(b),
               deviation_pct=[float(100 * (x - y) / y) if abs(y) > 1e-3 else None for x, y in zip(v, line)])
    pairs = [(v[j] - v[i]) * np.sign(c[j] - c[i]) for i in range(len(c)) for j in range(i + 1, len(c)) if c[i] != c[j]]
    out["monotone"] = "rising" if all(p > 0 for p in pairs) else "falling" if all(p < 0 for p in pairs) else None
    return out


def _cell(x: float | None, spec: str, scale: float = 1.0, unit: str = "") -> str:
    return "-" if x is None else format(scale * x, spec) + unit


def sweep_lines(report: dict) -> list[str]:
    """The report of :func:`command_sweep` as a table a person reads (a row per level: its stretch, speed, deviation
    from the fitted line, rhythm period, duty factor per foot, % of the time airborne, slip as % of the speed, step
    length, cadence, the gait's verdict), then the line fitted through it and whether it fell."""
    name, fit = report["command"], report["fit"]
    duty = "duty " + "/".join(f[0].upper() for f in report["feet"])
    lines = [f"{name:>6} {'stretch s':>11} {'speed m/s':>9} {'vs line':>8} {'period s':>8} {duty:>9} "
             f"{'airborne':>8} {'slip':>6} {'step m':>6} {'steps/s':>7}  gait"]
    for s in report["stretches"]:
        head = f"{s['level']:6g} {s['start']:5.1f}-{s['end']:5.1f}"
        if s["speed"] is None:
            lines.append(f"{head} " + ("down (fell before this stretch)" if s["down"]
                                       else "not measured (fell before it settled)"))
            continue
        g, d = s["gait"], s["deviation_pct"]
        duty = "/".join(_cell(g[k], ".2f") for k in g if k.startswith("duty_") and k not in ("duty_min",
                                                                                               "duty_asymmetry"))
        verdict = "walks" if s["walks"] else "not a walk: " + ", ".join(s["failed"])
        lines.append(f"{head} {s['speed']:9.3f} {_cell(d, '+.1f', unit=' %'):>8} "
                     f"{_cell(s['period'], '.3f'):>8} {duty:>9} {_cell(g['airborne'], '.1f', 100, ' %'):>8} "
                     f"{_cell(g['slip_share'], '.1f', 100, ' %'):>6} {_cell(g['step_length'], '.3f'):>6} "
                     f"{_cell(g['steps_per_s'], '.2f'):>7}  {verdict}" + (", FELL" if s["fell"] else ""))
    if fit["slope"] is None:
        lines.append("no line: fewer than two levels walked through without a fall")
    else:
        lines.append(f"speed = {fit['intercept']:.3f} {'+' if fit['slope'] >= 0 else '-'} {abs(fit['slope']):.3f} * "
                     f"{name} m/s (least squares over the {len(fit['levels'])} levels without a fall); "
                     + (f"monotone ({fit['monotone']})" if fit["monotone"] else "not monotone in the command")
                     + (f"; fastest / slowest {fit['ratio']:.2f}" if fit["ratio"] is not None else ""))
    lines.append("no fall" if not report["fell"] else f"fell at {report['end_time']:.1f} s")
    return lines
