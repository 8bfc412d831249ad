"""What a run sets for each generation beyond its config: the running observation normaliser and the curriculum's phase.

Generation g's episodes are normalised by the statistics of the senses
visited in generations 0 .. g-1 (:mod:`evobiped.interface.normaliser`) by the
evaluation walkers of an optimizer that has them (ES's theta), else by every
walker evaluated (the GA, CMA-ES, MAP-Elites)
and scored with the current phase's weights (:mod:`.curriculum`); both are
frozen into the genome file of each generation's best (its controller's
``input_norm``, its task's ``weights``), so a walker replays, is tested and is
distilled exactly as it was scored.  The statistics, the phase and the
evaluation walkers' record per generation (history.csv's ``phase``,
``evaluation_up`` and ``evaluation_forward``) are part of the checkpoint.

A run started ``--from`` a genome file (or run directory) whose walker froze an
``input_norm`` starts its running statistics from that normaliser rather than
from nothing: the seed genome then meets, in generation 0, exactly the inputs
it was evolved with (fine-tuning a walker does not begin by breaking it).  The
statistics are rebuilt as ``count`` ticks of that mean and std (m2 = count
std^2); an input the seed's controller did not read (a sense added for the new
run) starts at its declared centre and scale with the same count.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..episode import Context, EpisodeConfig, sense_sums
from ..episode.result import EpisodeResult
from ..core.errors import UserError
from ..episode.remap import input_widths
from ..interface.normaliser import Normaliser, frozen_table
from ..core.options import given
from ..optimizers import OPTIMIZERS
from .curriculum import Curriculum
from .stopping import Attempts, streak


#: history.csv's columns of a run with a context (after the best's terms)
HISTORY_EXTRA = ("phase", "evaluation_up", "evaluation_forward")
#: and, in a run with a stopping rule (:mod:`.stopping`), whether this generation met it
STOP_COLUMN = "stop_met"


class RunContext:
    """The per-generation settings of a run with config ``config`` (a no-op for a run that has neither)."""

    def __init__(self, config, start: EpisodeConfig | None = None):
        """``start``: the episode config of the genome file the run starts from (``--from``), whose frozen normaliser
        the running statistics start from (None: the declared centres and scales)."""
        self.config = config
        self.curriculum = Curriculum(config.curriculum)
        self.running = bool(config.normalise.running)
        controller = config.episode.parts()[1]
        self.declared = controller.input_norm
        self.stats = Normaliser.empty(len(self.declared[0])) if self.running else None
        if self.running and start is not None:
            self.stats = _seed_stats(start, config.episode, self.declared, self.stats)
        self.start_stats = self.stats  # what a restart begins from again
        # : the lost-run rule's record (:mod:`.stopping`; None: the run has no such rule), and whether the optimizer is
        # to
        #: start over after this generation
        self.attempts = Attempts() if config.restart.active else None
        self.restart_due = False
        self.floor = self._floors(controller) if self.running else None
        #: per generation: the phase it was scored in and how its evaluation walkers did (history.csv's extra columns)
        self.history: list[dict] = []
        #: the context the run's best genome was scored in (best.json freezes it)
        self.best: Context | None = None

    @property
    def active(self) -> bool:
        return (self.running or self.curriculum.active or OPTIMIZERS[self.config.optimizer].reports_evaluation_rows
                or self.config.stop.active or self.attempts is not None)

    def stopped(self) -> bool:
        """The stopping rule (:mod:`.stopping`) held for its generations running, or the lost-run rule stopped the
        run."""
        return (self.config.stop.active and streak(self.history) >= self.config.stop.generations) or self.lost_stop()

    def lost_stop(self) -> bool:
        """The lost-run rule stopped the run."""
        return self.attempts is not None and self.attempts.stopped

    def _floors(self, controller) -> np.ndarray:
        o = self.config.normalise
        widths = [(n, w) for n, w in zip(controller.input_names, input_widths(self.config.episode))]
        absolute = np.concatenate([np.full(w, float(o.floors.get(n, 0.0))) for n,
                                   w in widths]) if widths else np.zeros(0)
        return np.maximum(o.floor * self.declared[1], absolute)

    def now(self) -> Context:
        """The context of the next generation's episodes."""
        norm = self.stats.centre_scale(self.declared, self.floor) if self.running else None
        return Context(norm=norm, observe=self.running, weights=self.curriculum.weights(),
                       norm_count=self.stats.count if self.running else 0.0, seconds=self.curriculum.seconds())

    def episode(self, context: Context | None) -> EpisodeConfig:
        """The run's episode config with ``context`` frozen in (what a genome file of that generation records)."""
        cfg = self.config.episode
        if context is None or (context.norm is None and context.weights is None and context.seconds is None):
            return cfg
        changes = {} if context.seconds is None else {"seconds": context.seconds}
        if context.norm is not None:
            changes["controller_options"] = {**given(cfg.controller_options),
                                             "input_norm": frozen_table(*context.norm, context.norm_count)}
        if context.weights is not None:
            changes["task_options"] = {**given(cfg.task_options), "weights": dict(context.weights)}
        return dataclasses.replace(cfg, **changes)

    def best_episode(self) -> EpisodeConfig:
        return self.episode(self.best)

    def after(self, result: EpisodeResult, unknown: np.ndarray, evaluation_rows: np.ndarray | None,
              fitness: np.ndarray, *, helped: bool = False) -> None:
        """Learn from a generation: ``result`` over the evaluated rows (``unknown`` of the population), the optimizer's
        evaluation rows (None: the fittest evaluated row) and the population's ``fitness``; ``helped``: the pelvis
        assistance held its walkers up, or less than the model's gravity pulled them down (the stopping rule is not
        met then: a walker helped does not walk)."""
        if not self.active:
            return
        position = np.cumsum(unknown) - 1
        evaluated = np.flatnonzero(unknown)
        chosen = evaluated[np.argmax(fitness[evaluated])][None] if evaluation_rows is None else np.ravel(
            evaluation_rows)
        chosen = chosen[unknown[chosen]]
        rows = position[chosen]
        phase = self.curriculum.phase
        if self.running and len(rows):
            self.stats = self.stats.add(sense_sums(result, rows if evaluation_rows is not None
                                                   else np.arange(len(evaluated))))
        up = float(np.mean(~_row_fell(result, rows))) if len(rows) else float("nan")
        forward = float(np.mean(np.asarray(result.terms["forward"])[rows])) if "forward" in result.terms and len(
            rows) else float("nan")
        if len(rows):
            self.curriculum.after(result, rows)
        self._lost(phase, len(rows) > 0 and up == 0.0)
        values = (phase, up, None if not np.isfinite(forward) else forward)
        self.history.append(dict(zip(HISTORY_EXTRA, values)))
        stop = self.config.stop
        if stop.active:
            last_phase = not self.curriculum.active or phase == len(self.curriculum.options.phases) - 1
            # each presentation of each evaluation walker (a term is (genomes,) or (genomes, presentations))
            terms = {k: np.asarray(v)[rows].reshape(-1) for k, v in result.terms.items()}
            self.history[-1][STOP_COLUMN] = int(last_phase and not helped
                                                and stop.met(terms, _row_fell(result, rows), fitness[chosen]))

    def _lost(self, phase: int, fell: bool) -> None:
        """The lost-run rule after this generation (scored in ``phase``; ``fell``: every evaluation walker fell): a
        restart sends the curriculum back to its first phase and the normaliser to its start, and tells the run to
        start its optimizer over."""
        if self.attempts is None:
            return
        action = self.attempts.check(self.config.restart, len(self.history), phase, self.curriculum.phase != phase,
                                     fell)
        self.restart_due = action == "restart"
        if self.restart_due:
            self.curriculum.phase = self.curriculum.streak = 0
            self.stats = self.start_stats

    def early_phase(self, generation: int) -> bool:
        """Generation ``generation`` was (or, the next one, is) scored in a phase before the curriculum's last."""
        if not self.curriculum.active:
            return False
        phase = self.history[generation]["phase"] if generation < len(self.history) else self.curriculum.phase
        return phase < len(self.curriculum.options.phases) - 1

    # ---- the checkpoint's part
    def to_dict(self) -> dict:
        if not self.active:
            return {}
        out = {"history_extra": [dict(t) for t in self.history], "curriculum": self.curriculum.to_dict()}
        if self.running:
            out["normaliser"] = self.stats.to_dict()
        out["best_context"] = None if self.best is None else _context_table(self.best)
        if self.attempts is not None:
            out["restarts"] = self.attempts.to_dict()
        return out

    def restore(self, ck: dict) -> None:
        """Read :meth:`to_dict`'s keys back from a checkpoint (UserError, one line, when malformed)."""
        if not self.active:
            return
        extra = ck.get("history_extra", [])
        if not isinstance(extra, list) or not all(isinstance(t, dict) for t in extra):
            raise UserError("checkpoint: history_extra must be a list of tables")
        self.history = [{**t, STOP_COLUMN: int(t[STOP_COLUMN])} if isinstance(t.get(STOP_COLUMN), bool) else t
                        for t in extra]
        if "curriculum" in ck:
            self.curriculum.restore(ck["curriculum"])
        if self.running and "normaliser" in ck:
            self.stats = Normaliser.from_dict(ck["normaliser"], len(self.declared[0]))
        table = ck.get("best_context")
        self.best = None if table is None else _context_from(table, len(self.declared[0]) if self.declared else 0)
        if self.attempts is not None:
            self.attempts = Attempts.from_dict(ck.get("restarts"))


def _seed_stats(cfg: EpisodeConfig, episode: EpisodeConfig, declared: tuple[np.ndarray, np.ndarray],
                empty: Normaliser) -> Normaliser:
    """The running statistics a run --from a genome file of episode config ``cfg`` starts from: its ``input_norm``
    mapped input by input (by name and width) onto this run's inputs, the declared centre and scale for the others;
    ``empty`` when the file froze none (or shares no input)."""
    norm = cfg.controller_options.input_norm
    if norm is None or cfg.controller != episode.controller:
        return empty
    count = float(norm.get("count", 0.0) or 0.0)
    if count < 2:
        return empty
    old_names = cfg.parts()[1].input_names
    old = {}
    at = 0
    for name, width in zip(old_names, input_widths(cfg)):
        old[name] = (width, slice(at, at + width))
        at += width
    if at != len(norm["mean"]):
        return empty
    mean, std = declared[0].copy(), declared[1].copy()
    at, shared = 0, 0
    for name, width in zip(episode.parts()[1].input_names, input_widths(episode)):
        if name in old and old[name][0] == width:
            mean[at:at + width] = np.asarray(norm["mean"], float)[old[name][1]]
            std[at:at + width] = np.asarray(norm["std"], float)[old[name][1]]
            shared += 1
        at += width
    if not shared:
        return empty
    return Normaliser(count, mean, count * std * std)


def _row_fell(result: EpisodeResult, genomes: np.ndarray) -> np.ndarray:
    """Whether each presentation of ``genomes`` fell, one entry per presentation."""
    if result.rows is None:
        return result.fell[genomes]
    per = len(result.rows.fell) // len(result.fell)
    return result.rows.fell.reshape(-1, per)[genomes].ravel()


def _context_table(context: Context) -> dict:
    return {"input_norm": None if context.norm is None else frozen_table(*context.norm, context.norm_count),
            "weights": context.weights, "seconds": context.seconds}


def _context_from(table, k: int) -> Context:
    if not isinstance(table, dict):
        raise UserError("checkpoint: best_context must be a table")
    norm, weights = table.get("input_norm"), table.get("weights")
    if norm is not None:
        try:
            centre, scale = np.array(norm["mean"], float), np.array(norm["std"], float)
        except (TypeError, KeyError, ValueError):
            raise UserError("checkpoint: best_context.input_norm must hold mean and std") from None
        if centre.shape != (k,) or scale.shape != (k,) or not (scale > 0).all():
            raise UserError(f"checkpoint: best_context.input_norm must hold {k} means and stds > 0")
        norm = (centre, scale)
    if weights is not None and not isinstance(weights, dict):
        raise UserError("checkpoint: best_context.weights must be a table")
    count = table["input_norm"].get("count", 0) if norm is not None else 0
    if not isinstance(count, (int, float)) or isinstance(count, bool) or not count >= 0:
        raise UserError("checkpoint: best_context.input_norm.count must be a number >= 0")
    seconds = table.get("seconds")
    if seconds is not None and (not isinstance(seconds, (int, float)) or isinstance(seconds, bool) or not seconds > 0):
        raise UserError("checkpoint: best_context.seconds must be a length in s > 0, or null")
    return Context(norm=norm, weights=weights, norm_count=float(count), seconds=seconds)
