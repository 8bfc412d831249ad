"""The one loop: :class:`Episode` runs a body, a controller and a task for a whole population (see the package's
docstring): :meth:`Episode.step` is one control tick, :meth:`Episode.advance` a controller's actions through it."""

from __future__ import annotations

import numpy as np

from ..bodies.base import Body
from ..controllers.base import Controller
from ..core.errors import ConfigError
from ..core.kernel import compiled
from ..interface.mapping import to_action
from ..physics import gait
from ..physics.gait_lab import stacked
from ..physics.perturb import PerturbationOptions
from ..physics.trials import Trials
from ..physics.sim import Sims
from ..tasks.base import Task
from .disturbances import assisted_physics, disturb, draw_trials
from .grounds import Grounds
from .listener import Listener
from .result import EpisodeResult
from .senses import SensePlan
from .state import Context, Disturbances, EpisodeState, Pose, RowSenses
from .timing import check_timing


class Episode:
    """A body, a controller and a task with the model compiled once; run many times."""

    def __init__(self, body: Body, controller: Controller | None, task: Task, *, seconds: float,
                 stop_on_fall: bool = True,
                 perturbations: PerturbationOptions | None = None, latency: int = 0, control_dt: float | None = None,
                 kernel: str = "auto"):
        """``controller`` None: the actions come from outside (:meth:`step`, the Gymnasium environments), one
        every ``control_dt`` s (a multiple of the body's physics step).  ``kernel``: the tick's array work compiled
        or in NumPy (:mod:`evobiped.core.kernel`; the same numbers)."""
        self.body, self.controller, self.task = body, controller, task
        #: control ticks by which each action reaches the body late (a real controller's computation and
        #: transmission delay; the first action is held until the pipeline is full)
        self.latency = int(latency)
        self.seconds = float(seconds)
        self.stop_on_fall = stop_on_fall
        self.perturbations = perturbations
        dt, self.substeps = check_timing(body, controller, self.seconds, control_dt=control_dt)
        self.model = body.build_model()
        task.bind_model(self.model)
        self.low, self.high = body.action_bounds()
        self.control_dt = dt
        # the controller told its period: a bound copy, the caller's controller unchanged
        self.controller = None if controller is None else controller.bound(dt)
        #: whether the tick's array work runs compiled (ConfigError for a kernel that cannot run here)
        self.compiled = compiled(kernel)
        if self.compiled and self.controller is not None:
            self.controller = self.controller.compiled()
        self.grounds = Grounds(body, self.model)
        self._trunk = self.model.body(body.trunk).id
        # qpos address of each actuated joint, in action order (initial-pose noise)
        self._act_qadr = self.model.jnt_qposadr[self.model.actuator_trnid[:, 0]]
        #: what the controller reads each tick (None: no controller), and whether the task reads its neuron outputs
        #: (else they are computed only for a listener): planned once
        self.senses = None if self.controller is None else SensePlan(body, self.controller, task)
        self._task_reads_neurons = task.reads_neurons()
        self._task_reads_steps = task.reads_feet_steps()
        #: the whole episode compiled (:mod:`.compiled.whole`) for each model a batch runs on (the episode's, its
        #: grounds'), made on first use where the kernel is compiled
        self._whole: dict[int, object] = {}

    @property
    def n_ticks(self) -> int:
        return int(round(self.seconds / self.control_dt))

    def sims(self, n: int, *, friction: float | None = None, slope: float = 0.0, slope_direction: float = 0.0,
             gravity: float = 1.0) -> Sims:
        """A new batch of ``n`` simulations (each :meth:`start` owns one) on this ground (:meth:`Grounds.sims`)."""
        return self.grounds.sims(n, friction=friction, slope=slope, slope_direction=slope_direction, gravity=gravity)

    def trials_for(self, key: tuple[int, int] | None) -> Trials | None:
        """The perturbed presentations of generation key = (run seed, generation); None: nominal
        (:func:`draw_trials`)."""
        return draw_trials(self.perturbations, self.task, key, seconds=self.seconds,
                           n_actuators=len(self.body.actuator_names),
                           n_genes=None if self.controller is None else self.controller.layout.size)

    def run(self, genomes: np.ndarray, *, seconds: float | None = None, listener: Listener | None = None,
            trials: Trials | None = None, context: "Context | None" = None) -> EpisodeResult:
        """Simulate every genome ``(P, G)`` (or one ``(G,)``); returns fitness and outcome.

        A task with S presentations runs each genome S times side by side, and
        ``trials`` (R perturbed presentations) multiply them: row
        (p * R + r) * S + j is genome p under trial r and task presentation j.
        The listener sees all rows; the result has one entry per genome, its
        fitness combined over j by the task, then over r by the trials' aggregate.
        ``run`` is :meth:`start`, :meth:`advance` over the whole length, :meth:`result`; ``context``: what a run
        sets per generation (:class:`Context`).
        """
        if seconds is None and context is not None:
            seconds = context.seconds
        state = self.start(genomes, seconds=seconds, trials=trials, context=context)
        if listener is not None:
            listener.start(self, state.sims)
        self.advance(state, ticks=state.n_ticks, listener=listener)
        result = self.result(state)
        if listener is not None:
            listener.end(result)
        return result

    def start(self, genomes: np.ndarray | int, *, seconds: float | None = None, trials: Trials | None = None,
              pose: Pose | None = None, context: "Context | None" = None) -> EpisodeState:
        """Every genome ``(P, G)`` (or one ``(G,)``) at t = 0, rows as in :meth:`run`; ``seconds`` (default the
        episode's) is the planned length: each row's end time until it falls, and the task's ``seconds``.
        An episode without a controller takes the number of simulation rows instead of genomes (row i has
        the task's presentation i mod S and trial i // S mod R).  ``pose(sims, ids)``
        moves rows ``ids`` off the body's initial pose before the task starts (and calls ``sims.forward``)."""
        S = self.task.presentations
        R = 1 if trials is None else trials.R
        if self.controller is None:
            params: dict[str, np.ndarray] = {}
            P = int(genomes)
        elif trials is not None and trials.gene_noise is not None:  # every row its own genome: its trial's gene noise
            rows = np.repeat(np.atleast_2d(self.controller.layout.validate(genomes)), S * R, axis=0)
            params = self.controller.decode(self.controller.layout.jitter(rows,
                                                                          trials.gene_noise[np.arange(len(
                                                                              rows)) // S % R]))
            P = len(rows)
        else:
            params = self.controller.decode(genomes)
            if S * R > 1:
                params = {k: np.repeat(v, S * R, axis=0) for k, v in params.items()}
            P = next(iter(params.values())).shape[0]
        n_ticks = self.n_ticks if seconds is None else int(round(seconds / self.control_dt))
        body = self.body
        sims = self.sims(P) if trials is None else self.sims(P, friction=trials.friction, slope=trials.slope,
                                                              slope_direction=trials.slope_direction,
                                                              gravity=trials.gravity)
        body.reset(sims)
        trial = np.arange(P) // S % R  # each row's trial
        if trials is not None and trials.pose_offset is not None and trials.pose_offset.any():
            sims.qpos[:, self._act_qadr] += trials.pose_offset[trial]
            sims.forward()
        if pose is not None:
            pose(sims, np.arange(P))
        end_time = np.full(P, n_ticks * self.control_dt)
        tstate = self.task.start(body, sims)
        if trials is not None and trials.sources is not None:
            self.task.take_sources(tstate, trials.sources)
        # the task sees when each walker's episode ends: the full length until it falls (so a
        # fitness read mid-episode, e.g. by a recording, counts a walker still up as up to the end)
        tstate.end_time, tstate.seconds = end_time, n_ticks * self.control_dt
        ctx = context or Context()
        if ctx.weights is not None:
            tstate.weights = dict(ctx.weights)
        k = None if self.controller is None else self.controller.n_inputs
        return EpisodeState(
            sims=sims, params=params, task=tstate,
            controller=None if self.controller is None else self.controller.initial_state(params),
            alive=np.ones(P, bool), fell=np.zeros(P, bool), unstable=np.zeros(P, bool), end_time=end_time,
            start_position=body.planar_position(sims).copy(), start_facing=body.heading(sims).copy(),
            control_dt=self.control_dt, n_ticks=n_ticks, born=np.zeros(P, int),
            disturbances=None if trials is None else Disturbances.of(trials, trial), norm=ctx.norm,
            senses=RowSenses.zeros(P, k) if ctx.observe and k is not None else None,
        )

    def restart(self, state: EpisodeState, ids: np.ndarray, *, pose: Pose | None = None) -> EpisodeState:
        """Rows ``ids`` of ``state`` begin anew, in place, while the others go on (a vector environment's
        autoreset): the body's initial state, moved by ``pose`` as in :meth:`start`, the task's bookkeeping
        of those rows from its start, up again with their own clock (:attr:`EpisodeState.born`)."""
        body, sims = self.body, state.sims
        body.reset(sims, ids)
        if pose is not None:
            pose(sims, ids)
        self.task.restart(body, sims, state.task, ids)
        if "gait" in sims.extra:
            gait.restart(body.contacts(sims)[ids], sims, ids)
        state.alive[ids], state.fell[ids], state.unstable[ids] = True, False, False
        state.end_time[ids] = state.n_ticks * self.control_dt
        state.start_position[ids] = body.planar_position(sims)[ids]
        state.start_facing[ids] = body.heading(sims)[ids]
        state.born[ids] = state.ticks
        return state

    def advance(self, state: EpisodeState, seconds: float | None = None, *, ticks: int | None = None,
                listener: Listener | None = None) -> EpisodeState:
        """Continue ``state`` by ``seconds`` (or ``ticks`` control ticks), in place; rows that are down stay
        where they fell, and an all-down batch stops early (its clock stops with it).  Each tick is the
        controller's action (from its inputs) through :meth:`step`, the one loop every episode runs.  Between
        calls an experiment may change ``state.params``, the body's ground or forces on ``state.sims``."""
        n = int(round(seconds / self.control_dt)) if ticks is None else int(ticks)
        ctrl, st = self.controller, state
        if ctrl is None:
            raise ConfigError("this episode has no controller: its actions come from outside (Episode.step)")
        if self.compiled and self._run_whole(st, n, listener):
            return state
        params, alive = st.params, st.alive
        P = len(alive)
        for _ in range(n):
            if not alive.any():
                break
            neurons = ctrl.neuron_outputs(params,
                                          st.controller) if listener is not None or self._task_reads_neurons else None
            inputs, flip = self._inputs(st, P)
            if flip is not None:
                st.controller = ctrl.reframe(st.controller, flip)
            st.controller, out = ctrl.step(params, st.controller, inputs)
            action = to_action(ctrl.output_kind, self.low, self.high, self.body.action_kind, out)
            if flip is not None:
                action = ctrl.frame.actions(action, flip)
            self.step(st, action, neurons=neurons, listener=listener)
        return state

    def _run_whole(self, state: EpisodeState, n: int, listener: Listener | None) -> bool:
        """Whether ``n`` ticks of ``state`` ran in compiled calls (:mod:`.compiled.whole`: the same numbers), where
        its parts allow it and ``n`` is long enough to pay for a call; calls of at most ``CALL_WALKER_TICKS``
        walker-ticks, until every walker is down."""
        from .compiled.scope import unsupported
        from .compiled.whole import CALL_WALKER_TICKS, MIN_TICKS, WholeEpisodes

        if n < MIN_TICKS or unsupported(self, state, listener) is not None:
            return False
        model = state.sims.model
        whole = self._whole.get(id(model))
        if whole is None or whole.model is not model:
            whole = self._whole[id(model)] = WholeEpisodes(self, model)
        chunk = max(MIN_TICKS, CALL_WALKER_TICKS // max(1, len(state.alive)))
        done = 0
        while done < n and state.alive.any():
            ticks = min(n - done, chunk)
            whole.advance(self, state, ticks)
            done += ticks
        return True

    def step(self, state: EpisodeState, action: np.ndarray, *, neurons: np.ndarray | None = None,
             listener: Listener | None = None, rows: np.ndarray | None = None) -> EpisodeState:
        """One control tick of ``state``, in place: ``action`` ``(n, n_act)`` (rad targets or N m torques, the
        body's action kind; a controller's, or an agent's from outside) for every row, the rows that are up
        take it after the episode's perturbations and latency; then the physics, the task's bookkeeping
        (``neurons`` ``(n, k)``: the controller's outputs the task may read; default none) and the falls.
        ``rows``: only these take the tick (default all; a row that is down never does).  Returns ``state``."""
        body, task, sims, st = self.body, self.task, state.sims, state
        tstate, alive, d = st.task, st.alive, st.disturbances
        k = st.ticks
        ids = np.flatnonzero(alive) if rows is None else rows[alive[rows]]
        if neurons is None:
            neurons = np.zeros((len(alive), 0))
        if d is not None:
            action = disturb(d, sims, action, self.low, self.high, self._trunk, k * self.control_dt)
        if self.latency:
            st.pending.append(action)
            action = st.pending[0] if len(st.pending) <= self.latency else st.pending.pop(0)
        body.apply(sims, ids, action[ids])
        # the gait lab's samples after every physics step, for a task or listener that measures them
        samples: list | None = [] if self._task_reads_steps or getattr(listener, "reads_feet_steps", False) else None
        each = None if samples is None else (lambda: samples.append(body.feet(sims)))
        if d is None or d.assist is None:
            bad = self.body.advance(sims, ids, self.substeps, each)
        else:  # the pelvis assistance (N m/rad) on the trunk
            bad = assisted_physics(body, sims, ids, self._trunk, self.substeps, d.assist[ids], d.trials.assist_damping,
                                   each)
        if samples is not None:
            sims.readings["feet_steps"] = stacked(samples)  # what Body.tick_feet hands on until the state changes
        st.ticks = k + 1
        t = (k + 1) * self.control_dt
        if "gait" in sims.extra:  # a controller reads the gait senses
            gait.update(body.contacts(sims)[ids], sims, ids)
        task.on_tick(body, sims, tstate, ids, ~bad, neurons)
        if listener is not None:
            listener.tick(t, sims, ids, neurons, action, tstate)
        down = bad | body.fallen(sims, ids) if self.stop_on_fall else bad
        if down.any():
            st.unstable[ids[bad]] = True
            st.fell[ids[down]] = True
            alive[ids[down]] = False
            st.end_time[ids[down]] = (k + 1 - st.born[ids[down]]) * self.control_dt
        return state

    def result(self, state: EpisodeState) -> EpisodeResult:
        """The outcome of ``state`` so far, one entry per genome (see :meth:`run`): copies, which nothing done to the
        state later changes."""
        task, S = self.task, self.task.presentations
        tstate = state.task
        result = EpisodeResult(
            fitness=np.array(task.fitness(tstate)),
            fell=state.fell.copy(),
            unstable=state.unstable.copy(),
            end_time=state.end_time.copy(),
            start_position=state.start_position.copy(),  # copies: a later restart writes into the state's
            end_position=task.end_position(self.body, state.sims, tstate).copy(),
            start_facing=state.start_facing.copy(),
            terms={k: np.array(v) for k, v in task.terms(tstate).items()},
            senses=None if state.senses is None else state.senses.table(),
        )
        trials = None if state.disturbances is None else state.disturbances.trials
        if trials is not None:
            R = trials.R
            result = result.per_genome(S * R, lambda f: trials.combine(task.combine(f.reshape(-1, S)).reshape(-1, R)))
        elif S > 1:
            result = result.per_genome(S, task.combine)
        return result

    def _inputs(self, st: EpisodeState, P: int) -> tuple[np.ndarray, np.ndarray | None]:
        """The controller's inputs now and the rows its stance frame mirrors (:meth:`.senses.SensePlan.read`)."""
        return self.senses.read(st, P)
