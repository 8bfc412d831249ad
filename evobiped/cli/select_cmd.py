"""``evobiped select``: the walker of a run chosen by simulating its best candidates for longer (selected.json)."""

from __future__ import annotations

from ..errors import UserError
from ..flags import positive_float, positive_int


def add_select(sub) -> None:
    p = sub.add_parser("select", help="re-simulate a run's fittest generation bests (and its --from genome) for longer; "
                                      "writes the best as selected.json")
    p.add_argument("run", metavar="RUN", help="a run directory")
    p.add_argument("--top", type=positive_int, default=8, metavar="K", help="the generation bests of the K fittest generations (default 8)")
    p.add_argument("--seconds", type=positive_float, default=200.0, metavar="S",
                   help="each candidate up through its episode runs S s alone (default 200)")
    p.add_argument("--heading-limit", type=positive_float, default=30.0, metavar="DEG",
                   help="prefer walkers within DEG of their initial facing (default 30)")
    p.set_defaults(func=run_select_cmd)


def run_select_cmd(args) -> int:
    from pathlib import Path

    import numpy as np

    from .. import rundir
    from ..fileio import read_json, write_json
    from ..genome_file import load_genome, save_genome
    from ..outcome import outcome
    from ..evolution.run_config import RunConfig, initial_genome
    from ..selection import best_candidate, try_candidates

    d = Path(args.run)
    if not (d / rundir.CONFIG).is_file() or not (d / rundir.HISTORY).is_file():
        raise UserError(f"{d} is not a run directory with completed generations (no {rundir.CONFIG} or {rundir.HISTORY})")
    best = rundir.read_history(d / rundir.HISTORY)["best"]
    top = [int(g) for g in np.argsort(-best, kind="stable")[:args.top]]
    paths = [rundir.generation_file(d, g) for g in top]
    missing = [p for p in paths if not p.is_file()]
    if missing:
        raise UserError(f"{missing[0]} is missing: the run directory is incomplete (resume it first)")
    cfg = read_json(d / rundir.CONFIG, what="run config")
    if not isinstance(cfg, dict):
        raise UserError(f"run config {d / rundir.CONFIG} is not a table of settings")
    run = RunConfig.from_dict({k: v for k, v in cfg.items() if k not in ("evobiped", "environment")}, where=str(d / rundir.CONFIG))
    candidates = [load_genome(p) for p in paths]
    for p, (_, ep, _) in zip(paths, candidates):  # one experiment's walkers (what a generation froze in aside)
        if _experiment(ep, run) != _experiment(run.episode, run):
            raise UserError(f"{p} holds a {ep.body}/{ep.controller} genome of another episode than the run's "
                            f"({run.episode.body}/{run.episode.controller} in {rundir.CONFIG}): the run directory is mixed")
    labels = [f"generation {g}" for g in top]
    if run.initial:  # first: kept unless a tuned genome beats it
        kept = d / rundir.START
        src = kept if kept.is_file() else Path(run.initial) / rundir.BEST if Path(run.initial).is_dir() else Path(run.initial)
        if not src.is_file():
            raise UserError(f"the run started from {run.initial}, which is no longer there")
        start = load_genome(src)
        if len(start[0]) != run.episode.layout().size:  # a walker given more inputs to learn: padded, the run's episode
            start = (initial_genome(str(src), run.episode, run.episode.layout()), run.episode, start[2])
        candidates.insert(0, start)  # else in its own episode (e.g. the normaliser it was evolved with)
        labels.insert(0, f"start ({run.initial})")
    configs = [c[1] for c in candidates]  # each its own: generation files may freeze their own normaliser
    same = all(c.to_dict() == configs[-1].to_dict() for c in configs)
    genomes = np.array([c[0] for c in candidates])
    rows = try_candidates(configs[-1] if same else configs, genomes, args.seconds)
    k = best_candidate(rows, args.heading_limit)
    print(f"{'candidate':<40}{'episode':>14}{'distance (m)':>14}{'heading':>9}{f'up {args.seconds:g} s':>10}")
    for i, (label, r) in enumerate(zip(labels, rows)):
        ep = "fell %.1f s" % r["end_time"] if r["fell"] else "up"
        h = "-" if r["heading_deg"] is None else f"{r['heading_deg']:+.0f} deg"
        mark = "  <- selected" if i == k else ""
        print(f"{label:<40}{ep:>14}{r['distance']:>14.2f}{h:>9}{'yes' if r.get('up_long') else 'no':>10}{mark}")
    out = d / "selected.json"
    genome, cfg, meta = candidates[k]
    episode = cfg.nominal().build()
    done = episode.run(genome)
    save_genome(out, genome, cfg, **{**meta, "selected_from": labels[k], "up_long_seconds": args.seconds if rows[k].get("up_long") else None,
                                     "outcome": outcome(done, episode.task.targets())})
    write_json(d / "selected_candidates.json", {"seconds": args.seconds, "heading_limit": args.heading_limit,
                                               "candidates": [{"candidate": lab, **r} for lab, r in zip(labels, rows)]})
    print(f"selected: {labels[k]} -> {out}")
    return 0


def _experiment(episode, run) -> dict:
    """An episode config as a table without what ``run`` sets per generation (its running normaliser, its curriculum
    phase's weights and episode length: evobiped.evolution.run_context), so generation files of one run compare equal."""
    d = episode.to_dict()
    if run.curriculum.seconds:
        d.pop("seconds", None)
    if run.normalise.running:
        d["controller_options"] = {k: v for k, v in d["controller_options"].items() if k != "input_norm"}
    if run.curriculum.phases:
        d["task_options"] = {k: v for k, v in d["task_options"].items() if k != "weights"}
    return d


SUBCOMMANDS = (add_select,)
