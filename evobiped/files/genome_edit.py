"""Genome files made from a walker's: other gene ranges declared, senses rewired, a preset's start genome.

Each function reads a genome file and returns ``(genome (G,), EpisodeConfig)`` of a new one (``evobiped genome``
writes it); a walker's genes are kept wherever its episode still reads them, so the new file walks as the old one
did until a search moves it.

- :func:`with_ranges`: the same genes with other declared ranges for some gene blocks (the battery's gene noise
  is a fraction of a gene's range: another yardstick, the same walker);
- :func:`rewired`: the walker reading its inputs less some plus others (new rows zero,
  :func:`evobiped.episode.remap.remap_inputs`);
- :func:`hearing_genome`: the start of ``--preset steer-es``, the heading sense replaced by the ear signal;
- :func:`command_genome`: the start of ``--preset walker-command-tune``, the command senses added at zero weight, or
  the speed command moving the frame the walker's velocity sense reads.
"""

from __future__ import annotations

import dataclasses
import tomllib
from pathlib import Path

import numpy as np

from ..core.errors import UserError
from ..core.options import given
from ..episode import EpisodeConfig
from ..episode.remap import input_widths, remap_inputs, remap_norm
from .genome_file import load_genome
from .presets import names as preset_names, path as preset_path

#: m, the Reil ears either side of the pelvis centre
EAR = 0.25


def with_ranges(path: str | Path, ranges: dict[str, tuple[float, float]]) -> tuple[np.ndarray, EpisodeConfig, dict]:
    """(genome (G,), EpisodeConfig, metadata) of the genome file ``path`` with block name -> (low, high) declared
    (``[episode.controller_options.genes]``), every gene and the rest of the file kept; UserError for an unknown
    block, an empty range, or a gene outside its new range (it would be clipped: another walker)."""
    genome, cfg, meta = load_genome(path)
    genes = {**given(cfg.controller_options).get("genes", {})}
    for name, (lo, hi) in ranges.items():
        if not lo < hi:
            raise UserError(f"--block {name}: the range [{lo:g}, {hi:g}] is empty (give low < high)")
        if not np.isfinite(hi - lo):
            raise UserError(f"--block {name}: the range [{lo:g}, {hi:g}] must be finite and at most 1.8e308 wide")
        genes[name] = {**genes.get(name, {}), "low": float(lo), "high": float(hi)}
    new = dataclasses.replace(cfg, controller_options={**given(cfg.controller_options), "genes": genes})
    layout = new.parts()[1].layout  # ConfigError (a UserError) for an unknown block name
    for name, sl in layout.slices().items():
        g, (lo, hi) = genome[sl], (layout.low[sl], layout.high[sl])
        if ((g < lo) | (g > hi)).any():
            raise UserError(f"{path}: block {name} has genes in [{g.min():g}, {g.max():g}], outside the range "
                            f"[{lo.min():g}, {hi.max():g}]; they would be clipped (another walker)")
    return genome, new, meta


def rewired(walker: str | Path, drop: list[str], add: list[str]) -> tuple[np.ndarray, EpisodeConfig]:
    """(genome (G,), EpisodeConfig) of the walker in genome file ``walker`` reading its inputs less ``drop`` plus
    ``add`` (appended, zero rows, their declared centre and scale); each kept input keeps its row of weights and
    its frozen normalisation.  UserError for a sense it does not read (drop) or already reads (add)."""
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
        new = dataclasses.replace(new, controller_options={**bare, "inputs": new_inputs,
                                                           "input_norm": remap_norm(norm, old, new)})
    return _remapped(walker, genome, old, new), new


def hearing_genome(walker: str | Path, reference: float = 4.0, direct: bool = True, preset: str = "steer-es"
                   ) -> tuple[np.ndarray, EpisodeConfig]:
    """(genome (G,), EpisodeConfig) of the hearing walker of ``--preset steer-es`` (or another steering ``preset``,
    e.g. ``steer-walk``) made from the genome file ``walker``.

    The walker read ``heading_error`` (rad) and turned back to its first facing.  For a source at distance D (m)
    and a small bearing theta (rad, left positive) the ear signal is s ~ 2 e theta / D (ears at +-e = :data:`EAR`),
    so with s normalised by sigma_s = 2 e sigma_h / ``reference`` (m) and the rows of s minus those of the heading,
    the walker turns towards a source ``reference`` m away as it turned back to its facing.  ``direct`` False: the
    ear signal into the neurons only, not on the direct input-to-motor path.  ``reference`` must be > 0."""
    if not reference > 0:
        raise UserError(f"--reference-distance must be > 0 m, got {reference:g}")
    genome, old, _ = load_genome(walker)
    if "heading_error" not in (old.controller_options.inputs or ()):
        raise UserError(f"{walker}: the walker does not read heading_error; nothing to steer with")
    if old.controller_options.input_norm is None:
        raise UserError(f"{walker}: the walker has no frozen input_norm; the ear signal's scale is the heading's")
    sigma_h = old.controller_options.input_norm["std"][_offset(old, "heading_error")]
    genome, new = _onto_preset(walker, genome, old, preset, extra={"sound": ([0.0], [2 * EAR * sigma_h / reference])},
                               copy={"sound": ("heading_error", -1.0)})
    if not direct:  # the ear signal into the neurons only (they saturate; the direct path is linear)
        c = new.parts()[1]
        rows = genome[c.layout.slices()["direct_weights"]].reshape(c.n_inputs, -1)
        rows[_offset(new, "sound")] = 0.0
        genome[c.layout.slices()["direct_weights"]] = rows.ravel()
    return genome, new


def command_genome(walker: str | Path, speed_gain: float = 0.0, reference_speed: float | None = None,
                   stop_speed: float = 0.0) -> tuple[np.ndarray, EpisodeConfig]:
    """(genome (G,), EpisodeConfig) of ``--preset walker-command-tune``'s commanded walker made from the genome file
    ``walker``: every gene and its frozen input normalisation kept, ``command_speed`` and ``command_turning`` added.

    ``command_turning`` starts at zero weight (the commanded facing of the heading sense turns the walker).  With
    ``speed_gain`` k = 0, so does ``command_speed``.  With k > 0 the walker reads its forward velocity v (m/s,
    ``com_velocity``'s first column) in a frame moving at k (v* - v_ref) (v* the commanded speed, v_ref =
    ``reference_speed``, the speed it walks at, m/s): ``command_speed``'s rows of weights (into the neurons and on
    the direct path) are minus those of v, and its normalisation is (v* - v_ref) / (sigma_v / k) with sigma_v v's
    frozen scale, so the network sees (v - k (v* - v_ref) - m_v) / sigma_v where it saw (v - m_v) / sigma_v.  At
    v* = v_ref it is the walker; a faster command makes it feel slow, and its own speed regulation speeds it up
    (a walker that holds its pace through its velocity sense; k = 1 / (d v / d offset) makes the change one to one).
    ``stop_speed`` V0 > 0 m/s: at a stop (``command_stop`` 1) the frame is that of a V0 command, where the walker
    marks time (the speed a zero command would otherwise ask may be beyond what it can do); 0: ``command_stop`` at
    zero weight."""
    if not (np.isfinite(speed_gain) and speed_gain >= 0):
        raise UserError(f"--speed-gain must be a finite number >= 0, got {speed_gain:g}")
    if not (np.isfinite(stop_speed) and stop_speed >= 0) or (stop_speed and not speed_gain):
        raise UserError(f"--stop-speed must be a finite speed >= 0 m/s, and needs --speed-gain, got {stop_speed:g}")
    genome, old, _ = load_genome(walker)
    if not speed_gain:
        return _onto_preset(walker, genome, old, "walker-command-tune")
    if reference_speed is None or not (np.isfinite(reference_speed) and reference_speed > 0):
        raise UserError("--reference-speed must be a finite speed above 0 m/s with --speed-gain, got "
                        f"{reference_speed!r}")
    if "com_velocity" not in (old.controller_options.inputs or ()) or old.controller_options.input_norm is None:
        raise UserError(f"{walker}: the walker does not read com_velocity through a frozen input_norm; "
                        "a speed command cannot move its velocity sense")
    sigma_v = old.controller_options.input_norm["std"][_offset(old, "com_velocity")]
    extra = {"command_speed": ([float(reference_speed)], [sigma_v / speed_gain])}
    if stop_speed:
        extra["command_stop"] = ([0.0], [sigma_v / (speed_gain * stop_speed)])
    genome, new = _onto_preset(walker, genome, old, "walker-command-tune", extra=extra)
    c = new.parts()[1]
    v = _offset(new, "com_velocity")
    for block in ("input_weights", "direct_weights"):
        rows = genome[c.layout.slices()[block]].reshape(c.n_inputs, -1)
        for name in extra:
            rows[_offset(new, name)] = -rows[v]
        genome[c.layout.slices()[block]] = rows.ravel()
    return genome, new


def _onto_preset(walker, genome: np.ndarray, old: EpisodeConfig, preset: str, *, extra: dict | None = None,
                 copy: dict | None = None) -> tuple[np.ndarray, EpisodeConfig]:
    """``genome`` of episode ``old`` moved onto the episode of the preset named ``preset``, its frozen input
    normalisation with it (a new input: ``extra[name]`` = (means, stds), else its declared centre and scale).  A walker
    integrated otherwise than the preset's network (``integration``) is refused in one line: its network would
    change."""
    new = _preset_episode(preset)
    was, now = (getattr(e.controller_options, "integration", None) for e in (old, new))
    if was != now and old.controller == new.controller:
        others = [name for name in start_presets(new.task)
                  if _preset_episode(name).controller_options.integration == was]
        raise UserError(f"{walker}: the walker's network is integrated by {was!r}, --preset {preset}'s by {now!r}"
                        + (f" (take --preset {' or '.join(others)})" if others else ""))
    norm = old.controller_options.input_norm
    if norm is not None:
        new = dataclasses.replace(new, controller_options={**given(new.controller_options),
                                                           "input_norm": remap_norm(norm, old, new, extra)})
    return _remapped(walker, genome, old, new, copy), new


def _preset_episode(preset: str) -> EpisodeConfig:
    """The episode of the shipped preset named ``preset``."""
    return EpisodeConfig(**tomllib.loads(preset_path(preset).read_text())["episode"])


def start_presets(task: str) -> list[str]:
    """The shipped presets that start from a network walker (a CTRNN's start genome) and run task ``task``, by name."""
    out = []
    for name in preset_names():
        d = tomllib.loads(preset_path(name).read_text())
        e = d.get("episode", {})
        if d.get("preset", {}).get("needs_start") and e.get("controller") == "ctrnn" and e.get("task") == task:
            out.append(name)
    return out


def _remapped(walker, genome: np.ndarray, old: EpisodeConfig, new: EpisodeConfig,
              copy: dict | None = None) -> np.ndarray:
    """:func:`~evobiped.episode.remap.remap_inputs`, its ValueError (controllers that differ) one line naming
    ``walker``."""
    try:
        return remap_inputs(genome, old, new, copy=copy)
    except ValueError as e:
        raise UserError(f"{walker}: {e}") from None


def _offset(episode: EpisodeConfig, name: str) -> int:
    """Where input ``name`` of ``episode``'s controller begins among its input columns."""
    at = 0
    for n, w in zip(episode.parts()[1].input_names, input_widths(episode)):
        if n == name:
            return at
        at += w
    raise KeyError(name)
