"""Distillation: train a network to imitate any walker (a teacher), correcting its own mistakes (DAgger).

DAgger (Ross, Gordon & Bagnell 2011): run the student, label every state it visits with what the teacher
would do there, add those to a growing data set, refit, repeat.  Here:

- **Rollouts** run teacher and student side by side in one simulation (:class:`Blend`): the body executes
  ``beta * teacher + (1 - beta) * student`` (PD targets, rad), with ``beta = 1`` in the first iteration (the
  teacher alone) and ``beta = beta0 * 0.5^(i - 1)`` after, so the early rollouts stay near the teacher's states
  while the student learns; rollouts run under target noise and initial-pose noise, which widen the states seen.
- **Latency as the teacher knows it.**  A teacher evolved with its actions applied ``latency`` ticks late
  (the ``latency`` controller option) walks only with that delay; the student, whose outputs follow its senses
  within the tick, is labelled with what the teacher's body *executes*: the teacher's action of ``latency``
  ticks before.
- **Fitting** by backpropagation through time (JAX's ``lax.scan`` over the CTRNN's Euler steps, optax's Adam)
  on windows of the recorded rollouts: each window starts from rest, and the first ``burn_in`` ticks are not
  scored unless the window starts with its episode (where the network too starts from rest); the loss is the mean squared error of the student's PD targets (after its motor map), in rad^2.
  Genes are kept inside their bounds after every step.  JAX is an optional dependency
  (``pip install 'evobiped[distill]'``): it differentiates the network's recurrence exactly, fast on a CPU.
- **Selection.**  Each iteration's student is a candidate (later ones imitate better, but an imitation can
  settle into a gait that drifts or falls late); :func:`evobiped.selection.best_candidate` keeps the one that is up
  through ``select_seconds`` alone, then walks within ``heading_limit`` of its initial facing, then farthest
  along it.  ``select_seconds = 0`` keeps the last iteration's.

The student is the ``ctrnn`` controller with the options of a network fit for senses (:data:`STUDENT`; any of
them may be changed).  The result is a genome file like any other: ``evolve --from``, ``replay``, ``robustness``
and ``episode --genome`` take it.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from . import gait
from .controllers.base import Controller
from .episode import EpisodeConfig
from .errors import ConfigError, UserError
from .mapping import to_action
from .options import option, parse
from .perturb import PerturbationOptions
from .selection import best_candidate, try_candidates

#: the student's controller options: every sense of the Reil body normalised, 40 neurons whose outputs follow
#: the update, ln-tau genes down to the control period, centre-crossing biases, the full-range motor map
STUDENT = dict(
    n_neurons=40, dt=0.02, motor="full", time_constants=[0.02, 5.0], tau_scale="log", outputs="after",
    normalise_inputs=True, input_weights=[-30.0, 30.0], input_sigma=1.0, centre_crossing=True,
)


@dataclass(frozen=True, kw_only=True)
class DistillOptions:
    """How a student is distilled from a teacher."""

    iterations: int = option(5, "DAgger iterations (the first runs the teacher alone)", low=1, high=100, integer=True)
    rollouts: int = option(16, "perturbed rollouts per iteration, side by side", low=1, high=1024, integer=True)
    seconds: float = option(20.0, "length of each rollout", unit="s", above=0, high=1000)
    beta0: float = option(0.5, "teacher's share of the executed targets in the second iteration, halved in each later one",
                          low=0, high=1)
    target_noise: float = option(0.01, "noise on the executed PD targets in the rollouts, per tick", unit="rad", low=0)
    pose_noise: float = option(0.02, "noise on the initial joint angles of the rollouts", unit="rad", low=0)
    window: int = option(200, "length of the windows fitted", unit="control ticks", low=2, high=10000, integer=True)
    burn_in: int = option(50, "ticks at the start of a window not scored (the network settles from rest)",
                          unit="control ticks", low=0, integer=True)
    steps: int = option(2000, "Adam steps after each iteration's data", low=1, high=10**6, integer=True)
    batch: int = option(32, "windows per Adam step", low=1, high=10**5, integer=True)
    learning_rate: float = option(1e-2, "Adam's initial learning rate (gene units), decaying tenfold over all the steps",
                                  above=0, high=1)

    select_seconds: float = option(200.0, "each iteration's student runs this long alone; the best is kept (0: the last one)",
                                   unit="s", low=0, high=10000)
    heading_limit: float = option(30.0, "selection prefers students walking within this angle of their initial facing",
                                  unit="deg", above=0, high=180)

    def __post_init__(self):
        if self.burn_in >= self.window:
            raise ConfigError(f"burn_in ({self.burn_in}) must be shorter than window ({self.window})")


class Blend(Controller):
    """Teacher and student in one simulation: executes ``beta`` teacher + ``(1 - beta)`` student (PD targets) and
    records, per tick, the student's inputs and its label, the teacher's action ``latency`` ticks before.

    Not a registered controller: :func:`collect` builds it around a teacher and a student already wired to the
    same body.  Its genomes are the student's; the teacher's genome is fixed."""

    name = "blend"
    output_kind = "angle"

    def __init__(self, teacher: Controller, teacher_genome: np.ndarray, student: Controller, *, low: np.ndarray,
                 high: np.ndarray, action_kind: str, latency: int, beta: float):
        self.teacher, self.student = teacher, student
        self.teacher_params = teacher.decode(teacher_genome)
        self.n_outputs, self.dt = student.n_outputs, student.dt
        names = list(teacher.input_names) + [n for n in student.input_names if n not in teacher.input_names]
        self.input_names = tuple(names)
        self.input_norm = None
        self.low, self.high, self.action_kind = low, high, action_kind
        self.latency, self.beta = int(latency), float(beta)
        #: per tick: (student inputs (n, k), labels (n, n_act))
        self.log: list[tuple[np.ndarray, np.ndarray]] = []

    def wire(self, widths: dict[str, int]) -> None:
        """Tell the blend how wide each input is (the body's and task's sensor widths)."""
        at, cols = 0, {}
        for name in self.input_names:
            cols[name] = np.arange(at, at + widths[name])
            at += widths[name]
        self._t_cols = np.concatenate([cols[n] for n in self.teacher.input_names]) if self.teacher.input_names else np.zeros(0, int)
        self._s_cols = np.concatenate([cols[n] for n in self.student.input_names]) if self.student.input_names else np.zeros(0, int)

    @property
    def layout(self):
        return self.student.layout

    def decode(self, genomes):
        return self.student.decode(genomes)

    def initial_state(self, params):
        P = next(iter(params.values())).shape[0]
        tp = {k: np.repeat(v, P, axis=0) for k, v in self.teacher_params.items()}
        return {"teacher": self.teacher.initial_state(tp), "student": self.student.initial_state(params), "tp": tp,
                "queue": []}

    def step(self, params, state, inputs):
        xs = inputs[:, self._s_cols]
        if self.student.input_norm is not None:
            xs = (xs - self.student.input_norm[0]) / self.student.input_norm[1]
        ts, t_out = self.teacher.step(state["tp"], state["teacher"], inputs[:, self._t_cols])
        ss, s_out = self.student.step(params, state["student"], xs)
        t_act = to_action(self.teacher.output_kind, self.low, self.high, self.action_kind, t_out)
        s_act = to_action(self.student.output_kind, self.low, self.high, self.action_kind, s_out)
        queue = state["queue"] + [t_act]  # the teacher's actions as its latency delivers them
        executed_teacher = queue[0]
        if len(queue) > self.latency:
            queue = queue[1:]
        self.log.append((xs.copy(), executed_teacher.copy()))
        action = self.beta * executed_teacher + (1.0 - self.beta) * s_act
        return {"teacher": ts, "student": ss, "tp": state["tp"], "queue": queue}, action

    def neuron_outputs(self, params, state):
        return self.student.neuron_outputs(params, state["student"])


@dataclass
class Rollouts:
    """Recorded rollouts: student inputs ``x`` (R, T, k), labels ``y`` (R, T, n_act) rad, and ``alive`` (R, T)."""

    x: np.ndarray
    y: np.ndarray
    alive: np.ndarray

    def windows(self, length: int) -> np.ndarray:
        """Start indices ``(n, 2)`` (rollout, tick) of every window of ``length`` ticks in which the walker is up,
        starting every ``length // 4`` ticks."""
        out = []
        R, T = self.alive.shape
        for r in range(R):
            for t in range(0, T - length + 1, max(1, length // 4)):
                if self.alive[r, t : t + length].all():
                    out.append((r, t))
        return np.array(out, int).reshape(-1, 2)


def collect(teacher_cfg: EpisodeConfig, teacher_genome: np.ndarray, student_cfg: EpisodeConfig, student_genome: np.ndarray,
            *, beta: float, options: DistillOptions, key: tuple[int, int]) -> Rollouts:
    """``options.rollouts`` rollouts of ``options.seconds`` executing ``beta`` teacher + ``(1 - beta)`` student,
    under target and pose noise drawn from ``key`` = (seed, iteration)."""
    t_body, teacher, task = teacher_cfg.parts()
    _, student, _ = student_cfg.parts()
    latency = teacher_cfg.latency
    low, high = t_body.action_bounds()
    blend = Blend(teacher, teacher_genome, student, low=low, high=high, action_kind=t_body.action_kind, latency=latency,
                  beta=beta)
    blend.wire({**t_body.sensor_widths, **task.sensor_widths()})
    from .episode import Episode

    ep = Episode(t_body, blend, task, seconds=options.seconds)
    pert = PerturbationOptions(presentations=options.rollouts, target_noise=options.target_noise, pose_noise=options.pose_noise)
    trials = pert.draw(key, seconds=options.seconds, n_actuators=len(t_body.actuators))
    alive_log: list[np.ndarray] = []

    class Alive:
        def start(self, episode, sims):
            self.n = sims.n

        def tick(self, t, sims, ids, neurons, action, task_state):
            mask = np.zeros(self.n, bool)
            mask[ids] = True
            alive_log.append(mask)

        def end(self, result): ...

    ep.run(student_genome, trials=trials, listener=Alive())
    T = len(alive_log)
    x = np.stack([blend.log[t][0] for t in range(T)], axis=1)
    y = np.stack([blend.log[t][1] for t in range(T)], axis=1)
    return Rollouts(x=x, y=y, alive=np.stack(alive_log, axis=1))


def _jax():
    try:
        import jax
        import optax
    except ImportError:
        raise UserError("distillation fits the network with JAX: pip install 'evobiped[distill]' (jax, optax)") from None
    jax.config.update("jax_enable_x64", True)
    return jax, optax


class Fitter:
    """Backpropagation through time for the ``ctrnn`` student of ``student_cfg``: fits its genome to the labels."""

    def __init__(self, student_cfg: EpisodeConfig, options: DistillOptions, seed: int):
        jax, optax = _jax()
        import jax.numpy as jnp

        body, ctrl, _ = student_cfg.parts()
        o = ctrl.options
        if not (ctrl.name == "ctrnn" and o.outputs == "after" and o.tau_scale == "log" and o.centre_crossing and o.motor == "full"):
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

        starts = index[index[:, 2] == 0]  # the episode's first ticks, where the walker sets off: a quarter of each batch
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


@dataclass
class DistillReport:
    """What a distillation did: per iteration the teacher's share, data size (ticks), fit error (rad) and how the
    student alone fared (its 50 s episode: fell, end time s, distance m, heading deg)."""

    genome: np.ndarray
    config: EpisodeConfig
    iterations: list[dict]
    #: the iteration (1-based) whose student :attr:`genome` is
    chosen: int = 0


def student_config(teacher_cfg: EpisodeConfig, overrides: dict[str, Any] | None = None, *,
                   seconds: float | None = None) -> EpisodeConfig:
    """The student's episode: the teacher's body and task, ``seconds`` long (default the teacher's), the ``ctrnn``
    controller with :data:`STUDENT` (and ``overrides``) reading every sensor the body declares a standing value for
    but the gait senses (:mod:`evobiped.gait`: the teacher's phase is learnt from the instantaneous senses;
    ``inputs`` in ``overrides`` adds them); no latency, no perturbations."""
    from .bodies import BODIES

    senses = [n for n in BODIES[teacher_cfg.body].sensor_norms if n not in gait.NAMES]
    opts = {**STUDENT, "inputs": senses, **(overrides or {})}
    if isinstance(opts.get("n_neurons"), (int, float)) and not isinstance(opts["n_neurons"], bool) and opts["n_neurons"] <= 0:
        raise ConfigError(f"student n_neurons must be > 0, got {opts['n_neurons']}")
    return dataclasses.replace(teacher_cfg, controller="ctrnn", controller_options=opts, perturbations={},
                               seconds=teacher_cfg.seconds if seconds is None else float(seconds))


def distill(teacher_cfg: EpisodeConfig, teacher_genome: np.ndarray, *, student: EpisodeConfig, options: DistillOptions,
            seed: int = 0, progress: Callable[[str], None] | None = None,
            steps_done: Callable[[int], None] | None = None) -> DistillReport:
    """DAgger from ``teacher_genome`` into the ``student`` episode's ctrnn; see the module docstring.  ``progress``
    hears a line at each stage; ``steps_done`` (optional) the fitting steps done so far, of iterations x steps,
    before each line (what a time left is reckoned from)."""
    say = progress or (lambda line: None)
    done = steps_done or (lambda n: None)
    fitter = Fitter(student, options, seed)
    data: list[Rollouts] = []
    rows, students = [], []
    for i in range(options.iterations):
        beta = 1.0 if i == 0 else options.beta0 * 0.5 ** (i - 1)
        data.append(collect(teacher_cfg, teacher_genome, student, fitter.student_genome, beta=beta, options=options,
                            key=(seed, i)))
        ticks = int(sum(d.alive.sum() for d in data))
        rmse = fitter.fit(data, progress=lambda s, e: (done(i * options.steps + s),
                                                       say(f"iteration {i + 1}/{options.iterations}: step {s}/{options.steps}, "
                                                           f"window RMS error {e:.4f} rad")))
        students.append(fitter.student_genome.copy())
        alone = student.build().run(students[-1])
        walk = alone.walk()
        row = dict(iteration=i + 1, teacher_share=beta, ticks=ticks, rms_error=round(rmse, 5), fell=bool(alone.fell[0]),
                   end_time=float(alone.end_time[0]), distance=round(walk["distance"], 3), heading_deg=walk["heading_deg"])
        rows.append(row)
        say(f"iteration {i + 1}/{options.iterations}: teacher share {beta:g}, {ticks} ticks, RMS error {rmse:.4f} rad; "
            f"student alone: {'fell at %.1f s' % row['end_time'] if row['fell'] else 'up %g s' % row['end_time']}, "
            f"{row['distance']:.2f} m")
    chosen = select(student, students, rows, options, say)
    return DistillReport(genome=students[chosen], config=student, iterations=rows, chosen=chosen + 1)


def select(student: EpisodeConfig, genomes: list[np.ndarray], rows: list[dict], options: DistillOptions,
           say: Callable[[str], None]) -> int:
    """The index of the best student (:func:`evobiped.selection.best_candidate` over their runs alone); adds ``up_long``
    (bool: up through ``select_seconds``) to the row of every student."""
    if options.select_seconds <= 0:
        return len(genomes) - 1
    trials = try_candidates(student, np.array(genomes), options.select_seconds)
    for row, t in zip(rows, trials):
        row["up_long"] = bool(t.get("up_long", False))
    best = best_candidate(trials, options.heading_limit)
    say(f"selected iteration {best + 1}'s student (up {options.select_seconds:g} s: "
        + ", ".join(f"{i + 1}: {'yes' if r['up_long'] else 'no'}" for i, r in enumerate(rows)) + ")")
    return best


def parse_options(values: dict) -> DistillOptions:
    """``DistillOptions`` from a table (a ``[distill]`` config section); one ConfigError line for a bad value."""
    return parse(DistillOptions, values, "distill")
