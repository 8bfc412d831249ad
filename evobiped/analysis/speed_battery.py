"""A commanded walker's speed battery: random schedules of commanded speeds, every stretch's speed against its command,
and its gait at each speed.

:func:`random_schedules` draws ``n`` schedules of ``stretches`` speeds, each uniform in [low, high] m/s (steps of any
size inside the range), from one seed.  :func:`speed_battery` follows each with :func:`~evobiped.analysis.commanded.
follow_commands` (straight ahead, ``stretch`` s per command) and scores every stretch by its mean speed from
``settle`` s after it begins (its error in % of the command, within ``tolerance`` or not) and, inside it, by
``window`` s windows (the error of each window's mean speed), so a walker whose speed swings about the command shows
it.  A schedule passes when the walker does not fall and every stretch is within the tolerance.
:func:`gait_at_speeds` measures the gait lab's criteria under constant commands (what a walk at each speed is).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..core.errors import UserError
from ..core.options import given
from ..episode import EpisodeConfig
from .commanded import SETTLE, follow_commands
from .gait_report import gait_report

#: the battery's defaults: schedules, stretches per schedule, s per stretch, the tolerance (a fraction), s per window
SCHEDULES, STRETCHES, STRETCH, TOLERANCE, WINDOW = 30, 6, 10.0, 0.10, 1.0


def random_schedules(n: int, stretches: int, low: float, high: float, seed: int) -> np.ndarray:
    """``(n, stretches)`` commanded speeds (m/s), uniform in [``low``, ``high``], from ``seed``."""
    if not (n >= 1 and stretches >= 1 and 0 < low <= high and np.isfinite(high)):
        raise UserError(f"a speed battery needs n >= 1 schedules of >= 1 stretches and 0 < low <= high m/s, got n {n}, "
                        f"stretches {stretches}, low {low:g}, high {high:g}")
    return np.random.default_rng(seed).uniform(low, high, (n, stretches))


def _tick_lengths(t: np.ndarray) -> np.ndarray:
    """Each tick's length (s) from the ticks' start times ``t`` ``(T,)`` (the last as long as the one before)."""
    return np.diff(np.append(t, 2 * t[-1] - t[-2])) if len(t) > 1 else np.ones_like(t)


def _window_means(trace: dict, start: float, end: float, window: float) -> tuple[np.ndarray, np.ndarray]:
    """The starts (s) of the ``window`` s windows in [start, end] s and the mean walked speed (m/s) over each; NaN for
    a window the trace does not cover whole (a fall ends it)."""
    t, v = np.asarray(trace["time"]), np.asarray(trace["walked_speed"])
    dt = _tick_lengths(t)
    starts = np.arange(start, end - window + 1e-9, window)
    means = np.full(len(starts), np.nan)
    for i, a in enumerate(starts):
        k = (t >= a - 1e-9) & (t < a + window - 1e-9)
        if dt[k].sum() >= window - 1e-6:
            means[i] = np.sum(v[k] * dt[k]) / dt[k].sum()
    return starts, means


def _windows(trace: dict, start: float, end: float, command: float, window: float) -> list[float]:
    """The errors (% of ``command``) of the mean walked speed over each whole ``window`` s in [start, end] s."""
    _, means = _window_means(trace, start, end, window)
    return [float(100 * abs(m - command) / command) for m in means if np.isfinite(m)]


def speed_battery(config: EpisodeConfig, genome: np.ndarray, *, n: int = SCHEDULES, stretches: int = STRETCHES,
                  stretch: float = STRETCH, low: float = 0.2, high: float = 0.8, seed: int = 0,
                  tolerance: float = TOLERANCE, window: float = WINDOW, settle: float = SETTLE, progress=None) -> dict:
    """The commanded walker ``genome`` ``(G,)`` of ``config`` through ``n`` random schedules (module docstring): a dict
    with ``schedules`` (per schedule its speeds, per stretch the walked speed, error % and whether it is within the
    tolerance, the window errors, fell, passed) and ``summary`` (schedules without a fall and passed, stretches within
    the tolerance, the stretch and window errors' median, 90th percentile and maximum).  ``progress(i, n)`` after
    each."""
    if not (stretch > settle + window and 0 < tolerance < 1 and window > 0):
        raise UserError(f"a stretch ({stretch:g} s) must be longer than the settling time ({settle:g} s) and a window "
                        f"({window:g} s), and the tolerance a fraction in (0, 1) (got {tolerance:g})")
    speeds = random_schedules(n, stretches, low, high, seed)
    times = [i * stretch for i in range(stretches)]
    rows = []
    for i, schedule in enumerate(speeds):
        r = follow_commands(config, genome, times, list(map(float, schedule)), [0.0] * stretches, stretch * stretches,
                            settle=settle)
        out = []
        for s in r["stretches"]:
            measured = s["walked_speed"] is not None and not s["down"]
            err = s["speed_error_pct"] if measured else None
            out.append({"commanded": s["commanded_speed"], "walked": s["walked_speed"] if measured else None,
                        "error_pct": err, "within": err is not None and err <= 100 * tolerance and not s["fell"],
                        "windows_pct": _windows(r["trace"], s["measured_from"], s["end"], s["commanded_speed"], window)
                        if measured else [], "fell": s["fell"]})
        rows.append({"speeds": [float(v) for v in schedule], "stretches": out, "fell": r["fell"],
                     "end_time": r["end_time"], "passed": not r["fell"] and all(s["within"] for s in out)})
        if progress is not None:
            progress(i + 1, n)
    return {"n": n, "stretches": stretches, "stretch": stretch, "low": low, "high": high, "seed": seed,
            "tolerance": tolerance, "window": window, "settle": settle, "schedules": rows,
            "summary": battery_summary(rows)}


def _spread(values: list[float]) -> dict:
    if not values:
        return {"median": None, "p90": None, "max": None}
    v = np.asarray(values, float)
    return {"median": float(np.median(v)), "p90": float(np.percentile(v, 90)), "max": float(v.max())}


def battery_summary(rows: list[dict]) -> dict:
    """The battery's counts and error spreads over the schedules ``rows`` of :func:`speed_battery`."""
    stretches = [s for r in rows for s in r["stretches"]]
    return {"schedules": len(rows), "no_fall": sum(not r["fell"] for r in rows),
            "passed": sum(r["passed"] for r in rows),
            "stretches": len(stretches), "within": sum(s["within"] for s in stretches),
            "stretch_error_pct": _spread([s["error_pct"] for s in stretches if s["error_pct"] is not None]),
            "window_error_pct": _spread([w for s in stretches for w in s["windows_pct"]])}


def gait_at_speeds(config: EpisodeConfig, genome: np.ndarray, speeds: list[float], *,
                   seconds: float = 30.0) -> list[dict]:
    """The gait lab's report (:func:`~evobiped.analysis.gait_report.gait_report`, its first ``seconds`` s, less the
    stance episodes) of the commanded walker under each constant speed command (m/s, straight ahead), with
    ``commanded``."""
    out = []
    for v in speeds:
        options = {**given(config.task_options), "schedule": "constant", "speed": float(v), "turning": 0.0}
        cfg = dataclasses.replace(config, task_options=options)
        report = gait_report(cfg, genome, seconds=seconds)
        out.append({"commanded": float(v), **{k: x for k, x in report.items() if k != "stance"}})
    return out


#: m/s: a walker whose every 1 s window's mean speed stays within this of 0 has stopped
STOPPED = 0.05


def stop_and_go(config: EpisodeConfig, genome: np.ndarray, speeds: list[float], *, walk: float = 10.0,
                stop: float = 20.0, window: float = WINDOW) -> list[dict]:
    """Per speed v (m/s): ``walk`` s at v, a stop (speed 0) for ``stop`` s, ``walk`` s at v again, straight ahead.  Each
    dict: ``time_to_stop`` (s from the stop command to the start of the first ``window`` s window from which every
    window's mean speed is within :data:`STOPPED` of 0; None: it never stopped), ``stop_speed`` (mean speed over the
    stop's last half, m/s), ``drift`` (m moved along its facing over the whole stop), ``double_support`` (share of the
    stop's last half with both feet down: 1 is standing, about a tenth is marking time), ``walk_off`` (the speed walked
    in the last stretch, measured as :func:`~evobiped.analysis.commanded.follow_commands` measures), ``fell``."""
    out = []
    for v in speeds:
        r = follow_commands(config, genome, [0.0, walk, walk + stop], [float(v), 0.0, float(v)], [0.0] * 3, 2 * walk
                            + stop)
        tr = r["trace"]
        t, w, both = np.asarray(tr["time"]), np.asarray(tr["walked_speed"]), np.asarray(tr["both_down"], bool)
        dt = _tick_lengths(t)
        starts, means = _window_means(tr, walk, walk + stop, window)
        still = np.abs(np.nan_to_num(means, nan=np.inf)) <= STOPPED
        first = next((i for i in range(len(still)) if still[i:].all()), None)
        late = (t >= walk + stop / 2 - 1e-9) & (t < walk + stop - 1e-9)
        during = (t >= walk - 1e-9) & (t < walk + stop - 1e-9)
        out.append({"speed": float(v), "time_to_stop": None if first is None else float(starts[first] - walk),
                    "stop_speed": float(np.sum(w[late] * dt[late]) / dt[late].sum()) if late.any() else None,
                    "drift": float(np.sum(w[during] * dt[during])),
                    "double_support": float(both[late].mean()) if late.any() else None,
                    "walk_off": r["stretches"][2]["walked_speed"], "fell": r["fell"], "end_time": r["end_time"]})
    return out


def calibrate_speed(config: EpisodeConfig, genome: np.ndarray, speeds: list[float], *, seconds: float = 20.0
                    ) -> tuple[EpisodeConfig, dict]:
    """``config`` with the commanded walker's ``command_speed`` normalisation rescaled so that the speed it walks
    follows the command one to one, and the fit: the walker follows each constant command v of ``speeds`` (m/s) for
    ``seconds`` s, its walked speed w (from 3 s on) is fitted as w = a + b v, and the sense then reads (a + b v -
    m) / (b s) where it read (v - m) / s (m, s its frozen centre and scale), so a command v reaches the network as
    (v - a) / b did: the genes stay, only the input's scale and centre move.  A ``command_stop`` row keeps the
    frame it gave at a stop.  UserError for a walker without a frozen ``command_speed`` normalisation, fewer than two
    speeds, a fall, or a walker whose speed does not rise with the command (b <= 0)."""
    from ..episode.remap import input_widths

    norm = getattr(config.controller_options, "input_norm", None)
    names = list(config.parts()[1].input_names)
    if norm is None or "command_speed" not in names:
        raise UserError("calibrating the speed command needs a commanded walker with a frozen input_norm")
    if len(set(speeds)) < 2:
        raise UserError(f"calibrating the speed command needs at least two speeds, got {speeds}")
    walked = []
    for v in speeds:
        r = follow_commands(config, genome, [0.0], [float(v)], [0.0], seconds)
        if r["fell"]:
            raise UserError(f"the walker fell at {r['end_time']:.1f} s under a constant {v:g} m/s command: not "
                            "calibrated")
        walked.append(r["stretches"][0]["walked_speed"])
    b, a = np.polyfit(np.asarray(speeds, float), np.asarray(walked, float), 1)
    if not b > 0:
        raise UserError(f"the walker's speed does not rise with the command (slope {b:.3f}): not calibrated")
    at = dict(zip(names, np.cumsum([0] + list(input_widths(config)))[:-1]))
    mean, std = list(map(float, norm["mean"])), list(map(float, norm["std"]))
    i = at["command_speed"]
    before = -mean[i] / std[i]  # what a zero command read
    mean[i], std[i] = a + b * mean[i], b * std[i]
    if "command_stop" in at:  # the stop's frame as it was: zero command plus the stop's row, as before
        j = at["command_stop"]
        stop_before = before + 1.0 / std[j]
        std[j] = 1.0 / (stop_before + mean[i] / std[i])
    options = {**given(config.controller_options), "input_norm": {**norm, "mean": mean, "std": std}}
    fit = {"speeds": [float(v) for v in speeds], "walked": walked, "intercept": float(a), "slope": float(b)}
    return dataclasses.replace(config, controller_options=options), fit
