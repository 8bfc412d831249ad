"""Write a walker's genome rewired onto other senses: some inputs dropped, new ones added with zero weights.

Every gene that does not depend on the inputs is kept, each kept input keeps its row of weights and its frozen
normalisation, and an added input starts with zero weights (it changes nothing until a search moves them) and its
declared centre and scale (:func:`evobiped.episode.remap.remap_inputs`).  The start of the ES route's turning
repertoire (docs/repertoire/es_turning.toml) is the from-scratch walker without its heading sense (which steered
it back to its first facing) and with ``stance_side`` (the stance frame's symmetry broken, so it can turn)::

    python scripts/rewire_inputs.py OUT.json [--walker FILE] [--drop heading_error] [--add stance_side]

It prints the two lines of the controller's table the run's config needs (``inputs`` and ``input_norm``).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
from pathlib import Path

from evobiped.core.errors import UserError
from evobiped.core.options import given
from evobiped.episode.remap import remap_inputs, remap_norm
from evobiped.files.genome_file import load_genome, save_genome


def rewired(walker: Path, drop: list[str], add: list[str]):
    """(genome, EpisodeConfig) of the walker in genome file ``walker`` reading its inputs less ``drop`` plus ``add``."""
    genome, old, _ = load_genome(walker)
    table = given(old.controller_options)
    inputs = list(table.get("inputs") or ())
    for name in drop:
        if name not in inputs:
            raise UserError(f"{walker}: the walker does not read {name} (it reads {', '.join(inputs)})")
    for name in add:
        if name in inputs and name not in drop:
            raise UserError(f"{walker}: the walker already reads {name}")
    new_inputs = [n for n in inputs if n not in drop] + list(add)
    bare = {k: v for k, v in table.items() if k != "input_norm"}
    new = dataclasses.replace(old, controller_options={**bare, "inputs": new_inputs})
    norm = table.get("input_norm")
    if norm is not None:
        new = dataclasses.replace(new, controller_options={**bare, "inputs": new_inputs, "input_norm": remap_norm(norm, old, new)})
    return remap_inputs(genome, old, new), new


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("out")
    p.add_argument("--walker", default="docs/walkers/ctrnn_es_seed5.json")
    p.add_argument("--drop", action="append", default=None, metavar="SENSE", help="an input to drop (default: heading_error)")
    p.add_argument("--add", action="append", default=None, metavar="SENSE", help="an input to add (default: stance_side)")
    a = p.parse_args(argv)
    drop = ["heading_error"] if a.drop is None else a.drop
    add = ["stance_side"] if a.add is None else a.add
    try:
        genome, cfg = rewired(Path(a.walker), drop, add)
    except (UserError, ValueError) as e:
        print(f"rewire_inputs: error: {e}", file=sys.stderr)
        return 2
    save_genome(a.out, genome, cfg, source=str(a.walker))
    table = given(cfg.controller_options)
    print(f"inputs = {json.dumps(list(table['inputs']))}")
    if "input_norm" in table:
        n = table["input_norm"]
        print(f"input_norm = {{mean = {json.dumps(n['mean'])}, std = {json.dumps(n['std'])}, count = {n['count']!r}}}")
    print(a.out, file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
