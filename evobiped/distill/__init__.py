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
  scored unless the window starts with its episode (where the network too starts from rest); the loss is the mean
  squared error of the student's PD targets (after its motor map), in rad^2. Genes are kept inside their bounds after
  every step.  JAX is an optional dependency (``pip install 'evobiped[distill]'``): it differentiates the network's
  recurrence exactly, fast on a CPU.
- **Selection.**  Each iteration's student is a candidate (later ones imitate better, but an imitation can
  settle into a gait that drifts or falls late); :func:`evobiped.analysis.selection.best_candidate` keeps the one that
  is up through ``select_seconds`` alone, then walks within ``heading_limit`` of its initial facing, then farthest
  along it.  ``select_seconds = 0`` keeps the last iteration's.

The student is the ``ctrnn`` controller with the options of a network fit for senses (:data:`STUDENT`; any of
them may be changed).  The result is a genome file like any other: ``evolve --from``, ``replay``, ``robustness``
and ``episode --genome`` take it.

The package's modules: :mod:`.settings` (the settings, the student's episode), :mod:`.rollouts` (teacher and student
in one simulation, the data), :mod:`.fit` (the JAX fit), :mod:`.dagger` (the loop and the choice of a student).
"""

from .dagger import DistillReport, distill, select
from .fit import Fitter, random_start
from .settings import STUDENT, DistillOptions, parse_options, student_config
from .rollouts import Blend, Rollouts, collect

__all__ = ["STUDENT", "Blend", "DistillOptions", "DistillReport", "Fitter", "Rollouts", "collect", "distill",
           "parse_options", "random_start", "select", "student_config"]
