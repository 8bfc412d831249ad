"""A genome moved onto other inputs: the same controller reading a different list of senses (by name).

A walker evolved on some senses can seed a run that reads others (a walker that learns to steer: its heading
sense replaced by the ear signal).  :func:`remap_inputs` keeps every gene that does not depend on the inputs and
each input's row of weights by name; :func:`remap_norm` does the same for a frozen ``input_norm``.
"""

from __future__ import annotations

import numpy as np

from .config import EpisodeConfig


def input_widths(episode: EpisodeConfig) -> list[int]:
    """The widths of ``episode``'s controller's inputs, in input order."""
    body, controller, task = episode.parts()
    offered = {**body.sensor_widths, **task.sensor_widths()}
    return [offered[n] for n in controller.input_names]


#: controller -> its gene blocks of one row of genes per input (input-major), what :func:`remap_inputs` rearranges
INPUT_MAJOR = {"ctrnn": ("input_weights", "direct_weights"), "linear": ("weights",)}


def remap_inputs(genome: np.ndarray, old, new, *, copy: dict | None = None) -> np.ndarray:
    """``genome`` of episode config ``old`` as a genome of ``new``: the same controller reading other inputs.

    Every gene block that does not depend on the inputs is kept; a block of one row of genes per input
    (input-major: a CTRNN's ``input_weights`` and ``direct_weights``, a linear controller's weights) keeps each
    input's row by name and width, and a new input's row is zero (it has no influence), or ``factor`` times the
    row of an old input where ``copy`` maps new name -> (old name, factor) (e.g. the ear signal steering where
    the heading sense did).  An input ``old`` read and ``new`` does not is dropped.  ValueError when the two
    controllers differ in anything else."""
    genome = np.asarray(genome, float)
    (_, c_old, _), (_, c_new, _) = old.parts(), new.parts()
    if old.controller != new.controller:
        raise ValueError(f"a {old.controller} genome cannot become a {new.controller} genome")
    w_old, w_new = dict(zip(c_old.input_names, input_widths(old))), dict(zip(c_new.input_names, input_widths(new)))
    k_old, k_new = sum(w_old.values()), sum(w_new.values())
    at_old, at = {}, 0
    for n, w in w_old.items():
        at_old[n], at = at, at + w
    s_old, s_new = c_old.layout.slices(), c_new.layout.slices()
    if list(s_old) != list(s_new):
        raise ValueError(f"gene blocks differ: {list(s_old)} and {list(s_new)}")
    major = INPUT_MAJOR.get(new.controller)
    if major is None:
        raise ValueError(f"controller {new.controller!r}: which of its gene blocks hold one row per input is not known")
    out = np.zeros(c_new.layout.size)
    for name in s_new:
        a, b = genome[s_old[name]], s_new[name]
        n_new = b.stop - b.start
        if name not in major:
            if len(a) != n_new:
                raise ValueError(f"gene block {name}: {len(a)} genes cannot become {n_new}")
            out[b] = a
            continue
        m = len(a) // max(k_old, 1)
        if len(a) != m * k_old or n_new != m * k_new:
            raise ValueError(f"gene block {name}: {len(a)} genes for {k_old} inputs cannot become {n_new} for {k_new}")
        rows_old, rows = a.reshape(k_old, m), np.zeros((k_new, m))
        i = 0
        for n, w in w_new.items():
            src, factor = (n, 1.0) if n in w_old else (copy or {}).get(n, (None, 0.0))
            if src is not None and w_old.get(src) == w:
                rows[i:i + w] = factor * rows_old[at_old[src]:at_old[src] + w]
            i += w
        out[b] = rows.ravel()
    return out


def remap_norm(norm: dict, old, new, extra: dict | None = None) -> dict:
    """An ``input_norm`` of episode config ``old`` rearranged for ``new``'s inputs by name (as :func:`remap_inputs`);
    a new input takes ``extra[name]`` = (means, stds), else its declared centre and scale."""
    c_old, c_new = old.parts()[1], new.parts()[1]
    mean, std = np.asarray(norm["mean"], float), np.asarray(norm["std"], float)
    declared = c_new.input_norm
    at, old_at = 0, {}
    for n, w in zip(c_old.input_names, input_widths(old)):
        old_at[n], at = (at, w), at + w
    out_mean, out_std, at = [], [], 0
    for n, w in zip(c_new.input_names, input_widths(new)):
        if n in old_at and old_at[n][1] == w:
            i = old_at[n][0]
            out_mean += list(mean[i:i + w])
            out_std += list(std[i:i + w])
        elif extra and n in extra:
            out_mean += list(map(float, extra[n][0]))
            out_std += list(map(float, extra[n][1]))
        else:
            out_mean += list(declared[0][at:at + w])
            out_std += list(declared[1][at:at + w])
        at += w
    return {"mean": [float(v) for v in out_mean], "std": [float(v) for v in out_std],
            "count": float(norm.get("count", 0.0))}
