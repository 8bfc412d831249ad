"""A Gymnasium environment's episode as a Rerun recording (:class:`GymRecorder`, a listener of
:class:`~evobiped.episode.gym_episode.GymEpisode`'s first row; :func:`write_gym_recording`).

Entity tree (time series on the ``sim_time`` timeline, in s: steps times the environment's ``dt``)::

    world/ground/<geom>, world/bodies/<body>/<geom>   static: a MuJoCo environment's geometry (:func:`log_geometry`)
    world/bodies/<body>                               Transform3D per step (after each step, and t = 0)
    reward, return                                    Scalars: the step's reward and the return so far
    observation                                       Scalars: every observation component
    action                                            Scalars: every action component (after the box's clip)

An environment without ``unwrapped.model`` (not MuJoCo) gets the time series alone.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ...core.fileio import atomic_write
from ..geometry import wxyz_to_xyzw
from .rerun_recorder import TIMELINE, log_geometry


class GymRecorder:
    """Records the first row of an environment's episode: observation, action and reward after each of its T steps
    ``(T, k)``, ``(T, n)``, ``(T,)``, and a MuJoCo environment's body poses at t = 0 and after each step
    ``(T + 1, nbody, 3)`` m and quaternions ``(T + 1, nbody, 4)`` (wxyz)."""

    def start(self, episode, envs) -> None:
        self.dt = float(episode.control_dt)
        self.env = envs[0].unwrapped
        self.model = getattr(self.env, "model", None)
        self.obs, self.actions, self.rewards, self.pos, self.quat = [], [], [], [], []
        self._pose()

    def _pose(self) -> None:
        if self.model is not None:
            self.pos.append(np.array(self.env.data.xpos))
            self.quat.append(np.array(self.env.data.xquat))

    def tick(self, step: int, obs: np.ndarray, action: np.ndarray, reward: np.ndarray, rows: np.ndarray) -> None:
        if not len(rows) or rows[0] != 0:  # the first row has ended
            return
        self.obs.append(np.array(obs[0]))
        self.actions.append(np.array(action[0], float))
        self.rewards.append(float(reward[0]))
        self._pose()

    def end(self, result) -> None:
        self.result = result


def write_gym_recording(target: Path, recorder: GymRecorder, *, name: str, history: dict | None = None) -> Path:
    """The recording of ``recorder``'s episode written whole to ``target`` (through :func:`atomic_write`), the run's
    fitness ``history`` (``{column: (n_generations,)}``) beside it when given; returns ``target``."""
    import uuid

    import rerun as rr

    from .evolution_log import log_history

    rec = rr.RecordingStream("evobiped_replay", recording_id=uuid.uuid4().hex)
    stream = rec.binary_stream()
    rec.send_recording_name(name)
    T = len(recorder.rewards)
    steps = rr.TimeColumn(TIMELINE, duration=np.arange(1, T + 1) * recorder.dt)
    states = rr.TimeColumn(TIMELINE, duration=np.arange(T + 1) * recorder.dt)
    if recorder.model is not None:
        from ..geometry import body_names

        log_geometry(rec, recorder.model)
        pos, quat, names = np.array(recorder.pos), np.array(recorder.quat), body_names(recorder.model)
        for b in range(1, recorder.model.nbody):
            rec.send_columns(f"world/bodies/{names[b]}", indexes=[states],
                             columns=rr.Transform3D.columns(translation=pos[:, b], quaternion=wxyz_to_xyzw(quat[:, b])))
    rewards = np.array(recorder.rewards)
    for path, values in (("reward", rewards), ("return", np.cumsum(rewards))):
        rec.log(path, rr.SeriesLines(names=[path]), static=True)
        rec.send_columns(path, indexes=[steps], columns=rr.Scalars.columns(scalars=values))
    for path, values, index in (("observation", recorder.obs, steps), ("action", recorder.actions, steps)):
        values = np.array(values).reshape(T, -1)
        rec.log(path, rr.SeriesLines(names=[f"{path}[{i}]" for i in range(values.shape[1])]), static=True)
        rec.send_columns(path, indexes=[index], columns=rr.Scalars.columns(scalars=values))
    if history is not None:
        log_history(rec, history)
    data = stream.read(flush=True) or b""
    rec.disconnect()
    target.parent.mkdir(parents=True, exist_ok=True)
    atomic_write(target, data)
    return target
