"""Evolution strategies: OpenAI-ES (Salimans et al. 2017) and ARS V2-t (Mania, Guy & Recht 2018).

One search point theta (the policy), estimated gradients from mirrored samples:
each generation asks N pairs theta +- sigma eps_i (eps_i ~ N(0, I), from (run
seed, generation) only) and the evaluation rows, theta itself (the policy the
run reports: its walkers are the "evaluation walkers"); all rows meet the same
perturbed presentations (common random numbers).

* ``method = "openai"``: the 2N fitness values become centred ranks in
  [-0.5, 0.5] (tied values share their mean rank: ``ties``); g = sum_i (r+_i d+_i
  + r-_i d-_i) / (2N) - weight_decay (theta - c), and Adam (beta 0.9, 0.999)
  climbs g at ``learning_rate`` (as in Salimans et al.'s
  evolution-strategies-starter).  d+-_i is the perturbation row +-i was
  evaluated at, in units of sigma (+-eps_i unless clipped: ``credit``); c is
  each gene block's centre (``weight_decay_to``).
* ``method = "ars"``: the ``top`` directions by max(f+, f-) are kept and
  theta += learning_rate / (top sigma_f) sum ((f+ - b) d+ + (f- - b) d-), b the
  mean and sigma_f the std of those 2 top fitness values (= (f+ - f-) eps when
  nothing is clipped: ARS V2-t, with the normaliser the run keeps).  An unstable
  rollout (non-finite fitness) counts as the generation's worst finite one: a
  stand-in far below it would be the only thing sigma_f measured and erase the
  other pairs' information for that step.

Bounds (``credit = "evaluated"``, the default).  Samples are clipped to the
genes' bounds, and a sample's fitness is credited to the perturbation it was
evaluated at, (clipped row - theta) / sigma, not to the eps it was drawn with:
a sample clipped back onto theta (theta on a bound, eps pointing out) made no
move and is credited with none.  Where theta sits on a bound after a step,
Adam's momentum pointing out of it is dropped, so pressing on a bound builds no
momentum that would hold theta there after the fitness turns.  ``credit =
"drawn"`` is the update as first shipped (the unclipped eps credited, momentum
kept), which the presets evolved before keep.

Weight decay (``weight_decay_to = "centre"``, the default) pulls each gene
towards its block's centre (low + high) / 2: 0 for the weights and biases,
whose ranges are centred on 0 (with ``centre_crossing`` a bias gene 0 is the
sigmoid's sensitive middle), the middle of any block whose range is not.  A
block that declares ``decays = False`` (:class:`~evobiped.interface.genome.GeneBlock`:
the CTRNN's time constants, tau or ln tau) is not pulled: no time constant is
neutral, and a fitness that carries no information about tau would let the pull
alone set it.  ``"zero"`` pulls every gene towards 0 (as first shipped: it
drags ln tau towards 0, tau towards 1 s).

Everything is in gene units (``sigma``, ``learning_rate``).  ``sigma`` may
shrink each generation by ``sigma_decay`` down to ``sigma_min``.  Why our own
~200 lines rather than a library: evosax (JAX) and evotorch (PyTorch) would
bring a whole array framework into the core install for an update of a few
NumPy lines, and a state that is a plain value of floats is what the checkpoint
stores and a resume restores bit for bit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..core.errors import ConfigError, UserError
from ..core.options import check_fields, option
from .base import MAX_POPULATION, Optimizer, OptimizerState, frozen_array

BETA1, BETA2, EPS = 0.9, 0.999, 1e-8


@dataclass(frozen=True, kw_only=True)
class ESOptions:
    """Evolution-strategies settings (gene units)."""

    method: str = option("openai", "`openai`: OpenAI-ES (centred ranks, Adam); `ars`: ARS V2-t (top directions, SGD)",
                         choices=("openai", "ars"))
    pairs: int = option(16, "N, mirrored pairs theta +- sigma eps per generation", low=1, high=MAX_POPULATION // 2,
                        integer=True)
    evaluation_rows: int = option(1, "rows of theta itself per generation (its walkers report the run; each meets "
                                     "every presentation)", low=1, high=64, integer=True)
    sigma: float = option(0.05, "sampling step", unit="gene units", above=0)
    sigma_decay: float = option(1.0, "sigma times this each generation", above=0, high=1)
    sigma_min: float = option(0.0, "sigma never decays below this", unit="gene units", low=0)
    learning_rate: float = option(0.02, "Adam's (openai) or the step's (ars) learning rate", unit="gene units", above=0)
    weight_decay: float = option(0.005, "L2 pull of theta towards `weight_decay_to` (openai)", low=0)
    top: int = option(0, "ARS: directions kept (0: all)", low=0, integer=True)
    weight_decay_to: str = option("centre", "where weight decay pulls: `centre`: each gene block's centre (low + high) "
                                            "/ 2, blocks without a neutral value (a CTRNN's time constants) not at "
                                            "all; `zero`: every gene towards 0 (as first shipped)",
                                  choices=("centre", "zero"))
    credit: str = option("evaluated", "what a sample's fitness is credited to: `evaluated`: the perturbation its "
                                      "clipped row made (no momentum out of a bound theta sits on); `drawn`: the "
                                      "unclipped sigma eps (as first shipped)", choices=("evaluated", "drawn"))
    ties: str = option("average", "openai's ranks of tied fitness values: `average`: their mean rank (a tied pair "
                                  "gives no step); `order`: in order of appearance (as first shipped: a tied pair "
                                  "steps along -eps)", choices=("average", "order"))

    def __post_init__(self):
        check_fields(self, "es")
        if self.top > self.pairs:
            raise ConfigError(f"top: keeps at most the {self.pairs} pairs, got {self.top}")


@dataclass(frozen=True, kw_only=True, eq=False)
class ESState(OptimizerState):
    """ES between generations: theta ``(G,)``, Adam's moments ``m``, ``v`` ``(G,)``, the current population's fitness
    and the generation its current attempt started (``started``: 0 unless the run started over)."""

    name = "es"
    theta: np.ndarray
    m: np.ndarray
    v: np.ndarray
    started: int = 0

    def __post_init__(self):
        for k in ("theta", "m", "v", "fitness"):
            object.__setattr__(self, k, frozen_array(getattr(self, k)))

    def to_dict(self) -> dict:
        plain = lambda a: [float(x) if np.isfinite(x) else None for x in a]  # noqa: E731
        return {"name": self.name, "generation": self.generation, "theta": plain(self.theta), "m": plain(self.m),
                "v": plain(self.v), "fitness": plain(self.fitness),
                **({"started": self.started} if self.started else {})}


def centred_ranks(f: np.ndarray, ties: str = "average") -> np.ndarray:
    """Ranks of ``f`` scaled to [-0.5, 0.5]; tied values share their mean rank (``ties = "average"``) or are ranked in
    order of appearance (``"order"``)."""
    f = np.asarray(f, float)
    r = np.empty(len(f))
    r[np.argsort(f, kind="stable")] = np.arange(len(f))
    if ties == "average" and len(f):
        _, group = np.unique(f, return_inverse=True)
        r = (np.bincount(group, r) / np.bincount(group))[group]
    return r / max(len(f) - 1, 1) - 0.5


class EvolutionStrategy(Optimizer):
    """Ask/tell ES over a :class:`GenomeLayout` (:class:`~.base.Optimizer`): rows ``[theta + sigma eps (N), theta -
    sigma eps (N), theta (evaluation_rows)]``."""

    name, Options, table, about = "es", ESOptions, "es", "evolution strategies"
    reports_evaluation_rows = True
    starts_over = True

    def __init__(self, layout, config: ESOptions, **start):
        """As every optimizer (:meth:`Optimizer.__init__`); theta starts at the start point (the start genome, else the
        layout's ``init_mean``)."""
        super().__init__(layout, config, **start)
        self.theta = self.start_point()
        self.centre = layout.centre if config.weight_decay_to == "centre" else np.zeros(layout.size)
        self.decays = layout.decays if config.weight_decay_to == "centre" else np.ones(layout.size, bool)
        self.m, self.v = np.zeros(layout.size), np.zeros(layout.size)
        self.generation = self.started = 0
        self._sample()

    @classmethod
    def population_size(cls, options: ESOptions, n_genes: int) -> int:
        return 2 * options.pairs + options.evaluation_rows

    @classmethod
    def population_setting(cls, population: int) -> tuple[str, int]:
        """``--population`` P: P // 2 mirrored pairs (at least one)."""
        return "pairs", max(1, population // 2)

    @property
    def sigma(self) -> float:
        """The sampling step of this generation (gene units)."""
        c = self.config
        return max(c.sigma * c.sigma_decay ** (self.generation - self.started),
                   c.sigma_min) if c.sigma_decay < 1 else c.sigma

    def _noise(self) -> np.ndarray:
        eps = self.rng(self.generation).standard_normal((self.config.pairs, self.layout.size))
        return eps * self.mutable

    def _sample(self) -> None:
        eps, s = self._noise(), self.sigma
        rows = np.concatenate([self.theta + s * eps, self.theta - s * eps,
                               np.tile(self.theta, (self.config.evaluation_rows, 1))])
        self.population = np.clip(rows, self.low, self.high)
        self.fitness = np.full(len(self.population), np.nan)

    def _evaluated(self, eps: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The perturbations ``(N, G)`` the + and - rows were evaluated at, in units of sigma: +eps and -eps where their
        rows were not clipped; (row - theta) / sigma where they were (``credit = "evaluated"``; ``"drawn"``: None, None,
        the update credits +-eps)."""
        if self.config.credit == "drawn":
            return None, None
        N, s = self.config.pairs, self.sigma
        rows = self.population[: 2 * N]
        drawn = np.concatenate([self.theta + s * eps, self.theta - s * eps])
        d = np.where(rows == drawn, np.concatenate([eps, -eps]), (rows - self.theta) / s)
        return d[:N], d[N:]

    def evaluation_rows(self) -> np.ndarray:
        """The rows of theta itself (the evaluation walkers)."""
        return np.arange(2 * self.config.pairs, len(self.population))

    def ranking(self) -> np.ndarray:
        """The evaluation rows first (theta: the policy a generation stands for, what its generation file and the run's
        best keep), fittest first; then the samples by fitness."""
        order = np.argsort(-self.fitness, kind="stable")
        mean = order >= 2 * self.config.pairs
        return np.concatenate([order[mean], order[~mean]])

    def next_generation(self) -> np.ndarray:
        """Climb the estimated gradient; every row of the next generation is new (all -1)."""
        if np.isnan(self.fitness).any():
            raise RuntimeError("next_generation before every individual was evaluated")
        c, N = self.config, self.config.pairs
        f = self.fitness[: 2 * N]
        finite = np.isfinite(f)
        eps = self._noise()
        dp, dm = self._evaluated(eps)
        if c.method == "ars":
            # unstable: the generation's worst finite one
            f = np.where(finite, f, f[finite].min() if finite.any() else 0.0)
            plus, minus = f[:N], f[N:]
            keep = np.argsort(-np.maximum(plus, minus), kind="stable")[: c.top or N]
            kept = np.concatenate([plus[keep], minus[keep]])
            spread, b = float(np.std(kept)), float(np.mean(kept))
            if dp is None:
                total = (plus[keep] - minus[keep]) @ eps[keep]
            else:  # = (f+ - f-) eps where nothing is clipped
                total = (plus[keep] - b) @ dp[keep] + (minus[keep] - b) @ dm[keep]
            step = total * (c.learning_rate / (len(keep) * spread)) if spread > 0 else 0.0
            self.theta = self.theta + step * self.mutable
        else:
            r = centred_ranks(f, c.ties)  # unstable (told as -inf): below every finite one
            rp, rm = r[:N], r[N:]
            g = ((rp - rm) @ eps if dp is None else rp @ dp + rm @ dm) / (2 * N)  # the same where nothing is clipped
            g = (g - c.weight_decay * (self.theta - self.centre) * self.decays) * self.mutable
            t = self.generation - self.started + 1
            self.m = BETA1 * self.m + (1 - BETA1) * g
            self.v = BETA2 * self.v + (1 - BETA2) * g * g
            a = c.learning_rate * math.sqrt(1 - BETA2**t) / (1 - BETA1**t)
            self.theta = self.theta + a * self.m / (np.sqrt(self.v) + EPS)
        self.theta = np.clip(self.theta, self.low, self.high)
        if c.credit == "evaluated":  # no momentum out of a bound theta sits on
            self.m = np.where(((self.theta >= self.high) & (self.m > 0)) | ((self.theta <= self.low) & (self.m < 0)),
                              0.0, self.m)
        self.generation += 1
        self._sample()
        return np.full(len(self.population), -1)

    # ---- its state as a value
    def start_over(self) -> np.ndarray:
        """Start over at this generation (:meth:`Optimizer.start_over`): theta at the start point, Adam's moments and
        the sigma schedule from nothing; the noise is this generation's."""
        self.theta, self.started = self.start_point(), self.generation
        self.m, self.v = np.zeros(self.layout.size), np.zeros(self.layout.size)
        self._sample()
        return np.full(len(self.population), -1)

    def state(self) -> ESState:
        return ESState(generation=self.generation, theta=self.theta, m=self.m, v=self.v, fitness=self.fitness,
                       started=self.started)

    def restore(self, state: ESState) -> None:
        G = self.layout.size
        if any(len(a) != G for a in (state.theta, state.m, state.v)):
            raise UserError(f"checkpoint: the ES state's theta, m and v must have {G} genes each")
        self.generation, self.started = state.generation, state.started
        self.theta, self.m, self.v = (np.array(a, float) for a in (state.theta, state.m, state.v))
        self._resample_with_fitness(state.fitness, "ES")

    def _state_from(self, table: dict) -> ESState:
        gen = ESState.generation_of(table)
        out = {k: ESState.numbers_of(table, k, null=np.nan if k == "fitness" else None)
               for k in ("theta", "m", "v", "fitness")}
        if (out["v"] < 0).any():
            raise UserError("checkpoint: es.v must be >= 0")
        started = table.get("started", 0)
        if isinstance(started, bool) or not isinstance(started, int) or not 0 <= started <= gen:
            raise UserError(f"checkpoint: es.started must be a whole number in [0, {gen}], got {started!r}")
        return ESState(generation=gen, started=started, **out)
