"""Write the start genome of ``--preset walker-command-tune``: a walking CTRNN that reads the commands.

The walker (default ``docs/walkers/ctrnn_walk_seed1.json``, the from-scratch network that walks) keeps every gene and its frozen input normalisation; the
senses ``command_speed`` and ``command_turning`` are added with zero weights (they change nothing until the search
moves them) and their declared centre and scale (:func:`evobiped.episode.remap.remap_inputs`).  On the command task
its ``heading_error`` reads the angle from the commanded facing, so the heading hold it evolved turns it at a
commanded turning rate from the start::

    python scripts/command_start.py OUT.json [--walker FILE]
    evobiped evolve --preset walker-command-tune --from OUT.json
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import tomllib
from pathlib import Path

from evobiped.core.errors import UserError
from evobiped.core.options import given
from evobiped.episode import EpisodeConfig
from evobiped.episode.remap import remap_inputs, remap_norm
from evobiped.files.genome_file import load_genome, save_genome
from evobiped.files.presets import path as preset_path


def command_genome(walker: Path):
    """(genome, EpisodeConfig) of the commanded walker made from the genome file ``walker``."""
    genome, old, _ = load_genome(walker)
    new = EpisodeConfig(**tomllib.loads(preset_path("walker-command-tune").read_text())["episode"])
    norm = old.controller_options.input_norm
    if norm is not None:
        new = dataclasses.replace(new, controller_options={**given(new.controller_options), "input_norm": remap_norm(norm, old, new)})
    try:
        return remap_inputs(genome, old, new), new
    except ValueError as e:
        raise UserError(f"{walker}: {e}") from None


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("out")
    p.add_argument("--walker", default="docs/walkers/ctrnn_walk_seed1.json")
    a = p.parse_args(argv)
    try:
        genome, cfg = command_genome(Path(a.walker))
    except UserError as e:
        print(f"command_start: error: {e}", file=sys.stderr)
        return 2
    save_genome(a.out, genome, cfg, source=str(a.walker))
    print(a.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
