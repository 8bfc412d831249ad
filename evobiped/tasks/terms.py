"""The walk task's fitness terms as data: each term's name, unit and meaning, which options make the task report it,
and how it is computed, per control tick and per episode.

:data:`WALK_TERMS` is the table (the walk task's and the command task's, which extends it): a :class:`TermGroup`
is terms computed together (the gait lab's measures, the two gait measures), in the order the task reports them
(``term_names``, ``terms()``: so history.csv's ``best_<term>`` columns).  The task's term names, its weights'
validation and their error line, and docs/usage.md's table of terms (``python -m evobiped.readme``) are derived
from it.  A new term is one :class:`TermGroup` and one line: ``WALK_TERMS.append(group)`` (or an entry of the table
below); what it keeps from tick to tick it keeps in the state's ``kept`` (``start`` gives its rows, ``(n, ...)``
arrays by name, begun anew per row with the rest of the state).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from ..core.errors import ConfigError
from ..physics import gait, gait_lab


@dataclass(frozen=True)
class Term:
    """One fitness term: its name, its unit ("" for a share or a count), what it measures, and what it needs beside
    its group's options (``also``; "": nothing)."""

    name: str
    unit: str
    about: str
    also: str = ""


@dataclass(frozen=True)
class TermGroup:
    """Terms a task reports together, each ``(n,)`` per simulation row at the end of an episode.

    ``needs`` says in words which options make the task report them, ``wanted(task)`` decides it; ``value(task,
    state, out)`` computes them at the end of an episode (``out``: the terms of the groups before, by name) ->
    name -> ``(n,)``; ``tick(task, body, sims, state, ok, neurons)`` keeps what they need after each control tick
    (``ok``: the rows stepped and finite); ``start(task, body, sims, state)`` gives what ``tick`` keeps, name ->
    an ``(n, ...)`` array or a per-row record with ``restart(ids)`` (in ``state.kept``); ``names(task)``: the names
    reported where they depend on the options (the gait lab's sampling), else every term's; ``weighable``: the
    weighted fitness may weigh them."""

    terms: tuple[Term, ...]
    needs: str
    wanted: Callable[[Any], bool]
    value: Callable[[Any, Any, dict], dict[str, np.ndarray]]
    tick: Callable[..., None] | None = None
    start: Callable[[Any, Any, Any, Any], dict[str, Any]] | None = None
    names: Callable[[Any], tuple[str, ...]] | None = None
    weighable: bool = True

    @property
    def all_names(self) -> tuple[str, ...]:
        return tuple(t.name for t in self.terms)

    def reported(self, task) -> tuple[str, ...]:
        """The names ``task`` reports of this group (none unless it wants them)."""
        if not self.wanted(task):
            return ()
        return self.all_names if self.names is None else self.names(task)


def _steps_start(task, body, sims, state) -> dict:
    """Each row's stance leg (:mod:`evobiped.physics.gait`: the episode keeps it from now on) and its steps ``(n,)``."""
    if body.contact_sensor is None:
        raise ConfigError(f"the walk task counts steps by foot contact; body {body.name!r} declares no contact sensor")
    return {"stance": gait.tracker(body.contacts(sims), sims)["stance"].copy(), "steps": np.zeros(sims.n)}


def _steps_tick(task, body, sims, state, ok, neurons) -> None:
    kept, stance = state.kept, sims.extra["gait"]["stance"][ok]
    kept["steps"][ok] += stance != kept["stance"][ok]
    kept["stance"][ok] = stance


def _gait_measures_start(task, body, sims, state) -> dict:
    """The path along the facing (m) and the facing's unwrapped turn (rad) so far ``(n,)``, the facing now
    ``(n, 2)``."""
    return {"travel": np.zeros(sims.n), "yaw": np.zeros(sims.n), "facing_now": state.facing.copy()}


def _gait_measures_tick(task, body, sims, state, ok, neurons) -> None:
    kept = state.kept
    f, f1 = kept["facing_now"][ok], body.heading(sims)[ok]  # the facing before and after this tick
    step = body.planar_position(sims)[ok] - state.position[ok]
    kept["travel"][ok] += np.einsum("pi,pi->p", step, f1)
    kept["yaw"][ok] += np.arctan2(f[:, 0] * f1[:, 1] - f[:, 1] * f1[:, 0], np.einsum("pi,pi->p", f, f1))
    kept["facing_now"][ok] = f1


def _cyclic_tick(task, body, sims, state, ok, neurons) -> None:
    state.motor.append(neurons[:, : state.n_motor].copy())
    state.ticks[ok] += 1


def _gait_measures(task, state, out) -> dict[str, np.ndarray]:
    up = np.maximum(np.asarray(state.end_time, float), 1e-9)
    return {"speed": state.kept["travel"] / up, "turning": np.degrees(state.kept["yaw"]) / up}


def _lab(task, state, out) -> dict[str, np.ndarray]:
    lab = state.kept["gait_lab"].measure(task.forward(state))
    return {k: lab[k] for k in task.lab_terms}


#: the gait lab's terms (each foot's duty factor, then :data:`evobiped.physics.gait_lab.MEASURES`)
LAB = tuple(Term(f"duty_{foot}", "", f"the {foot} foot's duty factor: the share of the time up it stands")
            for foot in ("left", "right")) + tuple(
    Term(k, *v, also="" if k in gait_lab.MEASURES_TICK else "gait_sampling = 'physics_step'")
    for k, v in gait_lab.MEASURES.items())

#: the walk task's terms, in the order it reports them
WALK_TERMS: list[TermGroup] = [
    TermGroup((Term("distance", "m", "eq. 4: the planar distance from the start"),), "always", lambda task: True,
              lambda task, state, out: {"distance": task.distance(state)}),
    TermGroup((Term("forward", "m", "the displacement along the initial facing (negative: backwards)"),), "always",
              lambda task: True, lambda task, state, out: {"forward": task.forward(state)}),
    TermGroup((Term("cyclicity", "", "the cyclic-activity criterion c in [0, 1] (NaN without it)"),), "always",
              lambda task: True, lambda task, state, out: {"cyclicity": task.cyclicity(state) if task.cyclic_weight
                                                          else np.full(len(state.start), np.nan)},
              tick=lambda task, *args: _cyclic_tick(task, *args) if task.cyclic_weight else None, weighable=False),
    TermGroup((Term("time_up", "s", "the time until the walker fell (the episode's length if it did not)"),
               Term("steps", "", "stance switches: touchdowns of the swing foot")), "fitness = 'weighted'",
              lambda task: task.counts_steps,
              lambda task, state, out: {"time_up": np.array(state.end_time, float),
                                        "steps": state.kept["steps"].copy()},
              tick=_steps_tick, start=_steps_start),
    TermGroup((Term("pace", "m", "the displacement forward, counted up to pace_cap times the time up"),),
              "fitness = 'weighted' and weights naming it", lambda task: task.counts_steps and "pace" in task.weights,
              lambda task, state, out: {"pace": np.minimum(out["forward"], task.options.pace_cap * out["time_up"])}),
    TermGroup((Term("speed", "m/s", "the mean forward speed along the facing over the time up"),
               Term("turning", "deg/s", "the mean turning rate over the time up (+ left)")), "gait_measures = true",
              lambda task: task.options.gait_measures, _gait_measures, tick=_gait_measures_tick,
              start=_gait_measures_start, weighable=False),
    TermGroup(LAB, "gait_terms = true, or weights naming one", lambda task: task.gait_lab, _lab,
              tick=lambda task, body, sims, state, ok, neurons: state.kept["gait_lab"].tick(
                  body.tick_feet(sims), ok, sims.time[ok]),
              start=lambda task, body, sims, state: {"gait_lab": task.gait_meter(body, sims, task.sampling)},
              names=lambda task: task.lab_terms),
]


def weighable(groups=None) -> tuple[str, ...]:
    """The names the weighted fitness may weigh, in the table's order (``groups``: :data:`WALK_TERMS`)."""
    return tuple(name for g in (WALK_TERMS if groups is None else groups) if g.weighable for name in g.all_names)


def terms_table() -> str:
    """docs/usage.md's table of the walk task's terms: name, unit, when the task reports it, what it measures."""
    rows = ["| term | unit | reported with | what it measures |", "|---|---|---|---|"]
    for g in WALK_TERMS:
        rows += [f"| `{t.name}` | {t.unit} | {g.needs}{f'; {t.also}' if t.also else ''} | {t.about} |" for t in g.terms]
    return "\n".join(rows) + "\n"
