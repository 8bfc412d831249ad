"""A policy tested again on fresh noise: K presentations it never met, a measure and a success criterion.

A run's fitness is measured on the presentations it was selected on (its own best draw); a comparison of
run configurations re-evaluates each run's policy on new draws instead.  The test presentations are
drawn from a perturbations table (``[episode.perturbations]``'s options; :data:`DEFAULT_NOISE` unless
given) with ``presentations = K`` and the key (run seed, :data:`FRESH_GENERATION`): a generation no run
reaches (``generations`` is at most 10^6), so no run evaluated a genome on them, schedules are at their
end (their final strengths) and the pelvis assistance is off.  Every configuration's run of one seed
meets the same K presentations (common random numbers), and so does every checkpoint of that run.

What is taken of each presentation:

* the **measure**: the task's fitness (``fitness``) or one of its terms (``--measure TERM``, e.g.
  ``distance``), of an episode of the configuration's own length; a run's measure is the median over
  its K presentations;
* the **success**: ``walker``, the walker test of :func:`evobiped.analysis.selection.forward_walker` under
  the presentation's noise: no fall in 200 s and, over the first 50 s, a walk by the gait lab's criteria
  (:data:`evobiped.analysis.gait_report.WALKING`: speed, direction, duty factors, no flight, symmetric feet
  that do not slide); ``forward``, its older, gait-blind test (no fall in 200 s, at least 20 m in the
  first 50 s within 30 degrees of the initial facing); the durations and thresholds are
  ``forward_walker``'s defaults, read from its signature; or ``TERM>=X`` (``>``, ``<=``, ``<`` too) on
  the measure episode's fitness or term.  A run succeeds when every one of its K presentations does.
"""

from __future__ import annotations

import dataclasses
import inspect
import math
import operator
import re
from dataclasses import dataclass

import numpy as np

from ..core.errors import ConfigError, UserError
from ..episode import EpisodeConfig
from ..physics.perturb import PerturbationOptions
from .selection import forward_walker

#: the generation of the test presentations' key: beyond any run's generations (at most 10^6)
FRESH_GENERATION = 10**7
#: the test noise when none is given: each presentation's actuated joints start off the nominal pose by
#: Gaussian noise of this standard deviation (rad); every body has actuated joints
DEFAULT_NOISE = {"pose_noise": 0.02}
#: the forward-walker test's thresholds: :func:`forward_walker`'s defaults
WALKER = {name: p.default for name, p in inspect.signature(forward_walker).parameters.items()
          if name in ("seconds", "window", "min_distance", "heading_limit")}
_OPS = {">=": operator.ge, ">": operator.gt, "<=": operator.le, "<": operator.lt}


@dataclass(frozen=True)
class Success:
    """A success criterion: ``walker`` or ``forward`` (``term`` None; ``test`` says which) or ``term op threshold``."""

    term: str | None = None
    op: str = ">="
    threshold: float = 0.0
    test: str = "walker"

    @property
    def text(self) -> str:
        return self.test if self.term is None else f"{self.term}{self.op}{self.threshold:g}"


def parse_success(text: str, terms: tuple[str, ...]) -> Success:
    """``walker``, ``forward`` or ``TERM>=X`` (TERM ``fitness`` or one of the task's ``terms``); UserError otherwise."""
    text = text.strip()
    if text in ("walker", "forward"):
        return Success(test=text)
    m = re.fullmatch(r"\s*([A-Za-z_][A-Za-z0-9_]*)\s*(>=|<=|>|<)\s*([-+0-9.eE]+|[-+]?inf)\s*", text)
    if not m:
        raise UserError(f"--success {text!r}: give walker, forward or TERM>=X (e.g. distance>=5; also >, <=, <)")
    try:
        x = float(m.group(3))
    except ValueError:
        raise UserError(f"--success {text!r}: {m.group(3)!r} is not a number") from None
    return Success(check_measure(m.group(1), terms, "--success"), m.group(2), x)


def check_measure(name: str, terms: tuple[str, ...], flag: str = "--measure") -> str:
    """``name`` if it is ``fitness`` or one of the task's ``terms``; UserError otherwise."""
    if name != "fitness" and name not in terms:
        raise UserError(f"{flag}: {name!r} is not fitness nor a term of the task (its terms: "
                        f"{', '.join(terms) or 'none'})")
    return name


def fresh_noise(table: dict | None, trials: int) -> PerturbationOptions:
    """The perturbations of the K = ``trials`` test presentations from ``table`` (None: :data:`DEFAULT_NOISE`);
    one ConfigError line for a bad table."""
    table = dict(DEFAULT_NOISE if table is None else table)
    if "presentations" in table:
        raise ConfigError("the test noise's presentations are --trials K, not a setting of its table")
    return PerturbationOptions.from_dict({**table, "presentations": int(trials)})


def retest(config: EpisodeConfig, genome, *, seed: int, noise: PerturbationOptions, measure: str,
           success: Success) -> dict:
    """``genome`` ``(G,)`` of the episode ``config`` (its generation file's: the normaliser frozen as it was) on the
    test presentations of run seed ``seed``: ``measure`` and ``passed`` (lists, one per presentation), the run's
    ``value`` (their median) and ``success`` (every presentation passed)."""
    test = dataclasses.replace(config, perturbations=noise)
    episode = test.build()
    genome = np.asarray(genome, float)[None]
    trials = episode.trials_for((int(seed), FRESH_GENERATION))
    S, R = episode.task.presentations, 1 if trials is None else trials.R
    result = episode.run(genome, trials=trials)
    rows = result.rows if result.rows is not None else result
    by_trial = lambda a: np.asarray(a, float).reshape(R, S)  # noqa: E731  (row i: trial i // S, presentation i % S)
    values = {"fitness": episode.task.combine(by_trial(rows.fitness))}
    values.update({k: by_trial(v).mean(axis=1) for k, v in rows.terms.items()})
    if success.term is None:
        passed = _walkers(episode, genome, trials, R, S, gait=success.test == "walker")
    else:
        passed = _OPS[success.op](values[success.term], success.threshold)
    measured = [float(x) for x in values[measure]]
    return {"measure": measured, "passed": [bool(p) for p in passed],
            "value": float(np.median(measured)) if all(math.isfinite(x) for x in measured) else math.nan,
            "success": bool(np.all(passed))}


def check_walker_test(config: EpisodeConfig, success: Success) -> None:
    """UserError when the ``walker`` test cannot measure ``config``'s body (it declares no feet for the gait lab)."""
    from .gait_report import has_feet

    if success.term is None and success.test == "walker" and not has_feet(config.parts()[0]):
        raise UserError(f"--success walker: body {config.body!r} declares no feet, so its gait cannot be measured; "
                        "give --success forward or TERM>=X")


class _Rows:
    """An episode listener filling one gait recorder per simulation row (the feet read once a physics step for all
    rows)."""

    def __init__(self, recorders):
        self.recorders = recorders

    def start(self, episode, sims) -> None:
        for r in self.recorders:
            r.start(episode, sims)

    reads_feet_steps = True

    def tick(self, t, sims, ids, neurons, action, task_state) -> None:
        feet, running = self.recorders[0].body.tick_feet(sims), set(np.asarray(ids).tolist())
        for r in self.recorders:
            if r.row in running:
                r.take(feet, t)

    def end(self, result) -> None:
        pass


def _walkers(episode, genome, trials, R: int, S: int, *, gait: bool) -> np.ndarray:
    """Per test presentation: each of its rows passed the walker test (``gait``: the gait lab's walk and no fall;
    otherwise the forward test; :data:`WALKER`'s durations and thresholds) under its noise."""
    from ..tasks.walk import displacement_heading
    from .gait_report import FootRecorder, measured

    seconds, window = float(WALKER["seconds"]), float(WALKER["window"])
    state = episode.start(genome, seconds=seconds, trials=trials)
    recorders = [FootRecorder(row) for row in range(R * S)] if gait else []
    listener = _Rows(recorders) if gait else None
    if listener is not None:
        listener.start(episode, state.sims)
    episode.advance(state, min(window, seconds), listener=listener)
    end = episode.body.planar_position(state.sims).copy()
    start, facing = state.start_position.copy(), state.start_facing.copy()
    up_then, time_up = ~np.asarray(state.fell, bool), np.minimum(np.asarray(state.end_time, float), window)
    if gait:
        ok = np.array([measured(r, episode, start=start[i:i + 1], end=end[i:i + 1], facing=facing[i:i + 1],
                                time_up=float(time_up[i]), seconds=min(window, seconds), up=bool(up_then[i]))["walks"]
                       for i, r in enumerate(recorders)])
    else:
        distance = np.linalg.norm(end - start, axis=1)
        heading = displacement_heading(start, end, facing)
        straight = np.isfinite(heading) & (np.abs(np.nan_to_num(heading, nan=180.0)) <= WALKER["heading_limit"])
        ok = (distance >= WALKER["min_distance"]) & straight
    if seconds > window:
        episode.advance(state, seconds - window)
    return (ok & ~np.asarray(state.fell, bool)).reshape(R, S).all(axis=1)
