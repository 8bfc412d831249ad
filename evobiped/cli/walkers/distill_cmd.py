"""``evobiped distill``: a CTRNN trained to imitate a stored walker; its genome file."""

from __future__ import annotations

import dataclasses

from ...core.errors import UserError
from ...flags import add_stored_walker, positive_float, positive_int, seed, unfinished_note, walk_line
from ...core.progress import Progress


def add_distill(sub) -> None:
    p = sub.add_parser("distill", help="train a CTRNN to imitate a walker (DAgger + backpropagation through time); "
                                       "writes a genome file")
    add_stored_walker(p, "teacher", "TEACHER", also=", any controller")
    p.add_argument("--config", metavar="FILE.toml", help="[distill] settings and [student] controller options")
    p.add_argument("--neurons", type=int, metavar="N", help="the student's neurons (default 40)")
    p.add_argument("--iterations", type=positive_int, metavar="I", help="DAgger iterations (default 5)")
    p.add_argument("--seed", type=seed, default=0, help="seed of the rollouts' noise and the fit (default 0)")
    p.add_argument("--seconds", type=positive_float, default=50.0, metavar="S",
                   help="the student's episode length in s (default 50)")
    p.add_argument("--out", metavar="FILE.json", help="the student's genome file (default runs/distill_<teacher run or "
                                                      "file>_seed<S>/student.json)")
    p.add_argument("--quiet", action="store_true", help="no progress lines")
    p.set_defaults(func=run_distill_cmd)


def run_distill_cmd(args) -> int:
    from pathlib import Path

    from ...distill import distill, parse_options, student_config
    from ...core.fileio import read_toml, write_json
    from ...files.genome_file import save_genome
    from ...files.outcome import outcome
    from ...record.source import resolve

    source = resolve(args.teacher, args.generation, args.allow_unfinished)
    unfinished_note(source)
    table = read_toml(args.config) if args.config else {}
    unknown = sorted(set(table) - {"distill", "student"})
    if unknown:
        raise UserError(f"{args.config}: unknown section {unknown[0]!r} (choose from distill, student)")
    settings = dict(table.get("distill", {}))
    if args.iterations is not None:
        settings["iterations"] = args.iterations
    options = parse_options(settings)
    overrides = dict(table.get("student", {}))
    body = overrides.pop("body", source.config.body)
    if body != source.config.body:
        raise UserError(f"the student's body {body!r} differs from the teacher's {source.config.body!r}: a student "
                        "imitates its teacher on the teacher's body")
    if args.neurons is not None:
        overrides["n_neurons"] = args.neurons
    student = student_config(source.config, overrides, seconds=args.seconds)
    student.layout()  # the contract (sensors, normalisation) checked before anything runs
    name = source.run_dir.name if source.run_dir is not None else source.genome_path.stem
    out = Path(args.out) if args.out else Path("runs") / f"distill_{name}_seed{args.seed}" / "student.json"
    if out.exists() and not out.is_file():
        raise UserError(f"--out {out} exists and is not a file")
    teacher_cfg = dataclasses.replace(source.config, perturbations={})
    check = teacher_cfg.build().run(source.genome)
    if check.fell[0]:
        raise UserError(f"the teacher {source.genome_path} falls at {check.end_time[0]:.1f} s of its own episode "
                        f"(latency {teacher_cfg.latency} ticks): it cannot teach walking")
    walk = check.walk()
    progress = Progress("distill", options.iterations * options.steps, "fitting steps", quiet=args.quiet)
    progress.say(f"teacher {source.genome_path}: up {check.end_time[0]:g} s, {walk_line(walk)}")
    steps = [0]  # every stage's line is a progress line with the time left, reckoned from the fitting steps done
    report = distill(teacher_cfg, source.genome, student=student, options=options, seed=args.seed,
                     progress=lambda line: progress.report(steps[0], line),
                     steps_done=lambda n: steps.__setitem__(0, n))
    progress.finish()
    episode = student.build()
    done = episode.run(report.genome)
    out.parent.mkdir(parents=True, exist_ok=True)
    save_genome(out, report.genome, student, fitness=float(done.fitness[0]), fell=bool(done.fell[0]),
                end_time=float(done.end_time[0]), seed=args.seed, teacher=str(source.genome_path),
                distill=dataclasses.asdict(options), iterations=report.iterations, chosen_iteration=report.chosen,
                outcome=outcome(done, episode.task.targets()))
    write_json(out.with_name(out.stem + "_distill.json"),
               {"teacher": str(source.genome_path), "options": dataclasses.asdict(options),
                                                          "iterations": report.iterations,
                "chosen_iteration": report.chosen})
    state = f"fell at t = {done.end_time[0]:.2f} s" if done.fell[0] else f"stayed up for {done.end_time[0]:.1f} s"
    print(f"student ({student.controller_options.n_neurons} neurons, iteration {report.chosen}): {state}; "
          f"{walk_line(done.walk())}")
    print(f"genome file: {out}")
    return 0


SUBCOMMANDS = (add_distill,)
