"""Write the start genome of ``--preset steer-es``: a from-scratch CTRNN walker that hears.

The walker (default ``docs/walkers/ctrnn_es_seed5.json``) read ``heading_error``, the angle of its facing from its
initial facing, and turned back towards it.  The steering walker reads the ear signal s in its place (the steer task
does not offer a heading): for a source at distance D and a small bearing theta (left positive),
s ~ 2 e theta / D (ears at +-e = 0.25 m), so with s normalised by the scale sigma_s = 2 e sigma_h / D_ref, the
input weights of s = minus those of the heading make the walker turn towards a source D_ref m away as it turned back
to its initial facing (the heading error of a source on the left is negative).  Every other gene and input
normalisation is the walker's (:func:`evobiped.episode.remap.remap_inputs`)::

    python scripts/hearing_start.py OUT.json [--walker FILE] [--reference-distance 4] [--neurons-only]
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import tomllib
from pathlib import Path

from evobiped.episode import EpisodeConfig
from evobiped.core.errors import UserError
from evobiped.files.genome_file import load_genome, save_genome
from evobiped.core.options import given
from evobiped.files.presets import path as preset_path
from evobiped.episode.remap import remap_inputs, remap_norm

EAR = 0.25  # m, the Reil ears either side of the pelvis centre


def hearing_genome(walker: Path, reference: float = 4.0, direct: bool = True):
    """(genome, EpisodeConfig) of the hearing walker made from the genome file ``walker``."""
    genome, old, _ = load_genome(walker)
    if "heading_error" not in (old.controller_options.inputs or ()):
        raise UserError(f"{walker}: the walker does not read heading_error; nothing to steer with")
    table = tomllib.loads(preset_path("steer-es").read_text())["episode"]
    new = EpisodeConfig(**table)
    norm = old.controller_options.input_norm
    sigma_h = norm["std"][_offset(old, "heading_error")]
    sigma_s = 2 * EAR * sigma_h / reference
    new = dataclasses.replace(new, controller_options={**given(new.controller_options),
                                                         "input_norm": remap_norm(norm, old, new, {"sound": ([0.0], [sigma_s])})})
    genome = remap_inputs(genome, old, new, copy={"sound": ("heading_error", -1.0)})
    if not direct:  # the ear signal into the neurons only (they saturate; the direct path is linear)
        c = new.parts()[1]
        rows = genome[c.layout.slices()["direct_weights"]].reshape(c.n_inputs, -1)
        rows[_offset(new, "sound")] = 0.0
        genome[c.layout.slices()["direct_weights"]] = rows.ravel()
    return genome, new


def _offset(episode, name: str) -> int:
    from evobiped.episode.remap import input_widths as _widths

    at = 0
    for n, w in zip(episode.parts()[1].input_names, _widths(episode)):
        if n == name:
            return at
        at += w
    raise KeyError(name)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("out")
    p.add_argument("--walker", default="docs/walkers/ctrnn_es_seed5.json")
    p.add_argument("--reference-distance", type=float, default=4.0)
    p.add_argument("--neurons-only", action="store_true",
                   help="the ear signal into the neurons only, not on the direct input-to-motor path (the walker then hardly turns)")
    a = p.parse_args(argv)
    try:
        if not a.reference_distance > 0:
            raise UserError(f"--reference-distance must be > 0 m, got {a.reference_distance:g}")
        genome, cfg = hearing_genome(Path(a.walker), a.reference_distance, not a.neurons_only)
    except UserError as e:
        print(f"hearing_start: error: {e}", file=sys.stderr)
        return 2
    save_genome(a.out, genome, cfg, source=str(a.walker))
    print(a.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
