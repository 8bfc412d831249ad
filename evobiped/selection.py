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
"""

from __future__ import annotations

import numpy as np

from .episode import EpisodeConfig


def try_candidates(config: EpisodeConfig, genomes: np.ndarray, long_seconds: float) -> list[dict]:
    """Each genome ``(P, G)`` alone in ``config``'s nominal episode and, if up, for ``long_seconds``: one dict per
    genome with ``fell``, ``end_time`` (s), ``distance`` (m), ``heading_deg`` (None: did not move), ``up_long``."""
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
