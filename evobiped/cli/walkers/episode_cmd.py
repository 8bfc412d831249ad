"""``evobiped episode``: one episode of a genome file's walker or a random genome; its fitness and walk."""

from __future__ import annotations

import dataclasses
import json

import numpy as np

from ...flags import add_source_flag, choices_text, positive_float, refuse, seed, walk_line
from ...tasks.sound import with_sources


def add_episode(sub) -> None:
    p = sub.add_parser("episode", help="run one episode and print its fitness")
    src = p.add_mutually_exclusive_group()
    src.add_argument("--genome", metavar="FILE", help="genome JSON file (default: a random genome)")
    src.add_argument("--seed", type=seed, default=0, help="seed of the random genome (default 0)")
    p.add_argument("--body", help=f"body: {choices_text('body')}, or mjcf:PATH (an MJCF biped and its declaration: "
                                  "docs/own_robot.md; default reil; not with --genome, whose file names it)")
    p.add_argument("--controller", help=f"controller: {choices_text('controller')} (default ctrnn; not with --genome)")
    p.add_argument("--seconds", type=positive_float, help="episode length in s (default: the genome file's episode, "
                                                          "else 50)")
    add_source_flag(p)
    p.add_argument("--json", action="store_true", help="print machine-readable JSON")
    p.set_defaults(func=run_episode_cmd)


def run_episode_cmd(args) -> int:
    from ...episode import EpisodeConfig
    from ...files.genome_file import load_genome

    if args.genome:
        if args.body or args.controller:
            refuse("--body/--controller", "a genome file names its own body and controller; give them without --genome")
        genome, cfg, _ = load_genome(args.genome)
    else:
        cfg = EpisodeConfig(body=args.body or "reil", controller=args.controller or "ctrnn")
        genome = None
    if args.seconds:
        cfg = dataclasses.replace(cfg, seconds=args.seconds)
    cfg = with_sources(cfg, args.sources)
    ep = cfg.build()
    if genome is None:
        genome = ep.controller.layout.sample(np.random.default_rng(args.seed))
    r = ep.run(genome)
    out = {
        "body": cfg.body,
        "controller": cfg.controller,
        "fitness": float(r.fitness[0]),
        "fell": bool(r.fell[0]),
        "unstable": bool(r.unstable[0]),
        "end_time": float(r.end_time[0]),
        **r.walk(),
    }
    targets = ep.task.targets()
    if targets is not None:  # the final distance to each presentation's target (a steering walker's sources)
        rows = r.rows if r.rows is not None else r
        out["sources"] = [{"source": list(map(float, q)),
                           "final_distance": float(np.linalg.norm(rows.end_position[j] - q)),
                           "fell": bool(rows.fell[j]), "end_time": float(rows.end_time[j]), **_arrival(rows.terms, j)}
                          for j, q in enumerate(targets)]
        final = [s["final_distance"] for s in out["sources"]]
        out["median_final_distance"], out["worst_final_distance"] = float(np.median(final)), float(np.max(final))
        out["falls"] = sum(s["fell"] for s in out["sources"])
    if args.json:
        print(json.dumps(out))
    else:
        state = f"fell at t = {out['end_time']:.2f} s" if out["fell"] else f"stayed up for {out['end_time']:.1f} s"
        print(f"fitness = {out['fitness']:.3f}; {state}; {walk_line(out)}")
        for s in out.get("sources", []):
            how = f"fell at t = {s['end_time']:.2f} s" if s["fell"] else f"up for {s['end_time']:.1f} s"
            came = "" if "arrival_time" not in s else (f"; arrived at {s['arrival_time']:.1f} s"
                                                       if s["arrival_time"] is not None
                                                       else "; never arrived") + ("; stood there at the end" if s[
                                                           "stood"] else "")
            print(f"source ({s['source'][0]:g}, {s['source'][1]:g}) m: final distance {s['final_distance']:.2f} m "
                  f"({how}){came}")
        if out.get("sources"):
            stood = sum(s.get("stood", False) for s in out["sources"])
            print(f"over {len(out['sources'])} source(s): median final distance {out['median_final_distance']:.2f} m, "
                  f"worst {out['worst_final_distance']:.2f} m; fell in {out['falls']} of {len(out['sources'])}"
                  + (f"; stood at {stood} of them at the end" if "stood" in out["sources"][0] else ""))
    return 0


def _arrival(terms: dict, j: int) -> dict:
    """A commanded walker steered by its ears (the steer-command task): when presentation ``j`` first came within reach
    (s, None: never) and whether it stood there at the end; {} for another task."""
    if "arrival_time" not in terms:
        return {}
    t = float(np.ravel(terms["arrival_time"])[j])
    return {"arrival_time": None if np.isnan(t) else t, "stood": bool(np.ravel(terms["stood"])[j])}


SUBCOMMANDS = (add_episode,)
