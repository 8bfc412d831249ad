"""``evobiped repertoire``: a map-elites run's archive summarised, drawn (heat map, QD score and coverage), its cells
listed."""

from __future__ import annotations


def add_repertoire(sub) -> None:
    p = sub.add_parser("repertoire", help="summarise and draw a map-elites run's gait repertoire (its archive.json)")
    p.add_argument("run", metavar="RUN", help="a map-elites run directory")
    p.add_argument("--figures", metavar="DIR", help="where the figures go (default RUN/figures_archive; for an archive "
                                                    "not in a run directory of its own, e.g. docs/repertoire, "
                                                    "runs/<its name>/figures_archive)")
    p.add_argument("--list", action="store_true", help="also list every walking elite: cell, measures, objective")
    p.set_defaults(func=run_repertoire_cmd)


def run_repertoire_cmd(args) -> int:
    from pathlib import Path

    from ...record.png.archive_figures import archive_figure, progress_figure
    from ...record.png.figures import fitness_label
    from ...repertoire.elites import WALK_SPEED, load_repertoire
    from ...files.rundir import figures_dir

    rep = load_repertoire(args.run)
    a, walk = rep.archive, rep.walking()
    names = tuple(f"{m} ({ {'speed': 'm/s', 'turning': 'deg/s'}.get(m, 'term units') })" for m in a.measures)
    cells = int(a.resolution[0] * a.resolution[1])
    print(f"{len(a.cell)} elites in {cells} cells after {int(a.progress[-1, 0])} evaluations; {int(walk.sum())} walk "
          f"(up all {rep.episode.seconds:g} s" + (f", >= {WALK_SPEED:g} m/s)" if "speed" in a.measures else ")"))
    for k, m in enumerate(names):
        if walk.any():
            print(f"walking gaits' {m}: {a.values[walk, k].min():.3g} to {a.values[walk, k].max():.3g}")
    out = Path(args.figures) if args.figures else figures_dir(rep.outputs, "archive")
    out.mkdir(parents=True, exist_ok=True)
    who = f"{rep.run_dir.name}: {rep.episode.body}/{rep.episode.controller}, {rep.episode.seconds:g} s episodes"
    for f in (archive_figure(out / "archive.png", cells=a.cell, objective=a.objective, walking=walk, names=names,
                             low=a.low, high=a.high,
                             resolution=a.resolution, objective_label=fitness_label(rep.episode), who=who),
              progress_figure(out / "archive_progress.png", progress=a.progress, walking_cells=int(walk.sum()),
                              cells_total=cells, who=who)):
        print(f"figure: {f}")
    if args.list:
        for k in sorted(map(int, (walk.nonzero()[0])), key=lambda k: tuple(a.cell[k])):
            print(f"cell {a.cell[k, 0]},{a.cell[k, 1]}: "
                  + ", ".join(f"{n} {v:.3f}" for n, v in zip(a.measures, a.values[k]))
                  + f", objective {a.objective[k]:.4g}")
    return 0


SUBCOMMANDS = (add_repertoire,)
