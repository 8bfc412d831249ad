"""What a walker did in an episode, and whether a replay elsewhere did the same within declared tolerances.

Bit-identity is promised only within one numerical environment (:mod:`evobiped.core.provenance`).  Across
environments a long walk amplifies last-bit differences, so a replay there checks the *outcome* instead: whether
each presentation fell, how far and in which direction the walker went, and how close it ended to its target
(a steering walker's sound source).  :data:`TOLERANCE` declares how close is close enough.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from ..episode.result import EpisodeResult
from ..tasks.walk import displacement_heading


@dataclass(frozen=True)
class Tolerance:
    """How far a replay in another numerical environment may drift and still count as the same outcome."""

    #: distance walked: the larger of an absolute (m) and a relative allowance
    distance_m: float = 0.5
    distance_rel: float = 0.05
    #: walking direction relative to the initial facing (deg)
    heading_deg: float = 5.0
    #: final distance to the target may grow by at most this much (m)
    target_m: float = 0.5


TOLERANCE = Tolerance()


def outcome(result: EpisodeResult, targets: np.ndarray | None = None) -> dict:
    """The outcome of walker 0 of ``result``: ``fell`` (any presentation), ``end_time`` (the earliest, s) and
    ``rows``, one entry per presentation with ``fell``, ``end_time`` (s), ``distance`` (m), ``heading_deg`` (None:
    it did not move), ``end_position`` ``[x, y]`` (m) and, when the task has ``targets`` ``(S, 2)`` m, ``target``
    and ``to_target`` (final distance to it, m); ``tolerance``: the :data:`TOLERANCE` it is checked with."""
    rows = result.rows if result.rows is not None else result
    S = len(rows.fitness) // len(result.fitness)
    out = []
    for j in range(S):
        a, b, f = rows.start_position[j : j + 1], rows.end_position[j : j + 1], rows.start_facing[j : j + 1]
        heading = float(displacement_heading(a, b, f)[0])
        row = {
            "fell": bool(rows.fell[j]),
            "end_time": round(float(rows.end_time[j]), 6),
            "distance": round(float(np.linalg.norm(b - a)), 4),
            "heading_deg": round(heading, 2) if np.isfinite(heading) else None,
            "end_position": [round(float(v), 4) for v in b[0]],
        }
        if targets is not None:
            target = np.asarray(targets, float)[j]
            row["target"] = [float(v) for v in target]
            row["to_target"] = round(float(np.linalg.norm(b[0] - target)), 4)
        out.append(row)
    return {"fell": any(r["fell"] for r in out), "end_time": min(r["end_time"] for r in out), "rows": out,
            "tolerance": asdict(TOLERANCE)}


def compare(stored: dict, replayed: dict, tolerance: Tolerance = TOLERANCE) -> tuple[list[str], list[str]]:
    """Compare a stored outcome with a replayed :func:`outcome`.  ``stored`` may hold any part of one: ``fell`` and
    ``end_time`` of the genome, and ``rows`` with any of ``fell``, ``end_time``, ``distance``, ``heading_deg``,
    ``to_target`` (for the first ``len(rows)`` presentations).  Returns ``(drift, failures)``: a phrase per compared
    quantity saying how far the replay drifted, and one per quantity outside ``tolerance`` (empty: the outcome
    holds)."""
    drift: list[str] = []
    failures: list[str] = []
    _survival(stored, replayed, "", drift, failures)
    old_rows, new_rows = stored.get("rows"), replayed["rows"]
    if old_rows is None:
        return drift, failures
    if len(old_rows) > len(new_rows):
        return drift, failures + [f"{len(new_rows)} presentations replayed, {len(old_rows)} stored"]
    many = len(new_rows) > 1
    for j, (old, new) in enumerate(zip(old_rows, new_rows)):
        at = f"presentation {j + 1}: " if many else ""
        if many:
            _survival(old, new, at, drift, failures)
        if old.get("distance") is not None:
            d = new["distance"] - old["distance"]
            allowed = max(tolerance.distance_m, tolerance.distance_rel * old["distance"])
            drift.append(at + f"distance {new['distance']:.2f} m (stored {old['distance']:.2f} m, {d:+.4f} m)")
            if abs(d) > allowed:
                failures.append(at + f"distance {new['distance']:.2f} m, stored {old['distance']:.2f} m (allowed "
                                     f"+-{allowed:.2f} m)")
        if old.get("heading_deg") is not None and new["heading_deg"] is not None:
            d = (new["heading_deg"] - old["heading_deg"] + 180.0) % 360.0 - 180.0
            drift.append(at + f"heading {new['heading_deg']:+.1f} deg (stored {old['heading_deg']:+.1f} deg, {d:+.2f})")
            if abs(d) > tolerance.heading_deg:
                failures.append(at + f"heading {new['heading_deg']:+.1f} deg, stored {old['heading_deg']:+.1f} deg "
                                     f"(allowed +-{tolerance.heading_deg:g} deg)")
        if old.get("to_target") is not None and "to_target" in new:
            drift.append(at + f"ended {new['to_target']:.2f} m from its target (stored {old['to_target']:.2f} m)")
            if new["to_target"] > old["to_target"] + tolerance.target_m:
                failures.append(at + f"ended {new['to_target']:.2f} m from its target, stored {old['to_target']:.2f} m "
                                     f"(allowed +{tolerance.target_m:g} m)")
    return drift, failures


def _survival(old: dict, new: dict, at: str, drift: list[str], failures: list[str]) -> None:
    """Fell or not, and a survivor's end time (the episode's length), as stored."""
    if "fell" not in old:
        return
    if bool(old["fell"]) != new["fell"]:
        failures.append(at + (f"fell at {new['end_time']:.2f} s, stored: stayed up" if new["fell"]
                              else f"stayed up, stored: fell at {old.get('end_time', float('nan')):.2f} s"))
    elif not new["fell"] and old.get("end_time") is not None and old["end_time"] != new["end_time"]:
        failures.append(at + f"ended at {new['end_time']:g} s, stored {old['end_time']:g} s")
    else:
        drift.append(at + (f"fell at {new['end_time']:.2f} s (stored: fell at {old.get('end_time', float('nan')):.2f} "
                           "s)"
                           if new["fell"] else f"up {new['end_time']:g} s (as stored)"))
