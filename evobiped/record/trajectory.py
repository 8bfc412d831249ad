"""Collect one individual's episode, tick by tick, into plain arrays.

:class:`TrajectoryRecorder` is an episode :class:`~evobiped.episode.Listener`:
it only copies what the simulation already computed, so the episode (and
its fitness) are bit-identical with or without it.  The resulting
:class:`Trajectory` feeds the Rerun recording and the figures alike.

Times.  With T control ticks of period dt:

* *state* rows (poses, centre of mass, joint angles) are at t = 0, dt, ..., T dt
  (T + 1 rows: the initial pose, then the pose after each tick);
* *command* rows (neuron outputs, actions) are at t = 0, ..., (T - 1) dt: the
  neurons' outputs at the start of a control period and the action held
  during it (T rows);
* *tick* rows (task sensors, touch, fitness so far) are at t = dt, ..., T dt (T rows).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import mujoco
import numpy as np

_TOUCH = int(mujoco.mjtSensor.mjSENS_TOUCH)


@dataclass
class Trajectory:
    """One individual's episode.  Shapes: T ticks, B bodies, A actuators, N neurons."""

    model: mujoco.MjModel
    body_name: str
    dt: float
    action_kind: str
    actuator_names: tuple[str, ...]
    n_motor: int
    touch_names: list[str]
    state_time: np.ndarray  # (T+1,) s
    body_pos: np.ndarray  # (T+1, B, 3) m
    body_quat: np.ndarray  # (T+1, B, 4) wxyz
    com: np.ndarray  # (T+1, 3) m
    planar: np.ndarray  # (T+1, 2) m
    joint_angle: np.ndarray  # (T+1, A) rad (nan where an actuator has no joint)
    qpos: np.ndarray  # (T+1, nq) the generalised positions (what a video re-poses the model from)
    command_time: np.ndarray  # (T,) s
    neurons: np.ndarray  # (T, N) outputs, motor neurons first
    action: np.ndarray  # (T, A) rad (PD targets) or N m (torques)
    tick_time: np.ndarray  # (T,) s
    fitness: np.ndarray  # (T,) fitness so far
    touch: np.ndarray  # (T, K) touch sensor readings (N), K = len(touch_names)
    touch_pos: np.ndarray  # (T, K, 3) m, where each touch sensor's site is
    sensors: dict[str, np.ndarray] = field(default_factory=dict)  # name -> (T, k)
    source: np.ndarray | None = None  # (T, 2) m, this walker's target (a sound source), if the task has targets
    sources: np.ndarray | None = None  # (S, 2) m, every presentation's target (Task.targets), if it has them
    #: (2,) unit vector: the direction the walker faced at the start (``Body.heading`` after reset)
    start_facing: np.ndarray = field(default_factory=lambda: np.array([1.0, 0.0]))
    final_fitness: float = float("nan")
    #: the controller read and wrote in the stance frame (its motor neuron i drives the stance leg's joint i, not
    #: actuator i), and it has a direct input-to-motor path beside its neurons
    stance_frame: bool = False
    direct_path: bool = False
    fell: bool = False
    end_time: float = float("nan")

    @property
    def n_ticks(self) -> int:
        return len(self.tick_time)


class TrajectoryRecorder:
    """Episode listener that keeps individual ``index`` of the batch; read :attr:`trajectory` after the run."""

    def __init__(self, index: int = 0):
        self.index = int(index)
        self.trajectory: Trajectory | None = None

    # ------------------------------------------------------------ Listener
    def start(self, episode, sims) -> None:
        m = episode.model
        self._episode = episode
        self._joint_qadr = _actuated_qpos(m, episode.body.actuator_names)
        touch = [i for i in range(m.nsensor) if m.sensor_type[i] == _TOUCH]
        self._touch_adr = np.array([m.sensor_adr[i] for i in touch], int)
        self._touch_site = np.array([m.sensor_objid[i] for i in touch], int)
        self._touch_names = [m.sensor(i).name or f"touch{i}" for i in touch]
        self._rows: dict[str, list] = {k: [] for k in ("state", "command", "tick")}
        self._sensors: dict[str, list] = {}
        self._source: list = []
        task = episode.task
        self._sources = task.targets()  # (S, 2) m or None
        if self._sources is not None:
            self._sources = np.asarray(self._sources, float)
            self._target = self._sources[task.presentation_of(sims.n)[self.index]]
        self._facing = np.array(episode.body.heading(sims)[self.index], float)
        self._record_state(0.0, sims)

    def tick(self, t, sims, ids, neurons, action, task_state) -> None:
        p = self.index
        if p not in ids:
            return
        ep = self._episode
        self._rows["command"].append((t - ep.control_dt, neurons[p].copy(), action[p].copy()))
        self._record_state(t, sims)
        fitness = float(ep.task.fitness(task_state)[p])
        sd = sims.sensordata[p]
        self._rows["tick"].append((t, fitness, sd[self._touch_adr].copy(), sims.site_xpos[p, self._touch_site].copy()))
        readings = {**ep.body.sensors(sims), **ep.task.sensors(ep.body, sims, task_state)}
        for name, arr in readings.items():
            self._sensors.setdefault(name, []).append(np.array(arr[p], float))
        if self._sources is not None:
            self._source.append(self._target)

    def end(self, result) -> None:
        ep, p = self._episode, self.index
        result = result.rows if result.rows is not None else result  # this row's own presentation
        st, cmd, tk = self._rows["state"], self._rows["command"], self._rows["tick"]
        n_act = len(ep.body.actuator_names)
        K = len(self._touch_names)
        self.trajectory = Trajectory(
            model=ep.model,
            body_name=ep.body.name,
            dt=ep.control_dt,
            action_kind=ep.body.action_kind,
            actuator_names=tuple(ep.body.actuator_names),
            n_motor=ep.controller.n_outputs,
            stance_frame=getattr(ep.controller, "frame", None) is not None,
            direct_path=bool(getattr(ep.controller, "direct", False)),
            touch_names=self._touch_names,
            start_facing=self._facing,
            state_time=np.array([r[0] for r in st]),
            body_pos=np.stack([r[1] for r in st]),
            body_quat=np.stack([r[2] for r in st]),
            com=np.stack([r[3] for r in st]),
            planar=np.stack([r[4] for r in st]),
            joint_angle=np.stack([r[5] for r in st]),
            qpos=np.stack([r[6] for r in st]),
            command_time=np.array([r[0] for r in cmd]),
            neurons=_stack([r[1] for r in cmd], (0, 0)),
            action=_stack([r[2] for r in cmd], (0, n_act)),
            tick_time=np.array([r[0] for r in tk]),
            fitness=np.array([r[1] for r in tk]),
            touch=_stack([r[2] for r in tk], (0, K)),
            touch_pos=_stack([r[3] for r in tk], (0, K, 3)),
            sensors={k: np.stack(v) for k, v in self._sensors.items()},
            source=np.stack(self._source) if self._source else None,
            sources=self._sources,
            final_fitness=float(result.fitness[p]),
            fell=bool(result.fell[p]),
            end_time=float(result.end_time[p]),
        )

    # ------------------------------------------------------------ helpers
    def _record_state(self, t: float, sims) -> None:
        p, body = self.index, self._episode.body
        q = sims.qpos[p]
        angles = np.where(self._joint_qadr >= 0, q[np.maximum(self._joint_qadr, 0)], np.nan)
        self._rows["state"].append(
            (
                t,
                sims.xpos[p].copy(),
                sims.xquat[p].copy(),
                np.array(body.com(sims)[p], float),
                np.array(body.planar_position(sims)[p], float),
                angles,
                q.copy(),
            )
        )


def _actuated_qpos(model: mujoco.MjModel, actuators) -> np.ndarray:
    """qpos address of each actuator's hinge/slide joint (by joint name, else by the
    actuator's transmission); -1 where there is none."""
    adr = []
    for name in actuators:
        j = -1
        try:
            j = model.joint(name).id
        except KeyError:
            try:
                a = model.actuator(name).id
                if int(model.actuator_trntype[a]) == int(mujoco.mjtTrn.mjTRN_JOINT):
                    j = int(model.actuator_trnid[a, 0])
            except KeyError:
                pass
        ok = j >= 0 and int(model.jnt_type[j]) in (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE))
        adr.append(int(model.jnt_qposadr[j]) if ok else -1)
    return np.array(adr, int)


def _stack(rows: list, empty_shape: tuple) -> np.ndarray:
    return np.stack(rows) if rows else np.zeros(empty_shape)


def record(episode, genome: np.ndarray, *, seconds: float | None = None) -> tuple[Any, Trajectory]:
    """Run ``genome`` ``(G,)`` alone with a recorder -> ``(EpisodeResult, Trajectory)``."""
    rec = TrajectoryRecorder(0)
    result = episode.run(np.asarray(genome, float)[None, :], seconds=seconds, listener=rec)
    return result, rec.trajectory
