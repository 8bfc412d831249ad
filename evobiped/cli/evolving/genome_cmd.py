"""``evobiped genome``: a genome file made from a walker's (other gene ranges, senses rewired, a preset's start).

Five actions over :mod:`evobiped.files.genome_edit` (``command-calibrate`` over :mod:`evobiped.analysis.speed_battery`);
each writes only the OUT it is given and prints it.
"""

from __future__ import annotations

import json
import sys

from ...core.errors import UserError
from ...flags import MAX_SPEED, finite_float, positive_float

#: the shipped walkers the start genomes are made from by default (paths from the repository's root)
SCRATCH_WALKER = "docs/walkers/ctrnn_es_seed5.json"
WALKING_WALKER = "docs/walkers/ctrnn_walk_seed1.json"


def add_genome(sub) -> None:
    p = sub.add_parser("genome", help="write a genome file made from a walker's: other gene ranges, senses rewired, a "
                                      "preset's start genome",
                       description="Write a genome file made from a walker's genome file; nothing but OUT is written.")
    actions = p.add_subparsers(dest="action", required=True, metavar="ACTION")
    r = actions.add_parser("ranges", help="the same walker with other declared ranges for gene blocks (another "
                                          "yardstick for the battery's gene noise)",
                           description="Write IN as OUT with the ranges of the named gene blocks declared otherwise; "
                                       "every gene and the rest of the file kept. A gene outside its new range is "
                                       "refused (it would be clipped: another walker).")
    r.add_argument("genome", metavar="IN", help="a genome JSON file")
    r.add_argument("out", metavar="OUT", help="the genome file to write")
    r.add_argument("--block", nargs=3, action="append", required=True, metavar=("NAME", "LOW", "HIGH"),
                   help="a gene block's new range (repeat for several blocks)")
    r.set_defaults(func=run_genome_ranges)
    h = _from_walker(actions, "hearing-start", SCRATCH_WALKER, run_genome_hearing,
                     "the start genome of --preset steer-es: the walker's heading sense replaced by the ear signal",
                     "Write the start genome of --preset steer-es: the walker's heading_error rows become the ear "
                     "signal's, negated and scaled so that it turns towards a source --reference-distance m away as it "
                     "turned back to its first facing; every other gene and input normalisation kept.")
    h.add_argument("--reference-distance", type=positive_float, default=4.0, metavar="M",
                   help="the source distance in m at which it turns as it held its heading (default 4)")
    h.add_argument("--preset", default="steer-es", metavar="NAME",
                   help="the steering preset it starts (default steer-es; steer-walk for a walker whose network is "
                        "integrated exactly, as the walking route's are)")
    h.add_argument("--neurons-only", action="store_true",
                   help="the ear signal into the neurons only, not on the direct input-to-motor path (the walker then "
                        "hardly turns)")
    w = _from_walker(actions, "rewire", SCRATCH_WALKER, run_genome_rewire,
                     "the walker reading other senses: some dropped, others added with zero weights",
                     "Write the walker rewired onto other senses: each kept input keeps its weights and frozen "
                     "normalisation, an added one starts with zero weights and its declared centre and scale. Prints "
                     "the inputs and input_norm lines of the controller's table a run's config needs.")
    w.add_argument("--drop", action="append", metavar="SENSE", help="an input to drop (repeat; default: heading_error)")
    w.add_argument("--add", action="append", metavar="SENSE", help="an input to add (repeat; default: stance_side)")
    c = _from_walker(actions, "command-start", WALKING_WALKER, run_genome_command,
                     "the start genome of --preset walker-command-tune: the command senses added",
                     "Write the start genome of --preset walker-command-tune: the walker with command_speed and "
                     "command_turning added at zero weight (they change nothing until the search moves them), or with "
                     "--speed-gain K the speed command moving the frame its velocity sense reads: it feels K (v* - V) "
                     "m/s slower than it walks, V the --reference-speed.")
    c.add_argument("--speed-gain", type=finite_float, default=0.0, metavar="K",
                   help="the velocity sense's frame moves at K (v* - V) m/s (default 0: command_speed at zero weight)")
    c.add_argument("--stop-speed", type=finite_float, default=0.0, metavar="V0",
                   help="with --speed-gain: at a stop (command_stop) the frame of a V0 m/s command, where the walker "
                        "marks time (default 0: command_stop at zero weight)")
    k = actions.add_parser("command-calibrate", help="a commanded walker with its command_speed sense rescaled so that "
                           "it walks at the speed it is told",
                           description="Write IN as OUT with its command_speed input normalisation rescaled: IN "
                                       "follows each --speeds command for 20 s, its walked speed w is fitted as a + b "
                                       "v, and OUT reads a command v as IN read (v - a) / b. The genes stay; a "
                                       "command_stop row keeps its frame at a stop.")
    k.add_argument("genome", metavar="IN", help="a commanded walker's genome file or run directory")
    k.add_argument("out", metavar="OUT", help="the genome file to write")
    k.add_argument("--speeds", default="0.3,0.45,0.6,0.75", metavar="V,V[,...]",
                   help="the constant commands it follows, m/s (default 0.3,0.45,0.6,0.75)")
    k.set_defaults(func=run_genome_calibrate)
    c.add_argument("--reference-speed", type=positive_float, default=None, metavar="V",
                   help="with --speed-gain: the speed in m/s the walker walks at, where the command changes nothing")


def _from_walker(actions, name: str, walker: str, run, about: str, description: str):
    """An action writing OUT from the genome file ``--walker`` (default ``walker``); its parser, for its own flags."""
    p = actions.add_parser(name, help=about, description=description)
    p.add_argument("out", metavar="OUT", help="the genome file to write")
    p.add_argument("--walker", default=walker, metavar="FILE", help=f"the walker's genome file (default {walker})")
    p.set_defaults(func=run)
    return p


def run_genome_ranges(args) -> int:
    from ...files.genome_edit import with_ranges
    from ...files.genome_file import save_genome

    ranges = {}
    for name, lo, hi in args.block:
        try:
            ranges[name] = (float(lo), float(hi))
        except ValueError:
            raise UserError(f"--block {name}: low and high must be numbers, got {lo!r} {hi!r}") from None
    genome, cfg, meta = with_ranges(args.genome, ranges)
    save_genome(args.out, genome, cfg, **{k: v for k, v in meta.items() if k not in ("version", "environment")})
    print(args.out)
    return 0


def _walker(args) -> str:
    """``--walker``'s path; a default one missing here is one line saying where it is found."""
    from pathlib import Path

    if args.walker in (SCRATCH_WALKER, WALKING_WALKER) and not Path(args.walker).is_file():
        raise UserError(f"--walker: the default {args.walker} is a path from the repository's root; run there or give "
                        "--walker FILE")
    return args.walker


def run_genome_hearing(args) -> int:
    from ...files.genome_edit import hearing_genome

    _save(args, *hearing_genome(_walker(args), args.reference_distance, not args.neurons_only,
                                _steering_preset(args.preset)))
    print(args.out)
    return 0


def _steering_preset(name: str) -> str:
    """``--preset``: a shipped preset that steers a network walker (one line naming them otherwise)."""
    from ...files.genome_edit import start_presets

    steering = start_presets("steer")
    if name not in steering:
        raise UserError(f"--preset: must be a steering preset of a network that hears ({', '.join(steering)}), got "
                        f"{name!r}")
    return name


def run_genome_command(args) -> int:
    from ...files.genome_edit import command_genome

    _save(args, *command_genome(_walker(args), args.speed_gain, args.reference_speed, args.stop_speed))
    print(args.out)
    return 0


def run_genome_calibrate(args) -> int:
    from ...analysis.commanded import is_commanded
    from ...analysis.speed_battery import calibrate_speed
    from ...files.genome_file import save_genome
    from ...flags import number_list
    from ...record.source import resolve

    speeds = number_list("--speeds", args.speeds, MAX_SPEED, "m/s")
    if len(speeds) < 2 or not all(v > 0 for v in speeds):
        raise UserError(f"--speeds: expected two or more speeds above 0 m/s, comma-separated, got {args.speeds!r}")
    source = resolve(args.genome)
    if not is_commanded(source.config):
        raise UserError(f"{source.genome_path} is not a commanded walker (task {source.config.task!r}): it has no "
                        "speed command to calibrate")
    cfg, fit = calibrate_speed(source.config, source.genome, speeds)
    meta = source.meta  # the walker it was made from stays its source; each fit is kept
    save_genome(args.out, source.genome, cfg, source=meta.get("source", str(source.genome_path)),
                calibrations=[*meta.get("calibrations", []), fit])
    print(f"walked {', '.join(f'{w:.3f}' for w in fit['walked'])} m/s at {', '.join(f'{v:g}' for v in speeds)} m/s: "
          f"w = {fit['intercept']:.3f} + {fit['slope']:.3f} v", file=sys.stderr)
    print(args.out)
    return 0


def run_genome_rewire(args) -> int:
    from ...core.options import given
    from ...files.genome_edit import rewired

    drop = ["heading_error"] if args.drop is None else args.drop
    add = ["stance_side"] if args.add is None else args.add
    genome, cfg = rewired(_walker(args), drop, add)
    table = given(cfg.controller_options)
    _save(args, genome, cfg)
    print(f"inputs = {json.dumps(list(table['inputs']))}")
    if "input_norm" in table:
        n = table["input_norm"]
        print(f"input_norm = {{mean = {json.dumps(n['mean'])}, std = {json.dumps(n['std'])}, count = {n['count']!r}}}")
    print(args.out, file=sys.stderr)
    return 0


def _save(args, genome, cfg) -> None:
    """Write ``genome`` (G,) of episode ``cfg`` as ``args.out``, its source ``args.walker``."""
    from ...files.genome_file import save_genome

    save_genome(args.out, genome, cfg, source=str(args.walker))


SUBCOMMANDS = (add_genome,)
