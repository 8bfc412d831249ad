"""Choosing a walker among candidates by simulating them longer than their evaluation did.

A fitness measured over one episode (or a few) is a noisy ranking of walkers
that must keep walking: an imitation or a tuned genome can drift off its line
or fall late.  :func:`try_candidates` runs every candidate alone, nominally, for the
episode (``seconds``) and, when it is still up then, for ``long_seconds``;
:func:`best_candidate` ranks them by, in order:

1. up through the long run;
2. up through the episode;
3. walking within ``heading_limit`` degrees of its initial facing in the episode;
4. its displacement along that facing in the episode (m);
5. how long it stayed up (s).

The first candidate wins a tie (give the one to keep when nothing beats it first).

:func:`forward_walker` is the test every "forward walker" in the docs passed: no
fall in ``seconds`` (200 s), at least ``min_distance`` (20 m) walked in its
first ``window`` (50 s), within ``heading_limit`` (30 degrees) of its initial facing.
"""

from __future__ import annotations

import numpy as np

from ..episode import EpisodeConfig


def try_candidates(config: EpisodeConfig | list[EpisodeConfig], genomes: np.ndarray, long_seconds: float) -> list[dict]:
    """Each genome ``(P, G)`` alone in ``config``'s nominal episode (or each in its own: a list of one config per
    genome, e.g. generation files that each froze their normaliser) and, if up, for ``long_seconds``: one dict per
    genome with ``fell``, ``end_time`` (s), ``distance`` (m), ``heading_deg`` (None: did not move), ``up_long``."""
    if isinstance(config, list):
        return [try_candidates(c, np.asarray(g)[None], long_seconds)[0] for c, g in zip(config, genomes)]
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
    return rows


def rank_key(row: dict, heading_limit: float) -> tuple:
    """What :func:`best_candidate` maximises for one candidate's row (see the module docstring)."""
    h = row.get("heading_deg")
    h = 180.0 if h is None or not np.isfinite(h) else float(h)
    return (bool(row.get("up_long", False)), not row["fell"], abs(h) <= heading_limit, row["distance"] * np.cos(np.radians(h)),
            row["end_time"])


def best_candidate(rows: list[dict], heading_limit: float = 30.0) -> int:
    """The index of the best candidate's row (rows as :func:`try_candidates` gives them)."""
    return max(range(len(rows)), key=lambda i: (rank_key(rows[i], heading_limit), -i))


def forward_walker(config: EpisodeConfig, genome: np.ndarray, *, seconds: float = 200.0, window: float = 50.0,
                   min_distance: float = 20.0, heading_limit: float = 30.0) -> dict:
    """One genome alone in ``config``'s nominal episode for ``seconds`` s: ``up`` (no fall), ``end_time`` (s),
    ``distance`` (m) and ``heading_deg`` of its displacement at ``window`` s (or its fall, if sooner), and ``walker``:
    up, at least ``min_distance`` m, within ``heading_limit`` degrees of its initial facing."""
    from ..tasks.walk import displacement_heading

    episode = config.nominal().build()
    state = episode.start(np.asarray(genome, float)[None], seconds=seconds)
    episode.advance(state, min(window, seconds))
    start, facing = state.start_position.copy(), state.start_facing.copy()
    end = episode.body.planar_position(state.sims)[:1].copy()
    distance = float(np.linalg.norm(end - start))
    heading = float(displacement_heading(start, end, facing)[0])
    if seconds > window:
        episode.advance(state, seconds - window)
    up = not bool(state.fell[0])
    ok = np.isfinite(heading) and abs(heading) <= heading_limit
    return {"up": up, "end_time": float(state.end_time[0]), "distance": distance,
            "heading_deg": round(heading, 2) if np.isfinite(heading) else None,
            "walker": bool(up and distance >= min_distance and ok)}
