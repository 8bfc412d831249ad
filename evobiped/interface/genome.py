"""Flat real-valued genomes and their layouts.

A controller owns a :class:`GenomeLayout`: named blocks of genes, each with its
bounds, its initialisation Gaussian and its mutation sigma (Reil & Husbands
Fig. 4 and Table III).  The GA sees only the flat arrays and these vectors.
"""

from __future__ import annotations

from dataclasses import dataclass, fields, replace

import numpy as np

from ..core.errors import ConfigError, GenomeError


@dataclass(frozen=True, kw_only=True)
class GeneBlock:
    """``size`` consecutive genes of one parameter type."""

    name: str
    size: int
    low: float
    high: float
    init_mean: float
    init_sigma: float
    mutation_sigma: float
    #: whether an optimizer's weight decay (the ES's L2 pull) pulls this block towards its centre, (low + high) / 2;
    #: False for genes without a neutral value (a CTRNN's time constants), whose pull would be a prior of no meaning
    decays: bool = True

    def __post_init__(self):
        if self.size < 0 or not self.low <= self.high:
            raise ValueError(f"gene block {self.name!r}: bad size or bounds")


@dataclass(frozen=True)
class GenomeLayout:
    """An ordered tuple of :class:`GeneBlock`; genomes are flat ``(G,)`` arrays."""

    blocks: tuple[GeneBlock, ...]

    @property
    def size(self) -> int:
        return sum(b.size for b in self.blocks)

    def slices(self) -> dict[str, slice]:
        out, start = {}, 0
        for b in self.blocks:
            out[b.name] = slice(start, start + b.size)
            start += b.size
        return out

    def _per_gene(self, attr: str) -> np.ndarray:
        return np.concatenate([np.full(b.size, getattr(b, attr), float) for b in self.blocks])

    @property
    def low(self) -> np.ndarray:
        return self._per_gene("low")

    @property
    def high(self) -> np.ndarray:
        return self._per_gene("high")

    @property
    def centre(self) -> np.ndarray:
        """Each gene's block centre, (low + high) / 2."""
        return 0.5 * (self.low + self.high)

    @property
    def decays(self) -> np.ndarray:
        """Per gene: whether weight decay pulls it (:attr:`GeneBlock.decays`)."""
        return np.concatenate([np.full(b.size, b.decays, bool) for b in self.blocks])

    @property
    def init_mean(self) -> np.ndarray:
        return self._per_gene("init_mean")

    @property
    def init_sigma(self) -> np.ndarray:
        return self._per_gene("init_sigma")

    @property
    def mutation_sigma(self) -> np.ndarray:
        return self._per_gene("mutation_sigma")

    def sample(self, rng: np.random.Generator, n: int | None = None) -> np.ndarray:
        """Random genomes from the initialisation Gaussians, clipped to the bounds: ``(G,)``, or ``(n, G)``
        for a count ``n`` (one ``rng.normal`` draw of that shape, genes in order)."""
        size = None if n is None else (int(n), self.size)
        return np.clip(rng.normal(self.init_mean, self.init_sigma, size), self.low, self.high)

    def jitter(self, genomes: np.ndarray, noise: np.ndarray) -> np.ndarray:
        """``genomes`` ``(n, G)`` moved by ``noise`` ``(n, G)`` in units of each gene's range (high - low), clipped to
        the bounds."""
        return np.clip(genomes + noise * (self.high - self.low), self.low, self.high)

    def with_overrides(self, genes: dict[str, dict[str, float]]) -> "GenomeLayout":
        """A copy with some blocks' bounds or distributions replaced.

        ``genes`` maps a block name to new values of ``low``, ``high``,
        ``init_mean``, ``init_sigma``, ``mutation_sigma``, e.g.
        ``{"weights": {"init_sigma": 4.0}}`` (ConfigError on an unknown name).
        """
        if not isinstance(genes, dict):
            raise ConfigError("genes: must be a table of gene blocks")
        by_name = {b.name: b for b in self.blocks}
        settable = [f.name for f in fields(GeneBlock) if f.name not in ("name", "size", "decays")]
        new = dict(by_name)
        for name, values in genes.items():
            if name not in by_name:
                raise ConfigError(f"genes: no gene block {name!r} (have {', '.join(by_name)})")
            if not isinstance(values, dict) or not set(values) <= set(settable):
                raise ConfigError(f"genes.{name}: expected a table of {', '.join(settable)}")
            if not all(isinstance(v, (int, float)) and np.isfinite(v) for v in values.values()):
                raise ConfigError(f"genes.{name}: values must be finite numbers")
            try:
                new[name] = replace(by_name[name], **{k: float(v) for k, v in values.items()})
            except ValueError as exc:
                raise ConfigError(f"genes.{name}: {exc}") from None
            if min(new[name].init_sigma, new[name].mutation_sigma) < 0:
                raise ConfigError(f"genes.{name}: sigmas must be >= 0")
        return GenomeLayout(tuple(new[b.name] for b in self.blocks))

    def names(self) -> list[str]:
        """One label per gene, e.g. ``weights[3]``."""
        return [f"{b.name}[{i}]" for b in self.blocks for i in range(b.size)]

    def split(self, genomes: np.ndarray) -> dict[str, np.ndarray]:
        """``(P, G)`` genomes -> ``{block name: (P, block size)}`` views."""
        return {name: genomes[:, s] for name, s in self.slices().items()}

    def validate(self, genomes, *, what: str = "genome") -> np.ndarray:
        """Return genomes as a float ``(P, G)`` array or raise :class:`GenomeError`.

        Accepts one genome ``(G,)`` or a population ``(P, G)``.  Rejects a wrong
        length, non-finite values and values outside the bounds.
        """
        try:
            g = np.array(genomes, dtype=float)
        except (TypeError, ValueError) as exc:
            raise GenomeError(f"{what} is not an array of numbers ({exc})") from None
        if g.ndim == 1:
            g = g[None, :]
        if g.ndim != 2:
            raise GenomeError(f"{what} is an array of shape {g.shape}: give one genome ({self.size},) or a population "
                              f"(P, {self.size})")
        if g.shape[1] != self.size:
            raise GenomeError(f"{what} has {g.shape[1]} genes, the layout needs {self.size}")
        bad = ~np.isfinite(g)
        if bad.any():
            p, i = np.argwhere(bad)[0]
            raise GenomeError(f"{what} gene {self.names()[i]} is not finite ({g[p, i]})")
        low, high = self.low, self.high
        out = (g < low) | (g > high)
        if out.any():
            p, i = np.argwhere(out)[0]
            raise GenomeError(
                f"{what} gene {self.names()[i]} = {g[p, i]:g} is outside [{low[i]:g}, {high[i]:g}]"
            )
        return g
