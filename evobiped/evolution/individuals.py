"""What a run knows of each individual of its population beside its genome and fitness: the outcome of its evaluation.

The optimizer says which rows it keeps (``next_generation()`` returns, for each new
row, the previous row it is, -1 for a new individual); the run carries their
outcomes along, so row ``i``'s fitness (the optimizer's) and outcome (here) always
belong to the same individual.  Per row: ``fell``, ``unstable`` (bool), ``end_time``
(s), the task's terms (``terms[name]``: ``(P,)``, or ``(P, S)`` over S presentations
and trials) and where it walked in its first presentation (``displacement`` ``(P, 2)``
m, ``heading_deg`` ``(P,)``, NaN: it did not move; see ``EpisodeResult.walk``).
Everything round-trips through the checkpoint exactly (JSON floats).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..episode_result import walk_summary
from ..errors import UserError

#: the outcome of an individual beside its fitness: name -> value before it is known
OUTCOME = {"fell": False, "unstable": False, "end_time": np.nan}


@dataclass
class Individuals:
    """Outcomes of a population, one row per individual (empty until a result is told)."""

    outcome: dict[str, np.ndarray] = field(default_factory=dict)
    terms: dict[str, np.ndarray] = field(default_factory=dict)
    #: ``displacement`` ``(P, 2)`` m and ``heading_deg`` ``(P,)`` of each row's first presentation
    walk: dict[str, np.ndarray] = field(default_factory=dict)

    def told(self, unknown: np.ndarray, result) -> None:
        """The :class:`~evobiped.episode_result.EpisodeResult` of the rows ``unknown`` (a bool mask ``(P,)``), in order."""
        n = len(unknown)
        rows = np.flatnonzero(unknown)
        displacement, heading = result.displacements()
        for table, key, default, vals in (
            *((self.outcome, k, d, np.asarray(getattr(result, k))) for k, d in OUTCOME.items()),
            *((self.terms, k, np.nan, np.asarray(v, float)) for k, v in result.terms.items()),
            (self.walk, "displacement", np.nan, displacement),
            (self.walk, "heading_deg", np.nan, heading),
        ):
            known = table.get(key)
            arr = np.full((n, *vals.shape[1:]), default, dtype=vals.dtype) if known is None else known.copy()
            arr[rows] = vals
            table[key] = arr

    def carry(self, rows: np.ndarray) -> None:
        """The new population: row ``i`` keeps the previous row ``rows[i]``'s outcome (-1: none yet, zeros)."""
        rows = np.asarray(rows)
        for table in (self.outcome, self.terms, self.walk):
            for key, arr in table.items():
                new = np.zeros((len(rows), *arr.shape[1:]), dtype=arr.dtype)
                new[rows >= 0] = arr[rows[rows >= 0]]
                table[key] = new

    def terms_of(self, i: int) -> dict[str, float | list[float] | None]:
        """Row ``i``'s terms: a number each, or a list over its presentations (None: undefined, e.g. the
        cyclicity of a task that does not measure it)."""
        num = lambda x: float(x) if np.isfinite(x) else None  # noqa: E731
        return {k: num(v[i]) if v.ndim == 1 else [num(x) for x in v[i]] for k, v in self.terms.items()}

    def walk_of(self, i: int) -> dict | None:
        """Where row ``i`` walked, as ``EpisodeResult.walk`` gives it (None: not known, e.g. an older checkpoint)."""
        if "displacement" not in self.walk:
            return None
        return walk_summary(self.walk["displacement"][i], self.walk["heading_deg"][i])

    # ---- the checkpoint
    def to_dict(self) -> dict:
        """Plain lists for the checkpoint's ``outcome`` table (NaN as None)."""
        plain = lambda a: np.where(np.isnan(a), None, a).tolist() if a.dtype.kind == "f" else a.tolist()  # noqa: E731
        d = {k: v.tolist() for k, v in self.outcome.items()}
        if self.terms:
            d["terms"] = {k: plain(v) for k, v in self.terms.items()}
        if self.walk:
            d["walk"] = {k: plain(v) for k, v in self.walk.items()}
        return d

    @classmethod
    def from_dict(cls, d: dict, P: int) -> "Individuals":
        """Restore :meth:`to_dict` (types checked by :func:`evobiped.rundir.validate_checkpoint`); UserError unless
        each list has one entry per individual.  A checkpoint written before terms were kept has none."""
        lists = {k: v for k, v in d.items() if k in OUTCOME}
        nested = [v for k in ("terms", "walk") for v in d.get(k, {}).values()]
        if any(len(v) != P for v in [*lists.values(), *nested]):
            raise UserError(f"checkpoint: outcome lists must have one entry per individual ({P})")
        floats = lambda v: np.array(v, dtype=float)  # noqa: E731  (None -> nan)
        return cls(outcome={k: np.array(v, dtype=float if k == "end_time" else bool) for k, v in lists.items()},
                   terms={k: floats(v) for k, v in d.get("terms", {}).items()},
                   walk={k: floats(v) for k, v in d.get("walk", {}).items()})
