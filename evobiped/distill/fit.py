"""Fitting the student: backpropagation through time of the ctrnn's Euler steps (JAX's ``lax.scan``, optax's Adam)
on windows of the recorded rollouts (:class:`Fitter`)."""

from __future__ import annotations

from typing import Callable

import numpy as np

from ..episode import EpisodeConfig
from ..core.errors import ConfigError, UserError
from .settings import DistillOptions
from .rollouts import Rollouts


def _jax():
    try:
        import jax
        import optax
    except ImportError:
        raise UserError(
            "distillation fits the network with JAX: pip install 'evobiped[distill]' (jax, optax)") from None
    jax.config.update("jax_enable_x64", True)
    return jax, optax


class Fitter:
    """Backpropagation through time for the ``ctrnn`` student of ``student_cfg``: fits its genome to the labels."""

    def __init__(self, student_cfg: EpisodeConfig, options: DistillOptions, seed: int):
        jax, optax = _jax()
        import jax.numpy as jnp

        body, ctrl, _ = student_cfg.parts()
        o = ctrl.options
        if not (ctrl.name == "ctrnn" and o.outputs == "after" and o.tau_scale == "log" and o.centre_crossing
                and o.motor == "full"):
            raise ConfigError("distillation fits a ctrnn student with outputs = \"after\", tau_scale = \"log\", "
                              "centre_crossing = true and motor = \"full\" (the defaults of evobiped distill)")
        self.options, self.layout = options, ctrl.layout
        low, high = body.action_bounds()
        n, k, m, dt = ctrl.n, ctrl.n_inputs, ctrl.n_outputs, ctrl.dt
        sl = self.layout.slices()
        reach = np.maximum(np.abs(low), np.abs(high))

        def targets(genome, x):
            """Student targets (T, m) rad for inputs x (T, k), from rest."""
            W = genome[sl["weights"]].reshape(n, n)
            tau = jnp.exp(genome[sl["time_constants"]])
            alpha = genome[sl["biases"]] + 0.5 * W.sum(axis=0)
            V = genome[sl["input_weights"]].reshape(k, n) if k else jnp.zeros((0, n))

            def tick(A, xt):
                O = jax.nn.sigmoid(A - alpha)
                A = A + dt / tau * (O @ W + xt @ V - A)
                out = jax.nn.sigmoid(A - alpha)[:m]
                return A, jnp.clip((out - 0.5) * 2.0 * reach, low, high)

            return jax.lax.scan(tick, jnp.zeros(n), x)[1]

        def loss(genome, xb, yb, wb):
            """Mean squared target error (rad^2) over the scored ticks ``wb`` (B, T) of windows ``xb``, ``yb``."""
            pred = jax.vmap(targets, in_axes=(None, 0))(genome, xb)
            return jnp.sum(wb[..., None] * (pred - yb) ** 2) / (jnp.sum(wb) * m)

        # the rate decays tenfold over all the iterations' steps: coarse early, fine at the end
        total = options.steps * options.iterations
        self.opt = optax.adam(optax.exponential_decay(options.learning_rate, transition_steps=total, decay_rate=0.1))
        lo, hi = jnp.asarray(self.layout.low), jnp.asarray(self.layout.high)

        @jax.jit
        def update(genome, opt_state, xb, yb, wb):
            value, grad = jax.value_and_grad(loss)(genome, xb, yb, wb)
            updates, opt_state = self.opt.update(grad, opt_state)
            return jnp.clip(genome + updates, lo, hi), opt_state, value

        self._update, self._loss = update, jax.jit(loss)
        self._targets = jax.jit(targets)
        self.rng = np.random.default_rng([seed, 0xD15])
        self.genome = jnp.asarray(random_start(self.layout, n, k, self.rng))
        self.opt_state = self.opt.init(self.genome)

    def fit(self, data: list[Rollouts], progress: Callable[[int, float], None] | None = None) -> float:
        """``options.steps`` Adam steps on windows drawn from ``data``; returns the RMS target error (rad) over
        (up to 256 of) the windows."""
        o = self.options
        sets = [(d, d.windows(o.window)) for d in data]
        index = [(i, r, t) for i, (_, w) in enumerate(sets) for r, t in w]
        if not index:
            raise UserError("no rollout stayed up for a whole fitting window: shorten --window or check the teacher")
        index = np.array(index)

        def batch(rows):
            """Inputs, labels and scored ticks of windows ``rows`` (set, rollout, start tick): a window that starts
            with its episode starts from rest as the network does, so every tick counts; any other skips its burn-in."""
            xb = np.stack([sets[i][0].x[r, t : t + o.window] for i, r, t in rows])
            yb = np.stack([sets[i][0].y[r, t : t + o.window] for i, r, t in rows])
            wb = np.ones(xb.shape[:2])
            wb[rows[:, 2] > 0, : o.burn_in] = 0.0
            return xb, yb, wb

        # the episode's first ticks, where the walker sets off: a quarter of each batch
        starts = index[index[:, 2] == 0]
        for s in range(o.steps):
            rows = index[self.rng.integers(len(index), size=o.batch)]
            if len(starts):
                rows[: o.batch // 4] = starts[self.rng.integers(len(starts), size=o.batch // 4)]
            self.genome, self.opt_state, value = self._update(self.genome, self.opt_state, *batch(rows))
            if progress is not None and (s + 1) % 50 == 0:
                progress(s + 1, float(np.sqrt(value)))
        rows = index[self.rng.permutation(len(index))[:256]]
        return float(np.sqrt(self._loss(self.genome, *batch(rows))))

    def targets(self, genome: np.ndarray, x: np.ndarray) -> np.ndarray:
        """The student's PD targets ``(T, m)`` rad for normalised inputs ``x`` ``(T, k)`` from rest, as fitted."""
        return np.asarray(self._targets(genome, x))

    @property
    def student_genome(self) -> np.ndarray:
        return np.clip(np.asarray(self.genome, float), self.layout.low, self.layout.high)


def random_start(layout, n: int, k: int, rng: np.random.Generator) -> np.ndarray:
    """A random start for the fit (identical hidden neurons would stay identical under gradient descent): weights
    N(0, 1/n) and input weights N(0, 1/k) (fan-in scaling, so net inputs start near unit size), ln tau and biases
    their initial mean + N(0, 0.5^2); inside the bounds."""
    g = layout.init_mean.copy()
    sl = layout.slices()
    g[sl["weights"]] += rng.normal(0.0, 1.0 / np.sqrt(n), n * n)
    for name in ("time_constants", "biases"):
        g[sl[name]] += rng.normal(0.0, 0.5, n)
    if k:
        g[sl["input_weights"]] += rng.normal(0.0, 1.0 / np.sqrt(k), k * n)
    return np.clip(g, layout.low, layout.high)
