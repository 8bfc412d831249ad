"""What a run knows of each individual of its population beside its genome and fitness: the outcome of its evaluation.

The optimizer says which rows it keeps (``next_generation()`` returns, for each new
row, the previous row it is, -1 for a new individual; a GA also says which row
each child was bred from, ``parent_rows()``); the run carries their outcomes
along, so row ``i``'s fitness (the optimizer's) and outcome (here) always belong
to the same individual.  A row not yet evaluated has no outcome (``known`` false;
null in the checkpoint and in individuals.jsonl, never zeros).  Per row: ``fell``, ``unstable`` (bool), ``end_time``
(s), the task's terms (``terms[name]``: ``(P,)``, or ``(P, S)`` over S presentations
and trials) and where it walked in its first presentation (``displacement`` ``(P, 2)``
m, ``heading_deg`` ``(P,)``, NaN: it did not move; see ``EpisodeResult.walk``).
Everything round-trips through the checkpoint exactly (JSON floats).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..episode.result import walk_summary
from ..core.errors import UserError

#: the outcome of an individual beside its fitness: name -> value before it is known
OUTCOME = {"fell": False, "unstable": False, "end_time": np.nan}


@dataclass
class Individuals:
    """Outcomes of a population, one row per individual (empty until a result is told)."""

    outcome: dict[str, np.ndarray] = field(default_factory=dict)
    terms: dict[str, np.ndarray] = field(default_factory=dict)
    #: ``displacement`` ``(P, 2)`` m and ``heading_deg`` ``(P,)`` of each row's first presentation
    walk: dict[str, np.ndarray] = field(default_factory=dict)
    #: ``(P,)`` bool: the row's outcome is known (evaluated, or kept from an evaluated row)
    known: np.ndarray = field(default_factory=lambda: np.zeros(0, bool))
    #: ``(P,)`` int: the previous generation's row each row held (-1: new), and the row it was bred from (-1: not known)
    previous: np.ndarray | None = None
    parents: np.ndarray | None = None

    def record_results(self, unknown: np.ndarray, result) -> None:
        """The :class:`~evobiped.episode.result.EpisodeResult` of the rows ``unknown`` (a bool mask ``(P,)``), in
        order."""
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
        self.known = (self.known if len(self.known) == n else np.zeros(n, bool)).copy()
        self.known[rows] = True

    def carry(self, rows: np.ndarray, parents: np.ndarray | None = None) -> None:
        """The new population: row ``i`` keeps the previous row ``rows[i]``'s outcome (-1: a new individual, its
        outcome not known yet: NaN, False, and ``known`` false); ``parents`` ``(P,)``: the row each was bred from
        (-1: none; None: the optimizer does not say)."""
        rows = np.asarray(rows)
        kept = rows >= 0
        for table in (self.outcome, self.terms, self.walk):
            for key, arr in table.items():
                new = np.full((len(rows), *arr.shape[1:]), np.nan if arr.dtype.kind == "f" else 0, dtype=arr.dtype)
                new[kept] = arr[rows[kept]]
                table[key] = new
        known = np.zeros(len(rows), bool)
        if len(self.known):
            known[kept] = self.known[rows[kept]]
        self.known, self.previous = known, rows.astype(int)
        self.parents = None if parents is None else np.asarray(parents, int)

    def records(self, generation: int, fitness: np.ndarray, evaluated: np.ndarray) -> list[dict]:
        """One table per row for individuals.jsonl (:mod:`evobiped.files.rundir.individuals_file`): ``fitness`` ``(P,)``
        the optimizer's, ``evaluated`` ``(P,)`` bool the rows evaluated in ``generation``; unknown: None."""
        row = lambda a, i: None if a is None or a[i] < 0 else int(a[i])  # noqa: E731
        out = []
        for i in range(len(fitness)):
            known = bool(self.known[i]) if len(self.known) else False
            parent = row(self.parents, i)
            out.append({"generation": generation, "row": i, "evaluated": bool(evaluated[i]),
                        "previous": row(self.previous, i), "parents": None if parent is None else [parent],
                        "fitness": None if np.isnan(fitness[i]) else float(fitness[i]),
                        **{k: (v[i].item() if known and not (v.dtype.kind == "f" and np.isnan(v[i])) else None)
                           for k, v in self.outcome.items()},
                        "terms": self.terms_of(i)})
        return out

    def terms_of(self, i: int) -> dict[str, float | list[float] | None]:
        """Row ``i``'s terms: a number each, or a list over its presentations (None: undefined, e.g. the
        cyclicity of a task that does not measure it)."""
        num = lambda x: float(x) if np.isfinite(x) else None  # noqa: E731
        return {k: num(v[i]) if v.ndim == 1 else [num(x) for x in v[i]] for k, v in self.terms.items()}

    def walk_of(self, i: int) -> dict | None:
        """Where row ``i`` walked, as ``EpisodeResult.walk`` gives it (None: not known, no result told yet)."""
        if "displacement" not in self.walk:
            return None
        return walk_summary(self.walk["displacement"][i], self.walk["heading_deg"][i])

    # ---- the checkpoint
    def to_dict(self) -> dict:
        """Plain lists for the checkpoint's ``outcome`` table (NaN as None)."""
        plain = lambda a: np.where(np.isnan(a), None, a).tolist() if a.dtype.kind == "f" else a.tolist()  # noqa: E731
        known = self.known if len(self.known) else np.ones(len(next(iter(self.outcome.values()), ())), bool)
        d = {k: [x if ok else None for x, ok in zip(v.tolist(), known)] for k, v in self.outcome.items()}
        for name in ("previous", "parents"):
            rows = getattr(self, name)
            if rows is not None:
                d[name] = [None if r < 0 else int(r) for r in rows]
        if self.terms:
            d["terms"] = {k: plain(v) for k, v in self.terms.items()}
        if self.walk:
            d["walk"] = {k: plain(v) for k, v in self.walk.items()}
        return d

    @classmethod
    def from_dict(cls, d: dict, P: int) -> "Individuals":
        """Restore :meth:`to_dict` (types checked by :meth:`evobiped.files.rundir.RunRecord.from_dict`); UserError
        unless each list has one entry per individual.  An outcome holds no terms until a result told some."""
        lists = {k: v for k, v in d.items() if k in OUTCOME}
        rows = {k: d[k] for k in ("previous", "parents") if k in d}
        nested = [v for k in ("terms", "walk") for v in d.get(k, {}).values()]
        if any(len(v) != P for v in [*lists.values(), *rows.values(), *nested]):
            raise UserError(f"checkpoint: outcome lists must have one entry per individual ({P})")
        for k, v in rows.items():
            if not all(r is None or (isinstance(r, int) and not isinstance(r, bool) and 0 <= r < P) for r in v):
                raise UserError(f"checkpoint: outcome.{k} must hold rows of the population (0 to {P - 1}) or null")
        floats = lambda v: np.array(v, dtype=float)  # noqa: E731  (None -> nan)
        known = np.array([v is not None for v in lists.get("fell", [True] * P)], bool)
        outcome = {k: np.array([OUTCOME[k] if x is None else x for x in v], dtype=float if k == "end_time" else bool)
                   for k, v in lists.items()}
        lineage = {k: np.array([-1 if r is None else r for r in v], int) for k, v in rows.items()}
        return cls(outcome=outcome, terms={k: floats(v) for k, v in d.get("terms", {}).items()},
                   walk={k: floats(v) for k, v in d.get("walk", {}).items()}, known=known, **lineage)
