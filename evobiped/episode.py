"""One episode = body + controller + task, run for a whole population at once.

Control ticks at the controller's period (0.02 s for the CTRNN) over finer
physics steps stepped in C (``mujoco.batch``); bodies with custom forces (the
Taga ground) get them before every physics step.  A walker's episode ends at
``seconds`` or when it falls; a simulation that blows up counts as a fall.
Row p of every result depends only on genome p: the same genome gives the
bit-identical fitness alone or inside any batch.
"""

from __future__ import annotations

import copy
import dataclasses
from dataclasses import dataclass, field
from typing import Any, Callable, Protocol

import numpy as np

from .bodies import BODIES
from .bodies.base import Body
from .controllers import CONTROLLERS
from .episode_result import EpisodeResult
from .contract import Offer, normaliser, wire
from .frame import StanceFrame, flips
from .normaliser import SenseSums
from .controllers.base import Controller
from .errors import ConfigError
from .genome import GenomeLayout
from .options import given, parse, refuse_unknown
from .validate import number
from .mapping import MAPS, to_action
from . import gait
from .perturb import PerturbationOptions, Trials, assist_torque
from .sim import Sims
from .tasks import TASKS
from .tasks.base import Task


#: the most control ticks, and physics steps, one walker's episode may take
MAX_TICKS = 10**7
MAX_STEPS = 10**8


def check_timing(body: Body, controller: Controller | None, seconds: float, *,
                 control_dt: float | None = None) -> tuple[float, int]:
    """``(control period in s, physics steps per control tick)`` of an episode of ``seconds`` s; ConfigError
    when the controller's outputs do not map onto the body's actions, the period is no multiple of the
    physics step, or the episode is not 1 to MAX_TICKS ticks and at most MAX_STEPS physics steps per walker.
    Without a controller (actions from outside) the period is ``control_dt``."""
    if controller is None:
        if control_dt is None:
            raise ConfigError("an episode without a controller needs its control period (control_dt)")
        number(control_dt, "control_dt:", above=0, unit="s")
        dt = float(control_dt)
    else:
        if (controller.output_kind, body.action_kind) not in MAPS:
            raise ConfigError(
                f"controller {controller.name!r} gives {controller.output_kind} outputs, which body {body.name!r} cannot take as {body.action_kind}s"
            )
        dt = controller.dt if controller.dt is not None else body.timestep
    ratio = dt / body.timestep
    if abs(ratio - round(ratio)) > 1e-9 or round(ratio) < 1:
        raise ConfigError(f"control period {dt} s is not a multiple of the physics step {body.timestep} s")
    ticks = seconds / dt
    if not 1 <= round(ticks) <= MAX_TICKS:
        raise ConfigError(f"episode seconds = {seconds!r} gives {ticks:.3g} control ticks of {dt:g} s; "
                          f"an episode needs 1 to {MAX_TICKS:.0e}")
    if round(ticks) * round(ratio) > MAX_STEPS:
        raise ConfigError(f"an episode of {seconds:g} s at a physics step of {body.timestep:g} s takes "
                          f"{round(ticks) * round(ratio):.3g} steps per walker, more than {MAX_STEPS:.0e}")
    return dt, int(round(ratio))


@dataclass(frozen=True, kw_only=True)
class EpisodeConfig:
    """What to simulate: registry names, their options, and the episode length (s).

    The options are given as tables (a config file's, keyword settings) or as parsed objects; each table
    is parsed once, here, into its component's frozen ``Options`` (``body_options``: the body's,
    ``controller_options``: the controller's, with the options every controller takes, ``task_options``:
    the task's, ``perturbations``: :class:`PerturbationOptions`), which the parts are built from.
    :meth:`to_dict` writes back the settings the tables gave.
    """

    body: str = "reil"
    controller: str = "ctrnn"
    task: str = "walk"
    seconds: float = 50.0
    #: end a walker's episode when it falls (False: run to the end; only blow-ups stop, e.g. for benchmarks)
    stop_on_fall: bool = True
    body_options: Any = field(default_factory=dict)
    controller_options: Any = field(default_factory=dict)
    task_options: Any = field(default_factory=dict)
    #: how an evolutionary run perturbs each generation (see evobiped.perturb); {} = none
    perturbations: Any = field(default_factory=dict)

    def __post_init__(self):
        for kind, name, reg in (("body", self.body, BODIES), ("controller", self.controller, CONTROLLERS), ("task", self.task, TASKS)):
            if name not in reg:
                raise ConfigError(f"episode.{kind}: unknown {kind} {name!r} (choose from {', '.join(sorted(reg))})")
        number(self.seconds, "episode.seconds:", above=0, unit="s")
        if not isinstance(self.stop_on_fall, bool):
            raise ConfigError(f"episode.stop_on_fall: must be true or false, got {self.stop_on_fall!r}")
        for name, cls in (("body_options", BODIES[self.body].Options), ("controller_options", CONTROLLERS[self.controller].Options),
                          ("task_options", TASKS[self.task].Options), ("perturbations", PerturbationOptions)):
            object.__setattr__(self, name, parse(cls, getattr(self, name), f"episode.{name}"))

    def to_dict(self) -> dict:
        """The config as a table (config.json, genome files): every option table as its settings were given."""
        d = {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}
        for name in ("body_options", "controller_options", "task_options", "perturbations"):
            d[name] = copy.deepcopy(given(d[name]))
        return d

    @property
    def perturbed(self) -> bool:
        """The config perturbs its episodes (it has a perturbations table)."""
        return bool(given(self.perturbations)) or self.perturbations.active

    @property
    def latency(self) -> int:
        """Control ticks by which the controller's actions reach the body late."""
        return int(self.controller_options.latency)

    def nominal(self) -> "EpisodeConfig":
        """The same episode without perturbations (replays, the robustness battery)."""
        return dataclasses.replace(self, perturbations={})

    def parts(self) -> tuple[Body, Controller, Task]:
        """The body, controller and task, the controller wired to the sensors it needs: the controller
        contract checked (one ConfigError line on a mismatch); no model is compiled.  Built once per config
        and shared by :meth:`layout` and every :meth:`build` (parts keep no episode state: that is the
        :class:`EpisodeState`'s, and an episode binds its own copy of the controller)."""
        cached = self.__dict__.get("_parts")
        if cached is None:
            cached = self._make_parts()
            object.__setattr__(self, "_parts", cached)
        return cached

    def __getstate__(self) -> dict:
        """Pickled and copied without the built parts (a worker builds its own)."""
        return {k: v for k, v in self.__dict__.items() if k != "_parts"}

    def _make_parts(self) -> tuple[Body, Controller, Task]:
        body = BODIES[self.body](self.body_options)
        task = TASKS[self.task](self.task_options)
        cls, opts = CONTROLLERS[self.controller], self.controller_options
        added = task.sensor_widths()
        offer = Offer(body.actuators, {**body.sensor_widths, **added}, tuple(added), {**body.sensor_norms, **task.sensor_norms()})
        inputs = wire(cls.needs(opts), offer, chosen=opts.inputs,
                      what=f"controller {self.controller!r} (body {self.body!r}, task {self.task!r})")
        controller = cls(opts, n_outputs=len(body.actuators), inputs=inputs, actuators=body.actuators)
        where = "episode.controller_options"
        if controller.normalises_inputs:
            controller.input_norm = normaliser(inputs, offer.norms)
        if opts.input_norm is not None:
            width = sum(inputs.values())
            if not controller.normalises_inputs:
                raise ConfigError(f"{where}.input_norm: controller {self.controller!r} reads raw senses here (it does not normalise its inputs)")
            if len(opts.input_norm["mean"]) != width:
                raise ConfigError(f"{where}.input_norm: normalises {len(opts.input_norm['mean'])} inputs; the controller reads "
                                  f"{width} ({', '.join(f'{n} {w}' for n, w in inputs.items())})")
            controller.input_norm = (np.array(opts.input_norm["mean"], float), np.array(opts.input_norm["std"], float))
        if opts.frame == "stance":
            if body.actuator_mirror is None or body.contact_sensor is None:
                raise ConfigError(f"{where}.frame: 'stance' needs a bilateral body with foot contacts; body {self.body!r} "
                                  "declares no left/right mirror")
            controller.frame = StanceFrame(inputs, {**body.mirror, **task.sensor_mirror()}, body.actuator_mirror,
                                           what=f"{where}.frame")
        if "genes" in given(opts):
            try:
                controller.override_genes(opts.genes)
            except ConfigError as exc:
                raise ConfigError(f"episode.controller_options.{exc}") from None
        check_timing(body, controller, float(self.seconds))
        if body.action_kind != "position":  # offsets and noise are PD-target angles: a body of torques has none
            from .options import scheduled

            for name in ("target_offset", "target_noise"):
                s = scheduled(self.perturbations, name)
                if s.start or s.end:
                    raise ConfigError(f"episode.perturbations.{name}: disturbs PD targets (rad); body {self.body!r} is driven "
                                      f"by {body.action_kind}s and has none")
        return body, controller, task

    def check(self) -> None:
        """Every value checked in this process, without compiling a model: the options, the controller
        contract, the output mapping and the episode's length in control ticks and physics steps (what a worker
        building the episode would refuse); one ConfigError line otherwise."""
        self.parts()

    def layout(self) -> GenomeLayout:
        """The genome layout of this episode's controller, from the declarations alone (no simulation)."""
        return self.parts()[1].layout

    def build(self) -> "Episode":
        """The episode, its model compiled once."""
        body, controller, task = self.parts()
        return Episode(body, controller, task, seconds=float(self.seconds), stop_on_fall=bool(self.stop_on_fall),
                       perturbations=self.perturbations if self.perturbations.active else None, latency=self.latency)


#: ``pose(sims, ids)``: moves rows ``ids`` off the body's initial pose (and calls ``sims.forward(ids)``)
Pose = Callable[[Sims, np.ndarray], None]


class Listener(Protocol):
    """Watches an episode (recording, figures); never changes it."""

    def start(self, episode: "Episode", sims: Sims) -> None: ...
    def tick(self, t: float, sims: Sims, ids: np.ndarray, neurons: np.ndarray, action: np.ndarray, task_state: dict) -> None: ...
    def end(self, result: EpisodeResult) -> None: ...


class Listeners:
    """Several listeners as one (e.g. one recorder per presentation)."""

    def __init__(self, *listeners: Listener):
        self.listeners = listeners

    def start(self, episode, sims):
        for x in self.listeners:
            x.start(episode, sims)

    def tick(self, t, sims, ids, neurons, action, task_state):
        for x in self.listeners:
            x.tick(t, sims, ids, neurons, action, task_state)

    def end(self, result):
        for x in self.listeners:
            x.end(result)


@dataclass(eq=False, kw_only=True)
class EpisodeState:
    """A batch of simulations part-way through an episode (:meth:`Episode.start`, :meth:`Episode.advance`).

    Every per-row array is ``(n,)`` over the simulation rows of :meth:`Episode.run`.  A state is a
    value: it owns its simulations (and the body's state kept in them), so two states never share
    anything, and :meth:`copy` forks it: both copies continue independently, each exactly as a
    fresh run would.
    """

    sims: Sims
    #: decoded genomes, one row per simulation (an experiment may change them between advances)
    params: dict[str, np.ndarray]
    #: the controller's state (see :meth:`Controller.initial_state`)
    controller: Any
    #: the task's state (see :class:`evobiped.tasks.base.Task`)
    task: dict[str, Any]
    alive: np.ndarray
    fell: np.ndarray
    unstable: np.ndarray
    #: s: when each row fell, the planned length while it is up
    end_time: np.ndarray
    start_position: np.ndarray
    start_facing: np.ndarray
    #: s per control tick
    control_dt: float
    #: the planned length in control ticks
    n_ticks: int
    #: control ticks simulated so far
    ticks: int = 0
    trials: Trials | None = None
    #: each row's trial ``(n,)``, its noise stream, its actuator-target offsets ``(n, n_act)`` rad or None
    trial: np.ndarray | None = None
    noise: Any = None
    offset: np.ndarray | None = None
    #: a push force is on some trunk now
    pushed: bool = False
    #: the actions computed but not yet applied, oldest first (``Episode.latency`` > 0)
    pending: list = field(default_factory=list)
    #: the tick at which each row began ``(n,)`` (0; later for a row :meth:`Episode.restart` began anew)
    born: np.ndarray = field(default_factory=lambda: np.zeros(0, int))
    #: N m/rad: each row's pelvis assistance ``(n,)`` (None: none; see :mod:`evobiped.perturb`)
    assist: np.ndarray | None = None
    #: ``(centre (k,), scale (k,))`` the controller's inputs are normalised with in this episode (None: the controller's)
    norm: tuple | None = None
    #: per row: control ticks, sums and sums of squares of the inputs it sensed ``(n,)``, ``(n, k)``, ``(n, k)``
    #: (None: not collected; :mod:`evobiped.normaliser`)
    senses: tuple | None = None

    @property
    def time(self) -> float:
        """Simulated time so far, s."""
        return self.ticks * self.control_dt

    def copy(self) -> "EpisodeState":
        """An independent state equal to this one (simulations, controller, task, noise streams)."""
        return copy.deepcopy(self)


class Episode:
    """A body, a controller and a task with the model compiled once; run many times."""

    def __init__(self, body: Body, controller: Controller | None, task: Task, *, seconds: float, stop_on_fall: bool = True,
                 perturbations: PerturbationOptions | None = None, latency: int = 0, control_dt: float | None = None):
        """``controller`` None: the actions come from outside (:meth:`step`, the Gymnasium environments), one
        every ``control_dt`` s (a multiple of the body's physics step)."""
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
        self._models: dict[tuple, Any] = {}
        self._trunk = self.model.body(body.trunk).id
        # qpos address of each actuated joint, in action order (initial-pose noise)
        self._act_qadr = self.model.jnt_qposadr[self.model.actuator_trnid[:, 0]]

    @property
    def n_ticks(self) -> int:
        return int(round(self.seconds / self.control_dt))

    def sims(self, n: int, *, friction: float | None = None, slope: float = 0.0, slope_direction: float = 0.0) -> Sims:
        """A new batch of ``n`` simulations (each :meth:`start` owns one), on the model with this ground: floor
        ``friction``, and a ``slope`` (grade, rise over run) rising towards ``slope_direction`` (rad from +x, the
        walker's initial facing, towards +y, its left)."""
        key = (friction, slope, slope_direction if slope else 0.0)
        if key not in self._models:
            model = self.model
            if friction is not None or slope:
                model = copy.deepcopy(self.model)
                if friction is not None:
                    if self.body.floor_geom is None:
                        raise ConfigError(f"body {self.body.name!r} has no MuJoCo ground whose friction a trial could change")
                    model.geom_friction[model.geom(self.body.floor_geom).id, 0] = friction
                if slope:  # an inclined plane: gravity tilted down the slope, away from where the floor rises
                    g = float(np.linalg.norm(self.model.opt.gravity))
                    a = np.arctan(slope)
                    c, s = (0.0 if abs(v) < 1e-12 else float(v) for v in (np.cos(slope_direction), np.sin(slope_direction)))  # exact on the axes
                    model.opt.gravity[:] = (-g * np.sin(a) * c, -g * np.sin(a) * s if s else 0.0, -g * np.cos(a))
            self._models[key] = model
        return Sims(self._models[key], n)

    def trials_for(self, key: tuple[int, int] | None) -> Trials | None:
        """The perturbed presentations of generation key = (run seed, generation); None: nominal."""
        drawn = self.task.draw_sources(key) if key is not None and hasattr(self.task, "draw_sources") else None
        if key is None or (self.perturbations is None and drawn is None):
            return None
        n_act = len(self.body.actuator_names)
        trials = Trials.nominal(1, n_act) if self.perturbations is None else self.perturbations.draw(
            key, seconds=self.seconds, n_actuators=n_act, n_genes=None if self.controller is None else self.controller.layout.size)
        trials.sources = drawn  # a task's random sources of this generation (the steer task's), shared by every genome
        return trials

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
            params = self.controller.decode(self.controller.layout.jitter(rows, trials.gene_noise[np.arange(len(rows)) // S % R]))
            P = len(rows)
        else:
            params = self.controller.decode(genomes)
            if S * R > 1:
                params = {k: np.repeat(v, S * R, axis=0) for k, v in params.items()}
            P = next(iter(params.values())).shape[0]
        n_ticks = self.n_ticks if seconds is None else int(round(seconds / self.control_dt))
        body = self.body
        sims = self.sims(P) if trials is None else self.sims(P, friction=trials.friction, slope=trials.slope,
                                                              slope_direction=trials.slope_direction)
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
        tstate["end_time"], tstate["seconds"] = end_time, n_ticks * self.control_dt
        ctx = context or Context()
        if ctx.weights is not None:
            tstate["weights"] = dict(ctx.weights)
        k = self.controller.n_inputs if self.controller is not None and hasattr(self.controller, "n_inputs") else None
        return EpisodeState(
            sims=sims, params=params, task=tstate,
            controller=None if self.controller is None else self.controller.initial_state(params),
            alive=np.ones(P, bool), fell=np.zeros(P, bool), unstable=np.zeros(P, bool), end_time=end_time,
            start_position=body.planar_position(sims).copy(), start_facing=body.heading(sims).copy(),
            control_dt=self.control_dt, n_ticks=n_ticks, trials=trials, trial=trial, born=np.zeros(P, int),
            noise=trials.noise() if trials is not None else None,
            offset=trials.target_offset[trial] if trials is not None and trials.target_offset.any() else None,
            assist=trials.assist[trial] if trials is not None and trials.assist is not None else None,
            norm=ctx.norm,
            senses=(np.zeros(P), np.zeros((P, k)), np.zeros((P, k))) if ctx.observe and k is not None else None,
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
        params, alive = st.params, st.alive
        P = len(alive)
        for _ in range(n):
            if not alive.any():
                break
            neurons = ctrl.neuron_outputs(params, st.controller)
            inputs, flip = self._inputs(st, P)
            st.controller, out = ctrl.step(params, st.controller, inputs)
            action = to_action(ctrl.output_kind, self.low, self.high, self.body.action_kind, out)
            if flip is not None:
                action = ctrl.frame.actions(action, flip)
            self.step(st, action, neurons=neurons, listener=listener)
        return state

    def step(self, state: EpisodeState, action: np.ndarray, *, neurons: np.ndarray | None = None,
             listener: Listener | None = None, rows: np.ndarray | None = None) -> np.ndarray:
        """One control tick of ``state``, in place: ``action`` ``(n, n_act)`` (rad targets or N m torques, the
        body's action kind; a controller's, or an agent's from outside) for every row, the rows that are up
        take it after the episode's perturbations and latency; then the physics, the task's bookkeeping
        (``neurons`` ``(n, k)``: the controller's outputs the task may read; default none) and the falls.
        ``rows``: only these take the tick (default all; a row that is down never does).  Returns the rows
        that were stepped."""
        body, task, sims, st = self.body, self.task, state.sims, state
        tstate, alive, trials, trial = st.task, st.alive, st.trials, st.trial
        k = st.ticks
        ids = np.flatnonzero(alive) if rows is None else rows[alive[rows]]
        if neurons is None:
            neurons = np.zeros((len(alive), 0))
        if trials is not None:
            jitter = st.noise.next()
            if st.offset is not None or jitter is not None:
                disturbed = action + st.offset if st.offset is not None else action.copy()
                if jitter is not None:
                    disturbed += jitter[trial]
                action = np.clip(disturbed, self.low, self.high)
            if trials.push_start.size > 0:
                force = trials.push_at(k * self.control_dt)  # (R, 3) N
                if st.pushed or force.any():  # write only while a push is on or just ended
                    sims.xfrc_applied[:, self._trunk, :3] = force[trial]
                    st.pushed = bool(force.any())
        if self.latency:
            st.pending.append(action)
            action = st.pending[0] if len(st.pending) <= self.latency else st.pending.pop(0)
        body.apply(sims, ids, action[ids])
        bad = self._advance(sims, ids) if st.assist is None else self._assisted(sims, ids, st.assist[ids], trials.assist_damping)
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
        return ids

    def result(self, state: EpisodeState) -> EpisodeResult:
        """The outcome of ``state`` so far, one entry per genome (see :meth:`run`)."""
        task, S = self.task, self.task.presentations
        tstate = state.task
        result = EpisodeResult(
            fitness=task.fitness(tstate),
            fell=state.fell.copy(),
            unstable=state.unstable.copy(),
            end_time=state.end_time.copy(),
            start_position=state.start_position.copy(),  # copies: a later restart writes into the state's
            end_position=task.end_position(self.body, state.sims, tstate).copy(),
            start_facing=state.start_facing.copy(),
            terms=task.terms(tstate),
            senses=None if state.senses is None else dict(zip(("count", "total", "squares"), (a.copy() for a in state.senses))),
        )
        trials = state.trials
        if trials is not None:
            R = trials.R
            result = result.per_genome(S * R, lambda f: trials.combine(task.combine(f.reshape(-1, S)).reshape(-1, R)))
        elif S > 1:
            result = result.per_genome(S, task.combine)
        return result

    def _inputs(self, st: EpisodeState, P: int) -> tuple[np.ndarray, np.ndarray | None]:
        """The controller's inputs ``(P, k)`` now (in its frame, normalised if it normalises) and the rows whose
        senses and actions its stance frame mirrors (None: no frame).  Collects the senses of rows that are up."""
        ctrl, sims = self.controller, st.sims
        frame = getattr(ctrl, "frame", None)
        flip = None if frame is None else flips(gait.read(self.body.contacts(sims), sims)["stance_leg"])
        names = ctrl.input_names
        if not names:
            return np.zeros((P, 0)), flip
        available = self.task.sensors(self.body, sims, st.task)
        if any(n not in available for n in names):  # body sensors only when the controller reads one
            available = {**self.body.sensors(sims), **available}
        x = np.concatenate([available[n] for n in names], axis=1)
        if flip is not None:
            x = frame.inputs(x, flip)
        if st.senses is not None:
            count, total, squares = st.senses
            if st.alive.all():
                count += 1
                total += x
                squares += x * x
            else:
                up = st.alive
                count[up] += 1
                total[up] += x[up]
                squares[up] += x[up] * x[up]
        norm = st.norm if st.norm is not None else ctrl.input_norm
        return (x if norm is None else (x - norm[0]) / norm[1]), flip

    def _advance(self, sims: Sims, ids: np.ndarray) -> np.ndarray:
        """One control period of physics for ``ids``; bool mask of blow-ups."""
        return self.body.advance(sims, ids, self.substeps)

    def _assisted(self, sims: Sims, ids: np.ndarray, stiffness: np.ndarray, damping: float) -> np.ndarray:
        """:meth:`_advance` with the pelvis assistance (``stiffness`` ``(len(ids),)`` N m/rad) set on the trunk before
        every physics step."""
        bad = np.zeros(len(ids), bool)
        b = self._trunk
        for _ in range(self.substeps):
            sims.xfrc_applied[ids, b, 3:] = assist_torque(stiffness, damping, sims.xmat[ids, b], sims.cvel[ids, b, :3])
            bad |= self.body.advance(sims, ids, 1)
        return bad


@dataclass(frozen=True)
class Context:
    """What a run sets for one generation's episodes, beyond the config: the inputs' normaliser
    ``(centre (k,), scale (k,))`` (None: the controller's own), whether to collect the senses visited
    (``EpisodeResult.senses``), fitness weights by term for a task whose fitness weighs its terms (None:
    the task's own) and the episodes' length."""

    norm: tuple | None = None
    observe: bool = False
    weights: dict | None = None
    #: control ticks of senses behind ``norm`` (recorded with it in genome files)
    norm_count: float = 0.0
    #: s: the episodes' length (None: the episode's own)
    seconds: float | None = None

    @property
    def empty(self) -> bool:
        """Nothing beyond the config (a plain run's: its evaluations need no context)."""
        return self.norm is None and not self.observe and self.weights is None and self.seconds is None


def sense_sums(result: EpisodeResult, rows: np.ndarray) -> SenseSums:
    """What genomes ``rows`` sensed in an episode run with ``Context(observe=True)``, all presentations together."""
    count, total, squares = (result.senses[k] for k in ("count", "total", "squares"))
    return SenseSums(float(count[rows].sum()), total[rows].sum(axis=0), squares[rows].sum(axis=0))


def build_episode(**config: Any) -> Episode:
    """Convenience: ``build_episode(body="reil", seconds=10)``."""
    return EpisodeConfig(**refuse_unknown(EpisodeConfig, config, "episode")).build()
