"""The select use case: a run's walker chosen by simulating its fittest generation bests (and its start genome)
for longer than their evaluation did (:mod:`evobiped.analysis.selection`); written as ``RUN/selected.json``."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..files import rundir
from ..core.errors import UserError
from ..run.run_config import RunConfig, initial_genome
from ..core.fileio import read_json, write_json
from ..files.genome_file import load_genome, save_genome
from ..files.outcome import outcome
from ..files.rundir.output_set import output_set
from ..analysis.selection import best_candidate, try_candidates

#: what select writes into the run directory: the chosen walker, and every candidate's row
SELECTED, CANDIDATES = "selected.json", "selected_candidates.json"


@dataclass
class Selection:
    """What :func:`select_walker` found: one label and row (:func:`~evobiped.analysis.selection.try_candidates`) per
    candidate, the chosen one's index, and the file it was written to."""

    labels: list[str]
    rows: list[dict]
    chosen: int
    path: Path


def select_walker(run_dir: str | Path, *, top: int = 8, seconds: float = 200.0, heading_limit: float = 30.0,
                  walking: bool = False, note=None, allow_unfinished: bool = False) -> Selection:
    """Simulate the bests of the ``top`` fittest generations of ``run_dir`` (and first its start genome, kept unless
    one beats it) for ``seconds``; write the best as selected.json and every candidate's row beside it.  ``walking``:
    a candidate that walks by the gait lab's criteria ranks first (:func:`~evobiped.analysis.selection.try_candidates`).
    The two files are one set (``note(line)`` hears that the previous select was cut short between them).  A run
    another process is writing is one line unless ``allow_unfinished``; selected.json records the checkpoint it was
    chosen from (:data:`~evobiped.files.rundir.FROM_CHECKPOINT`), so a later read of a run that went on is refused."""
    d = Path(run_dir)
    if not (d / rundir.CONFIG).is_file() or not (d / rundir.HISTORY).is_file():
        raise UserError(f"{d} is not a run directory with completed generations (no {rundir.CONFIG} or "
                        f"{rundir.HISTORY})")
    live = rundir.check_at_rest(d, allow_unfinished)
    if live is not None and note is not None:
        note(f"{d} is being written by process {live['writer']}: chosen from its first {live['generations']} "
             "generations")
    mark = live or rundir.checkpoint_mark(d)
    rundir.check_generation_files(d)  # every committed generation file is the run's (rewritten, or one line naming it)
    best = rundir.read_history(d / rundir.HISTORY)["best"]
    chosen_generations = [int(g) for g in np.argsort(-best, kind="stable")[:top]]
    paths = [rundir.generation_file(d, g) for g in chosen_generations]
    missing = [p for p in paths if not p.is_file()]
    if missing:
        raise UserError(f"{missing[0]} is missing: the run directory is incomplete (resume it first)")
    cfg = read_json(d / rundir.CONFIG, what="run config")
    if not isinstance(cfg, dict):
        raise UserError(f"run config {d / rundir.CONFIG} is not a table of settings")
    run = RunConfig.from_dict({k: v for k, v in cfg.items() if k not in ("evobiped", "environment")},
                              where=str(d / rundir.CONFIG))
    try:  # the long episode within what any episode may take (10^7 ticks), before any is simulated
        dataclasses.replace(run.episode, seconds=seconds).check()
    except UserError as exc:
        raise UserError(f"--seconds {seconds:g}: {exc}") from None
    candidates = [load_genome(p) for p in paths]
    for p, (_, ep, _) in zip(paths, candidates):  # one experiment's walkers (what a generation froze in aside)
        if _experiment(ep, run) != _experiment(run.episode, run):
            raise UserError(f"{p} holds a {ep.body}/{ep.controller} genome of another episode than the run's "
                            f"({run.episode.body}/{run.episode.controller} in {rundir.CONFIG}): the run directory is "
                            "mixed")
    labels = [f"generation {g}" for g in chosen_generations]
    if run.initial:  # first: kept unless a tuned genome beats it
        candidates.insert(0, _start(d, run))
        labels.insert(0, f"start ({run.initial})")
    configs = [c[1] for c in candidates]  # each its own: generation files may freeze their own normaliser
    same = all(c.to_dict() == configs[-1].to_dict() for c in configs)
    genomes = np.array([c[0] for c in candidates])
    rows = try_candidates(configs[-1] if same else configs, genomes, seconds, walking=walking)
    k = best_candidate(rows, heading_limit)
    out = d / SELECTED
    genome, episode_config, meta = candidates[k]
    episode = episode_config.nominal().build()
    done = episode.run(genome)
    # one set: never a new selected.json beside old candidates
    with output_set("select", [out, d / CANDIDATES], say=note):
        save_genome(out, genome, episode_config,
                    **{**meta, "selected_from": labels[k], "up_long_seconds": seconds if rows[k].get("up_long")
                       else None,
                                                   "outcome": outcome(done, episode.task.targets()),
                                                   rundir.FROM_CHECKPOINT: mark})
        write_json(d / CANDIDATES, {"seconds": seconds, "heading_limit": heading_limit, rundir.FROM_CHECKPOINT: mark,
                                    "candidates": [{"candidate": lab, **r} for lab, r in zip(labels, rows)]})
    return Selection(labels=labels, rows=rows, chosen=k, path=out)


def _start(d: Path, run: RunConfig) -> tuple:
    """The run's start genome as a candidate ``(genome, episode config, meta)``: the one its directory kept
    (start.json), else its source's; a walker given more inputs to learn is padded, in the run's episode, else it
    walks in its own (e.g. the normaliser it was evolved with)."""
    kept = d / rundir.START
    try:
        src = kept if kept.is_file() else rundir.genome_path(run.initial)[0]
    except UserError:
        raise UserError(f"the run started from {run.initial}, which is no longer there") from None
    start = load_genome(src)
    if len(start[0]) != run.episode.layout().size:
        start = (initial_genome(str(src), run.episode, run.episode.layout()), run.episode, start[2])
    return start


def _experiment(episode, run) -> dict:
    """An episode config as a table without what ``run`` sets per generation (its running normaliser, its curriculum
    phase's weights and episode length: evobiped.run.run_context), so generation files of one run compare equal."""
    d = episode.to_dict()
    if run.curriculum.seconds:
        d.pop("seconds", None)
    if run.normalise.running:
        d["controller_options"] = {k: v for k, v in d["controller_options"].items() if k != "input_norm"}
    if run.curriculum.phases:
        d["task_options"] = {k: v for k, v in d["task_options"].items() if k != "weights"}
    return d
