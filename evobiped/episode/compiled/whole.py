"""A whole episode in one compiled call: the control ticks of every walker, MuJoCo's stepping included, without
Python and without the GIL (the episode's ``kernel``, :mod:`evobiped.core.kernel`).

:meth:`Episode.advance <evobiped.episode.loop.Episode.advance>` steps the batch in lock step, one control tick of
every walker at a time, with the tick's work in NumPy between MuJoCo calls.  Where the episode's parts are ones this
module knows (:func:`.scope.unsupported` says which are not), the ticks run instead in one numba call
(``@njit(cache=True, nogil=True)``): walker after walker, each its own ``MjData`` stepped through MuJoCo's C entry
points (reached from compiled code at run-time addresses) for all its ticks while its data stay in the cache.  In the
same loop: the senses the controller reads, the stance frame's mirror, the running normaliser's sums and its read,
the controller's step (:mod:`evobiped.controllers.ctrnn_kernel`'s), the output mapping, the gait tracker, the fall
test and the walk task's bookkeeping (its position, its steps, the gait lab's samples).  A thread that runs it holds
no GIL, so threads evaluate in parallel.

What it computes is what the lock-step loop computes, to the last bit (tests hold every supported part to it): the
same MuJoCo calls on the same state (``mj_step2`` then ``mj_step1`` for each physics step, as the persistent batch
runs them), every elementwise expression in NumPy's order, every sum in NumPy's order, every transcendental NumPy's
own loop (:func:`evobiped.core.kernel.ufunc_loop`).  The episode starts and ends in the batch
(:meth:`Episode.start`, :meth:`Episode.result`): each walker's ``MjData`` is loaded from the batch before the ticks;
after them the batch is put in the state before each walker's last physics step and takes that step itself, so every
field it holds (acceleration-stage sensors too) is what the loop would have left, and a later call of either kind
continues from it.  The gait lab's samples are handed to the task's meter as its own ticks would have been.

Known today: the Reil body; a CTRNN, with any of the body's senses and its task's as inputs, in the body or the
stance frame, normalised or not, with or without its direct path, or the SIMBICON-style controller, deaf or hearing;
the walk task with any fitness but the cyclic criterion and the gait measures (its steps and gait-lab terms at either
sampling included); the command task (any schedule, drawn or not); the steer task (its ears, its reach, its gait
terms); presentations whose disturbances end at the start (pose noise, the drawn commands and sources) on any ground;
no disturbance while the episode runs (target noise or offsets, pushes, assistance), no latency, no listener.
Anything else runs the lock-step loop, with the same numbers.
"""

from __future__ import annotations

import mujoco
import numpy as np
from numba import typed

from ...controllers import ctrnn_kernel
from ...controllers.simbicon import Simbicon
from ...core.kernel import jit, ufunc_loop, ufunc_scalar2
from ...physics import gait
from ...physics.sim import FIRST_BAD_WARNING, MAX_SPEED
from ...tasks.steer import SteerTask
from .mujoco_calls import call, entry, read_state, time_of
from . import command_tick, state_arrays
from .readings import SENSES, facing, foot_sample, senses
from .scope import OUTPUT_MAPS
from .simbicon_tick import INPUTS as SIMBICON_INPUTS, simbicon_step

_STATE = int(mujoco.mjtState.mjSTATE_INTEGRATION)
#: the gait lab's sampling: none, the last physics step of each tick, every physics step
_SAMPLING = {None: 0, "control_tick": 1, "physics_step": 2}
#: fewer ticks than this in one call run the lock-step loop (loading and handing back the batch costs about a tick)
MIN_TICKS = 10
#: a call runs at most about this many walker-ticks (a third of a second): signals (Ctrl-C, a run's stop) are handled
#: between calls, and a call's handing back of the batch costs about a tick
CALL_WALKER_TICKS = 12_500


@jit
def _to_action(kind, out, low, high, span, action):
    """The PD targets ``action`` ``(n_act,)`` of the controller's outputs ``out`` by output kind ``kind``
    (:data:`.scope.OUTPUT_MAPS`; :func:`evobiped.interface.mapping.to_action`'s expressions)."""
    for j in range(action.shape[0]):
        o = out[j]
        if kind == 0:
            action[j] = low[j] + o * (high[j] - low[j])
            continue
        if kind == 1:
            y = (o - 0.5) * (high[j] - low[j])
        elif kind == 2:
            y = (o - 0.5) * 2.0 * span[j]
        else:
            y = o
        action[j] = low[j] if y < low[j] else (high[j] if y > high[j] else y)


@jit
def _blew_up(warnings, qvel, qpos):
    """A walker's simulation blew up in its last steps (:meth:`Sims.step <evobiped.physics.sim.Sims.step>`'s test)."""
    for i in range(FIRST_BAD_WARNING, warnings.shape[0]):
        if warnings[i] > 0:
            return True
    for i in range(qvel.shape[0]):
        if not abs(qvel[i]) < MAX_SPEED:
            return True
    for i in range(qpos.shape[0]):
        if not np.isfinite(qpos[i]):
            return True
    return False


@jit
def _episode(funcs, mj, datas, F, body_ids, qadr, dadr, share, radius, knees,
             codes, widths, mirror, norm, observed, ctrnn, kind, bounds, n_ticks, nstep, stop_on_fall, fall,
             tick0, born, control_dt, facing0, tracker, steps, samples, position, alive, fell, unstable, end_time,
             pre, command, steer, simb, ran, first):
    """``n_ticks`` control ticks of every walker that is up, walker after walker (see the module docstring); writes
    the ticks each ran into ``ran`` ``(P,)`` and the simulated time after the first tick of the call into ``first``
    ``(1,)`` (NaN: none ran).  It returns nothing: numba boxes a returned array by running Python, where a pending
    signal (Ctrl-C) would raise inside its wrapper and leave a SystemError instead of the KeyboardInterrupt.

    ``funcs``: the addresses of NumPy's exp, arcsin and arctan2 loops, of its hypot and of its mod loop; ``mj``: of
    mj_step1,
    mj_step2, mj_getState and the mjModel; ``datas`` ``(P,)`` each walker's mjData, at the velocity stage of its
    state; ``F`` a tuple of typed lists of each walker's views of its ``MjData`` fields.  In place: the CTRNN's state,
    the tracker, the steps, the running sums, the gait lab's ``samples`` ``(n_ticks S, P, ...)``, ``position``
    ``(P, 2)`` (the last finite planar position), ``alive``, ``fell``, ``unstable``, ``end_time`` (s), and ``pre``
    ``(P, nstate)``: each walker's integration state before its last physics step; ``command``: whether the task is
    the command task, its schedule (times s, speeds m/s, turning rates rad/s, drawn stretch s or 0), its rows' start
    times ``(P,)``, its arrays (:func:`.command_tick.tick`) and options, all in place; ``steer``: the steer task's
    sources ``(P, 2)`` m, its ears' site ids, its sound limit, its reach m (0: none) and the ticks each walker spent
    within it ``(P,)``, in place; ``simb``: whether the controller is the SIMBICON-style one, its genes, its inputs'
    offsets, its state (stance, time in the swing, targets; in place) and constants (:mod:`.simbicon_tick`)."""
    qpos, qvel, ctrl, xpos, xmat, subtree_com, site_xpos, cvel, xipos, sensordata, geom_xpos, force, avel, warnings = F
    in_perm, in_sign, act_perm, act_sign, framed = mirror
    mean, std, normalised = norm
    count, total, squares, observe = observed
    A, alpha, W, V, tau, substeps, dt, exponential, after, c, D, n_out = ctrnn
    low, high, span = bounds
    fall_height, cos_tilt = fall
    stance, touchdown, lifted, tracked = tracker
    kept_stance, n_steps, counts_steps = steps
    contact, slip, height, knee, power, torque, ticked, sampling = samples
    exp = funcs[0]
    step1, step2, get_state, model = mj[0], mj[1], mj[2], mj[3]
    touch0, touch1, pelvis = body_ids[1], body_ids[2], body_ids[0]
    commands, times, speeds, turns, stretch, t0, kept, options = command
    clock_c, yaw_cmd = kept[0], kept[3]
    sources, ears, sound_limit, reach, near = steer
    simbicon, G, at_in, s_stance, s_t, s_out, hears, s_limit, pcols, rcols, kcols, s_dt = simb
    P = A.shape[0]
    k = codes.shape[0]
    n_in = 0
    for g in range(k):
        n_in += widths[g]
    ran[:] = 0
    first_time = np.nan
    x, xm, xn = np.zeros((1, n_in)), np.zeros(n_in), np.zeros((1, n_in))
    scratch, clock = np.zeros(3), np.zeros(1)
    action = np.zeros(ctrl[0].shape[0])
    o_row = np.zeros(ctrl[0].shape[0])
    for p in range(P):
        if not alive[p]:
            continue
        d = datas[p]
        q, v, u, sens, w = qpos[p], qvel[p], ctrl[p], sensordata[p], warnings[p]
        a, al, Wp, Vp, tp, sp = A[p:p + 1], alpha[p:p + 1], W[p:p + 1], V[p:p + 1], tau[p:p + 1], substeps[p:p + 1]
        cp, Dp = c[p:p + 1] if c.shape[0] else c, D[p:p + 1] if D.shape[0] else D
        now = time_of(get_state, model, d, clock)  # the simulated time now (s), read again after each tick
        for t in range(n_ticks):
            # the inputs, in the stance frame where the controller takes it, summed for a running normaliser
            flip = framed and stance[p] != 0
            v_cmd, w_cmd = command_tick.command_at(times, speeds, turns, stretch, clock_c[p] - t0[p]) if commands else (
                0.0, 0.0)
            if k:
                senses(codes, widths, xm, funcs, q, v, xmat[p], subtree_com[p], site_xpos[p], cvel[p], xipos[p],
                       sens, now, body_ids, qadr, dadr, share, stance[p], touchdown[p],
                       facing0[p], (commands, v_cmd, w_cmd, yaw_cmd[p]), (sources[p], ears, sound_limit), scratch)
                for i in range(n_in):
                    x[0, i] = xm[in_perm[i]] * in_sign[i] if flip else xm[i]
                if observe:
                    count[p] += 1
                    for i in range(n_in):
                        total[p, i] += x[0, i]
                        squares[p, i] += x[0, i] * x[0, i]
                for i in range(n_in):
                    xn[0, i] = (x[0, i] - mean[i]) / std[i] if normalised else x[0, i]
            if simbicon:
                s_stance[p], s_t[p] = simbicon_step(xn[0], at_in, G[p], s_stance[p], s_t[p], hears, s_limit, pcols,
                                                    rcols, kcols, s_dt, o_row)
                for j in range(o_row.shape[0]):
                    s_out[p, j] = o_row[j]
            else:
                a2, out = ctrnn_kernel._step(exp, a, xn, al, Wp, Vp, tp, sp, dt, exponential, after, cp, Dp, n_out)
                a[0, :] = a2[0, :]
                for j in range(o_row.shape[0]):
                    o_row[j] = out[0, j]
            _to_action(kind, o_row, low, high, span, action)
            for j in range(action.shape[0]):
                u[j] = action[act_perm[j]] * act_sign[j] if flip else action[j]
            # the physics, the gait lab's samples after every physics step (or the last)
            for s in range(nstep):
                if s == nstep - 1:
                    read_state(get_state, model, d, pre[p].ctypes.data, _STATE)
                call(step2, model, d)
                call(step1, model, d)
                if sampling == 2 or (sampling == 1 and s == nstep - 1):
                    at = t * nstep + s if sampling == 2 else t
                    foot_sample(funcs, at, p, q, geom_xpos[p], cvel[p], subtree_com[p], force[p], avel[p], body_ids,
                                 radius, knees, contact, slip, height, knee, power, torque)
            ran[p] = t + 1
            now = time_of(get_state, model, d, clock)
            bad = _blew_up(w, v, q)
            if tracked:  # the gait tracker (physics.gait.update), every row that took the tick
                c0, c1 = sens[touch0] > 0, sens[touch1] > 0
                st = stance[p]
                other = c1 if st == 0 else c0
                lift = lifted[p, 1] if st == 0 else lifted[p, 0]
                if other and now - lift >= gait.MIN_AIRBORNE:
                    stance[p], touchdown[p] = 1 - st, now
                lifted[p, 0] = np.inf if c0 else (lifted[p, 0] if lifted[p, 0] < now else now)
                lifted[p, 1] = np.inf if c1 else (lifted[p, 1] if lifted[p, 1] < now else now)
            if not bad:  # the task's bookkeeping of a row stepped and finite
                if commands:
                    fx, fy = facing(xmat[p], pelvis)
                    command_tick.tick(funcs, p, now, fx, fy, xpos[p][pelvis, 0], xpos[p][pelvis, 1],
                                   sens[touch0] > 0 and sens[touch1] > 0, position, kept, options, v_cmd, w_cmd,
                                   scratch)
                if t == 0 and first_time != first_time:
                    first_time = now
                if counts_steps:
                    n_steps[p] += 1.0 if stance[p] != kept_stance[p] else 0.0
                    kept_stance[p] = stance[p]
                if sampling == 2:
                    for s in range(nstep):
                        ticked[t * nstep + s, p] = True
                elif sampling == 1:
                    ticked[t, p] = True
                position[p, 0], position[p, 1] = xpos[p][pelvis, 0], xpos[p][pelvis, 1]
                if reach > 0:
                    dx, dy = position[p, 0] - sources[p, 0], position[p, 1] - sources[p, 1]
                    if np.sqrt(dx * dx + dy * dy) <= reach:
                        near[p] += 1.0
            mp = xmat[p]
            down = bad or (stop_on_fall and (subtree_com[p][pelvis, 2] < fall_height or mp[pelvis, 8] < cos_tilt))
            if down:
                unstable[p] = bad
                fell[p], alive[p] = True, False
                end_time[p] = (tick0 + t + 1 - born[p]) * control_dt
                break
    first[0] = first_time


class WholeEpisodes:
    """One ``MjData`` per walker of an episode's model, kept for the worker's life, and the typed lists of their
    fields the compiled episode reads (built once for each count of walkers)."""

    FIELDS = ("qpos", "qvel", "ctrl", "xpos", "xmat", "subtree_com", "site_xpos", "cvel", "xipos", "sensordata",
              "geom_xpos", "actuator_force", "actuator_velocity")

    def __init__(self, episode, model: mujoco.MjModel):
        self.model = model  # the episode's, or one of its grounds' (another friction, slope or gravity)
        self.datas: list[mujoco.MjData] = []
        self._lists: dict[int, tuple] = {}
        body, m = episode.body, model
        self.body_ids = np.array([body._pelvis, body._touch[0], body._touch[1], body._feet[0], body._feet[1],
                                  body._foot_geoms[0], body._foot_geoms[1], body._foot_bodies[0],
                                  body._foot_bodies[1]], np.int64)
        self.qadr, self.dadr = body._qadr.astype(np.int64), body._dadr.astype(np.int64)
        self.knees = body._knees.astype(np.int64)
        self.share = np.ascontiguousarray(body._mass_share, float)
        self.radius = np.ascontiguousarray(body._foot_radius, float)
        if m.nbody - 1 != len(self.share):
            raise AssertionError("every link is in the pelvis's tree")
        ctrl = episode.controller
        widths = {**body.sensor_widths, **episode.task.sensor_widths()}
        self.codes = np.array([SENSES.index(n) for n in ctrl.input_names], np.int64)
        self.widths = np.array([widths[n] for n in ctrl.input_names], np.int64)
        frame = getattr(ctrl, "frame", None)
        k = int(self.widths.sum())
        n_act = len(body.actuator_names)
        self.mirror = ((frame.input_perm.astype(np.int64), frame.input_sign.astype(float),
                        frame.action_perm.astype(np.int64), frame.action_sign.astype(float), True)
                       if frame is not None else
                       (np.arange(k), np.ones(k), np.arange(n_act), np.ones(n_act), False))
        low, high = episode.low.astype(float), episode.high.astype(float)
        self.bounds = (low, high, np.maximum(np.abs(low), np.abs(high)))
        at = getattr(ctrl, "_at", {})
        self.simbicon_at = np.array([at[name].start if name in at else 0 for name in SIMBICON_INPUTS], np.int64)
        self.funcs = (ufunc_loop(np.exp), ufunc_loop(np.arcsin), ufunc_loop(np.arctan2), ufunc_scalar2(np.hypot),
                      ufunc_loop(np.remainder))
        self.mj = (entry("mj_step1"), entry("mj_step2"), entry("mj_getState"), self.model._address)

    def fields(self, n: int) -> tuple:
        """The addresses ``(n,)`` of the first ``n`` ``MjData`` and typed lists of their fields."""
        got = self._lists.get(n)
        if got is None:
            while len(self.datas) < n:
                self.datas.append(mujoco.MjData(self.model))
            ds = self.datas[:n]

            def listed(f):
                out = typed.List()
                for d in ds:
                    out.append(f(d))
                return out

            views = tuple(listed(lambda d, name=name: getattr(d, name)) for name in self.FIELDS)
            got = self._lists[n] = (np.array([d._address for d in ds], np.int64),
                                    views + (listed(lambda d: d.warning.number),))
        return got

    def advance(self, episode, state, n: int) -> None:
        """``n`` ticks of ``state`` (an :class:`EpisodeState` of ``episode``, which :func:`.scope.unsupported`
        allows), in place, as :meth:`Episode.advance` would run them."""
        sims, ctrl, body, task = state.sims, episode.controller, episode.body, episode.task
        if sims.model is not self.model:
            raise AssertionError("a whole episode runs on the model its MjData were made for")
        P = sims.n
        addresses, F = self.fields(P)
        batch = sims.batch
        for i in range(P):
            batch.get_data(i, self.datas[i])
        S = episode.substeps
        # the gait tracker, begun from the contacts now where anything reads it (as the loop's first read would)
        if getattr(ctrl, "frame", None) is not None or any(SENSES[c] in gait.NAMES for c in self.codes):
            gait.tracker(body.contacts(sims), sims)
        table = sims.extra.get("gait")
        tracker = ((table["stance"], table["touchdown"], table["lifted"], True) if table is not None else
                   (np.zeros(P, np.int64), np.zeros(P), np.zeros((P, 2)), False))
        if tracker[0].dtype != np.int64:
            raise AssertionError("the tracker's stance is int64")
        tstate = state.task
        kept = getattr(tstate, "kept", {})
        steer = isinstance(task, SteerTask)
        steps = ((kept["stance"], kept["steps"], True) if not steer and task.counts_steps else
                 (np.zeros(P, np.int64), np.zeros(P), False))
        meter = tstate.gait_lab if steer else kept.get("gait_lab")
        sampling = _SAMPLING[None if meter is None else meter.sampling]
        T = 0 if meter is None else n * (S if sampling == 2 else 1)
        A = len(body.actuator_names)
        samples = (np.zeros((T, P, 2), bool), np.zeros((T, P, 2)), np.zeros((T, P, 2)), np.zeros((T, P, 2)),
                   np.zeros((T, P, A)), np.zeros((T, P, A)), np.zeros((T, P), bool), sampling)
        k = int(self.widths.sum())
        norm = state.norm if state.norm is not None else ctrl.input_norm
        norm = ((np.ascontiguousarray(norm[0], float) * np.ones(k), np.ascontiguousarray(norm[1], float) * np.ones(k),
                 True) if norm is not None else (np.zeros(k), np.ones(k), False))
        rs = state.senses
        observed = ((rs.count, rs.total, rs.squares, True) if rs is not None else
                    (np.zeros(P), np.zeros((P, k)), np.zeros((P, k)), False))
        params, f = state.params, np.ascontiguousarray
        simbicon = isinstance(ctrl, Simbicon)
        ctrnn, simb = state_arrays.controller(ctrl, state, P, self.simbicon_at)
        facing0 = np.zeros((P, 2)) if steer else f(tstate.facing, float)
        pre = np.zeros((P, mujoco.mj_stateSize(self.model, _STATE)))
        ran, first = np.zeros(P, np.int64), np.full(1, np.nan)
        _episode(
            self.funcs, self.mj, addresses, F, self.body_ids, self.qadr, self.dadr, self.share, self.radius,
            self.knees, self.codes, self.widths, self.mirror, norm, observed, ctrnn, OUTPUT_MAPS[ctrl.output_kind],
            self.bounds, int(n), S, episode.stop_on_fall, (body.fall_height, float(np.cos(body.fall_tilt))),
            int(state.ticks), f(state.born, np.int64), float(episode.control_dt), facing0, tracker, steps, samples,
            tstate.position, state.alive, state.fell, state.unstable, state.end_time, pre,
            state_arrays.commands(task, tstate, n, episode.control_dt), state_arrays.hearing(task, tstate, P), simb,
            ran, first)
        first_time = float(first[0])
        if simbicon:
            state.controller = {"stance": simb[3], "t": simb[4], "out": simb[5]}
        else:
            state.controller = ctrnn[0]
        ticks = int(ran.max(initial=0))
        state.ticks += ticks
        if steer:
            tstate.ticks += ticks
        if meter is not None and ticks:
            per_tick = S if sampling == 2 else 1
            state_arrays.hand_to_meter(meter, samples, ticks * per_tick, per_tick, first_time)
        # the batch takes each walker's last physics step itself: every field it holds is then the loop's
        stepped = np.flatnonzero(ran > 0)
        if len(stepped):
            batch.state[stepped] = pre[stepped]
            sims.forward(stepped)
            batch.step(ids=stepped, nstep=1, stage=mujoco.mjtStage.mjSTAGE_VEL)
            sims.readings.clear()
