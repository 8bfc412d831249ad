"""DAgger's data: teacher and student side by side in one simulation (:class:`Blend`), and the rollouts it records
(:class:`Rollouts`: the student's inputs and the teacher's executed actions as labels)."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from ..controllers.base import Controller
from ..episode import EpisodeConfig
from ..interface.mapping import to_action
from ..physics.perturb import PerturbationOptions
from .settings import DistillOptions


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
        self._t_cols = np.concatenate([cols[n]
                                       for n in self.teacher.input_names]) if self.teacher.input_names else np.zeros(
                                           0, int)
        self._s_cols = np.concatenate([cols[n]
                                       for n in self.student.input_names]) if self.student.input_names else np.zeros(
                                           0, int)

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


def collect(teacher_cfg: EpisodeConfig, teacher_genome: np.ndarray, student_cfg: EpisodeConfig,
            student_genome: np.ndarray, *, beta: float, options: DistillOptions, key: tuple[int, int]) -> Rollouts:
    """``options.rollouts`` rollouts of ``options.seconds`` executing ``beta`` teacher + ``(1 - beta)`` student,
    under target and pose noise drawn from ``key`` = (seed, iteration)."""
    t_body, teacher, task = teacher_cfg.parts()
    _, student, _ = student_cfg.parts()
    latency = teacher_cfg.latency
    low, high = t_body.action_bounds()
    blend = Blend(teacher, teacher_genome, student, low=low, high=high, action_kind=t_body.action_kind, latency=latency,
                  beta=beta)
    blend.wire({**t_body.sensor_widths, **task.sensor_widths()})
    # the student's episode (the teacher's body and task), ``seconds`` long, ending at a fall, driven by the blend
    ep = dataclasses.replace(student_cfg, seconds=options.seconds, stop_on_fall=True).build(controller=blend)
    pert = PerturbationOptions(presentations=options.rollouts, target_noise=options.target_noise,
                               pose_noise=options.pose_noise)
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
