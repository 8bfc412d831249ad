"""Declare other ranges for a walker's gene blocks: the same genes, the same walker, another yardstick for gene noise.

The battery's gene noise moves every gene by Gaussian noise of a fraction of its declared range (high - low).  A walker
keeps its genes and behaves exactly as before when its ranges are declared otherwise (a genome decodes the same way
whatever its bounds), but the same fraction is then another noise.  This writes the genome file IN as OUT with the
ranges of the named blocks replaced (``[episode.controller_options.genes]``), every gene and the rest of the file kept;
a gene outside its new range is refused (it would be clipped: another walker)::

    python scripts/gene_ranges.py IN.json OUT.json --block weights -2 2 --block direct_weights -1 1 ...
"""

from __future__ import annotations

import argparse
import dataclasses
import sys

from evobiped.core.errors import UserError
from evobiped.files.genome_file import load_genome, save_genome
from evobiped.core.options import given


def with_ranges(path: str, ranges: dict[str, tuple[float, float]]):
    """(genome, EpisodeConfig, metadata) of the genome file ``path`` with block name -> (low, high) declared;
    UserError for an unknown block, an empty range, or a gene outside its new range."""
    genome, cfg, meta = load_genome(path)
    genes = {**given(cfg.controller_options).get("genes", {})}
    for name, (lo, hi) in ranges.items():
        if not lo < hi:
            raise UserError(f"--block {name}: the range [{lo:g}, {hi:g}] is empty (give low < high)")
        genes[name] = {**genes.get(name, {}), "low": float(lo), "high": float(hi)}
    new = dataclasses.replace(cfg, controller_options={**given(cfg.controller_options), "genes": genes})
    layout = new.parts()[1].layout  # ConfigError (a UserError) for an unknown block name
    for name, sl in layout.slices().items():
        g, (lo, hi) = genome[sl], (layout.low[sl], layout.high[sl])
        if ((g < lo) | (g > hi)).any():
            raise UserError(f"{path}: block {name} has genes in [{g.min():g}, {g.max():g}], outside the range "
                            f"[{lo.min():g}, {hi.max():g}]; they would be clipped (another walker)")
    return genome, new, meta


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("genome")
    p.add_argument("out")
    p.add_argument("--block", nargs=3, action="append", metavar=("NAME", "LOW", "HIGH"), required=True)
    a = p.parse_args(argv)
    try:
        ranges = {}
        for name, lo, hi in a.block:
            try:
                ranges[name] = (float(lo), float(hi))
            except ValueError:
                raise UserError(f"--block {name}: low and high must be numbers, got {lo!r} {hi!r}") from None
        genome, cfg, meta = with_ranges(a.genome, ranges)
    except UserError as e:
        print(f"gene_ranges: error: {e}", file=sys.stderr)
        return 2
    save_genome(a.out, genome, cfg, **{k: v for k, v in meta.items() if k not in ("version", "environment")})
    print(a.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
