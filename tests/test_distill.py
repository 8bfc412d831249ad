"""Distillation (evobiped.distill): the fitted network is the controller that runs, teacher and student share a
simulation, and the labels are what the teacher's body executes."""

import dataclasses

import numpy as np
import pytest

from evobiped.distill import DistillOptions, Fitter, collect, student_config
from evobiped.episode import EpisodeConfig
from evobiped.files.genome_file import load_genome
from evobiped.core.options import given
from evobiped.interface.mapping import to_action

from .conftest import WALKERS

pytest.importorskip("jax")


def test_the_fitted_recurrence_is_the_ctrnn_that_runs():
    """JAX's scan over the Euler steps gives the numpy controller's targets for the same genome and inputs."""
    _, teacher, _ = load_genome(WALKERS / "simbicon_cma_seed3.json")
    cfg = student_config(teacher, {"n_neurons": 12})
    fitter = Fitter(cfg, DistillOptions(), seed=0)
    body, ctrl, _ = cfg.parts()
    rng = np.random.default_rng(1)
    genome = np.clip(ctrl.layout.init_mean + 0.5 * ctrl.layout.init_sigma * rng.normal(size=ctrl.layout.size),
                     ctrl.layout.low, ctrl.layout.high)
    x = rng.normal(size=(60, ctrl.n_inputs))
    params = ctrl.decode(genome)
    state, want = ctrl.initial_state(params), []
    low, high = body.action_bounds()
    for t in range(len(x)):
        state, out = ctrl.step(params, state, x[t : t + 1])
        want.append(to_action(ctrl.output_kind, low, high, body.action_kind, out)[0])
    np.testing.assert_allclose(fitter.targets(genome, x), np.array(want), rtol=0, atol=1e-12)


def test_rollouts_label_the_student_s_states_with_the_teacher_s_executed_actions():
    """With the teacher's share 1 the rollout is the teacher's own (latency included), and each label is the
    action its body executed, which a plain teacher episode shows its listener."""
    g, cfg, _ = load_genome(WALKERS / "simbicon_cma_seed3.json")
    teacher = dataclasses.replace(cfg.nominal(), seconds=2.0,
                                  controller_options={**given(cfg.controller_options), "latency": 1})
    student = student_config(teacher, {"n_neurons": 12})
    opts = DistillOptions(rollouts=1, seconds=2.0, target_noise=0.0, pose_noise=0.0)
    roll = collect(teacher, g, student, student.layout().init_mean, beta=1.0, options=opts, key=(0, 0))
    executed = []

    class Watch:
        def start(self, episode, sims): ...
        def tick(self, t, sims, ids, neurons, action, task_state): executed.append(action[0].copy())
        def end(self, result): ...

    teacher.build().run(g, listener=Watch())
    assert roll.y.shape == (1, 100, 6) and roll.alive.all()
    np.testing.assert_array_equal(roll.y[0], np.array(executed))
    # the student's inputs are the body's senses, normalised as declared
    assert roll.x.shape == (1, 100, 24) and np.abs(roll.x).max() < 20


def test_a_bad_student_is_one_line():
    from evobiped.core.errors import ConfigError

    _, cfg, _ = load_genome(WALKERS / "simbicon_cma_seed3.json")
    with pytest.raises(ConfigError, match="n_neurons must be > 0"):
        student_config(cfg, {"n_neurons": 0})
    with pytest.raises(ConfigError, match="gives centred_full outputs, which body 'taga' cannot take as torques"):
        student_config(EpisodeConfig(body="taga", controller="matsuoka"), {"inputs": ["link_angles"]}).build()
    with pytest.raises(ConfigError, match="inputs \\['height'\\] are not sensors of the body or task"):
        student_config(cfg, {"inputs": ["height"]}).build()


def test_selection_trusts_the_long_run_over_the_episode():
    """A candidate that looks best in its episode but falls in the long run loses to one that stays up; with
    select_seconds = 0 the last iteration's student is kept."""
    from evobiped.distill import select

    walker, cfg, _ = load_genome(WALKERS / "ctrnn_distilled_seed5.json")
    limp = np.array(cfg.build().controller.layout.low)  # every gene at its lower bound: falls at once
    rows = [dict(fell=False, end_time=50.0, distance=31.0, heading_deg=28.0),
            dict(fell=False, end_time=50.0, distance=40.0, heading_deg=0.0)]  # claims a better episode
    assert select(cfg, [walker, limp], [dict(r) for r in rows], DistillOptions(select_seconds=0), print) == 1
    checked = [dict(r) for r in rows]
    assert select(cfg, [walker, limp], checked, DistillOptions(select_seconds=60.0), print) == 0
    assert checked[0]["up_long"] and not checked[1]["up_long"]
