"""Choosing a walker among candidates by simulating them longer than their evaluation did.

A fitness measured over one episode (or a few) is a noisy ranking of walkers
that must keep walking: an imitation or a tuned genome can drift off its line
or fall late.  :func:`try_candidates` runs every candidate alone, nominally, for the
episode (``seconds``) and, when it is still up then, for ``long_seconds``;
:func:`best_candidate` ranks them by, in order:

0. (when they were tried for it) a walk by the gait lab's walking criteria;
1. up through the long run;
2. up through the episode;
3. walking within ``heading_limit`` degrees of its initial facing in the episode;
4. its displacement along that facing in the episode (m);
5. how long it stayed up (s).

The first candidate wins a tie (give the one to keep when nothing beats it first).

:func:`forward_walker` tells a walker: no fall in ``seconds`` (200 s) and, over its first ``window`` (50 s), a walk
(the gait lab's walking criteria: at least 0.3 m/s within 30 degrees of its initial facing, each foot standing at
least half the time, no flight, symmetric feet that do not slide); ``forward`` is the older, gait-blind test (at
least ``min_distance``, 20 m, in the window within ``heading_limit``, 30 degrees) that earlier forward walkers passed.
"""

from __future__ import annotations

import numpy as np

from ..episode import EpisodeConfig


def try_candidates(config: EpisodeConfig | list[EpisodeConfig], genomes: np.ndarray, long_seconds: float, *,
                   walking: bool = False) -> list[dict]:
    """Each genome ``(P, G)`` alone in ``config``'s nominal episode (or each in its own: a list of one config per
    genome, e.g. generation files that each froze their normaliser) and, if up, for ``long_seconds``: one dict per
    genome with ``fell``, ``end_time`` (s), ``distance`` (m), ``heading_deg`` (None: did not move), ``up_long``; with
    ``walking``, also ``walks`` and ``failed``: the walking criteria over its first 50 s (:func:`forward_walker`'s
    window), for a candidate up through the episode."""
    if isinstance(config, list):
        return [try_candidates(c, np.asarray(g)[None], long_seconds, walking=walking)[0] for c,
                g in zip(config, genomes)]
    episode = config.nominal().build()
    short = episode.run(genomes)
    rows = []
    for i in range(len(genomes)):
        walk = short.walk(i)
        rows.append(dict(fell=bool(short.fell[i]), end_time=float(short.end_time[i]), distance=float(walk["distance"]),
                         heading_deg=walk["heading_deg"]))
    up = [i for i, r in enumerate(rows) if not r["fell"]]
    if up and long_seconds > 0:
        long = episode.run(genomes[up], seconds=long_seconds)
        for j, i in enumerate(up):
            rows[i]["up_long"] = not bool(long.fell[j])
    if walking:
        from .gait_report import gait_report

        for i, r in enumerate(rows):
            report = gait_report(config, genomes[i],
                                 seconds=50.0) if not r["fell"] else {"walks": False, "failed": ["up"]}
            r["walks"], r["failed"] = bool(report["walks"] and r.get("up_long", True)), report["failed"]
    return rows


def rank_key(row: dict, heading_limit: float) -> tuple:
    """What :func:`best_candidate` maximises for one candidate's row (see the module docstring; a row that was tried
    for the walking criteria ranks a walk first)."""
    h = row.get("heading_deg")
    h = 180.0 if h is None or not np.isfinite(h) else float(h)
    return (bool(row.get("walks", False)), bool(row.get("up_long", False)), not row["fell"], abs(h) <= heading_limit,
            row["distance"] * np.cos(np.radians(h)), row["end_time"])


def best_candidate(rows: list[dict], heading_limit: float = 30.0) -> int:
    """The index of the best candidate's row (rows as :func:`try_candidates` gives them)."""
    return max(range(len(rows)), key=lambda i: (rank_key(rows[i], heading_limit), -i))


def forward_walker(config: EpisodeConfig, genome: np.ndarray, *, seconds: float = 200.0, window: float = 50.0,
                   min_distance: float = 20.0, heading_limit: float = 30.0) -> dict:
    """One genome alone in ``config``'s nominal episode for ``seconds`` s, its gait measured over its first ``window``
    s (:func:`evobiped.analysis.gait_report.gait_report`): ``up`` (no fall), ``end_time`` (s), ``distance`` (m) and
    ``heading_deg`` of its displacement at ``window`` s (or its fall, if sooner); ``forward``: up, at least
    ``min_distance`` m, within ``heading_limit`` degrees of its initial facing (the test every "forward walker" of
    earlier docs passed, whatever its gait); ``walker``: a walk: up ``seconds`` s and every walking criterion
    (:data:`~evobiped.analysis.gait_report.WALKING`: speed, direction, duty factors, flight, symmetry, slip) over the
    ``window``; ``failed``: the criteria it missed; ``gait``: the gait's measures."""
    from .gait_report import MEASURES, gait_report

    report = gait_report(config, genome, seconds=min(window, seconds), up_for=seconds)
    heading = report["heading_deg"]
    distance = float(np.hypot(*report["displacement"]))
    ok = heading is not None and abs(heading) <= heading_limit
    forward = bool(report["up"] and distance >= min_distance and ok)
    failed = report["failed"]
    gait = {k: report[k] for k in ("speed", *(f"duty_{f}" for f in report["feet"]), *MEASURES)}
    return {"up": report["up"], "end_time": report.get("end_time", report["time_up"]), "distance": distance,
            "heading_deg": None if heading is None else round(heading, 2), "forward": forward,
            "walker": not failed, "failed": failed, "gait": gait}
