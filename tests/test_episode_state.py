"""An episode state is a value: it owns its simulations, starts are independent, a fork continues as a fresh run."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from evobiped.bodies import BODIES
from evobiped.episode import Episode, EpisodeConfig
from evobiped.experiments.taga.parameters import preset_genome
from evobiped.experiments.taga.walking import set_push
from evobiped.files.genome_file import load_genome
from evobiped.tasks import TASKS

from .conftest import WALKERS, ActionRecorder, random_genomes


def _same(a, b) -> None:
    """Bit-for-bit equal states: MuJoCo's full state, the body's own, the controller's, the task's, the outcome."""
    assert np.array_equal(a.sims.batch.state, b.sims.batch.state)
    assert a.sims.extra.keys() == b.sims.extra.keys()
    for k, table in a.sims.extra.items():
        for name, arr in table.items():
            assert np.array_equal(arr, b.sims.extra[k][name]), (k, name)
    ca, cb = (s.controller if isinstance(s.controller, dict) else {"state": s.controller} for s in (a, b))
    for name in ca:
        assert np.array_equal(ca[name], cb[name]), name
    for name in ("alive", "fell", "end_time"):
        assert np.array_equal(getattr(a, name), getattr(b, name)), name
    assert a.ticks == b.ticks


def _taga_changes(ep, state, which: str) -> None:
    """Two ways to go on: a faster rhythm and a push on the hip, or a slower one and none."""
    if which == "fast":
        state.params["u0"][:] = 6.5
        set_push(state.sims, np.arange(2), "hip", 60.0)
    else:
        state.params["u0"][:] = 4.5


def test_a_taga_walk_forked_mid_walk_continues_each_way_as_a_fresh_run():
    """Fork at 0.6 s; one copy speeds up and is pushed, the other slows down.  Each equals a fresh run
    that made the same change at 0.6 s, bit for bit (ground contacts and pushes included)."""
    ep = EpisodeConfig(body="taga", controller="matsuoka", seconds=1.2).build()
    g = np.tile(preset_genome(ep.controller), (2, 1))
    state = ep.advance(ep.start(g), 0.6)
    fork = state.copy()
    assert fork.sims is not state.sims and fork.sims.extra["taga"]["rest"] is not state.sims.extra["taga"]["rest"]
    for s, which in ((state, "fast"), (fork, "slow")):
        _taga_changes(ep, s, which)
        ep.advance(s, 0.6)
    fast, slow = (ep.advance(ep.start(g), 0.6) for _ in range(2))
    _taga_changes(ep, fast, "fast")
    _taga_changes(ep, slow, "slow")
    ep.advance(fast, 0.6)
    ep.advance(slow, 0.6)
    _same(state, fast)
    _same(fork, slow)
    # the two ways really differ: the pushed, faster walker is further on
    assert state.sims.qpos[0, 0] > fork.sims.qpos[0, 0] + 0.01
    assert np.array_equal(ep.result(state).fitness, ep.result(fast).fitness)


def test_a_perturbed_reil_walk_forked_keeps_its_noise_streams_and_pushes():
    """The shipped SIMBICON walker under target noise and pushes: forked at 1 s, one copy's gains are
    halved; each copy equals a fresh run with the same change, and the unchanged one the uninterrupted run."""
    g, cfg, _ = load_genome(str(WALKERS / "simbicon_seed1.json"))
    cfg = dataclasses.replace(cfg, seconds=3.0, perturbations=dict(pushes=1, push_after=0.5, push_force=40.0,
                                                                   target_noise=0.02))
    ep = cfg.build()
    g = np.tile(g, (2, 1))
    trials = ep.trials_for((1, 0))
    whole = ep.advance(ep.start(g, trials=trials), 3.0)
    state = ep.advance(ep.start(g, trials=trials), 1.0)
    fork = state.copy()
    name = next(iter(fork.params))
    fork.params[name] = fork.params[name] * 0.5
    ep.advance(state, 2.0)
    ep.advance(fork, 2.0)
    _same(state, whole)
    again = ep.advance(ep.start(g, trials=trials), 1.0)
    again.params[name] = again.params[name] * 0.5
    ep.advance(again, 2.0)
    _same(fork, again)
    assert state.alive.all() and not np.array_equal(state.sims.qpos, fork.sims.qpos)


def test_two_starts_are_independent_states():
    """Advancing one state leaves another started from the same genomes at t = 0."""
    ep = EpisodeConfig(seconds=1.0).build()
    g = random_genomes(ep.controller.layout, 2, seed=1)
    a, b = ep.start(g), ep.start(g)
    q0 = b.sims.qpos.copy()
    ep.advance(a, 0.5)
    assert a.sims is not b.sims and np.array_equal(b.sims.qpos, q0) and not np.array_equal(a.sims.qpos, q0)
    assert b.ticks == 0


def test_the_episode_binds_a_copy_of_the_controller():
    """Building an episode tells a copy of the controller its period; the caller's is unchanged."""
    cfg = EpisodeConfig(body="taga", controller="matsuoka", seconds=0.1)
    body, ctrl, task = cfg.parts()
    ep = Episode(body, ctrl, task, seconds=0.1)
    assert ctrl.period is None and ep.controller.period == body.timestep


def _outside(body: str, dt: float) -> Episode:
    """An episode without a controller: its actions come from outside (as the Gymnasium environments' do)."""
    return Episode(BODIES[body](), None, TASKS["walk"](fitness="forward"), seconds=2.0, control_dt=dt)


@pytest.mark.parametrize("body, dt, size", [("reil", 0.02, 0.5), ("taga", 0.01, 40.0)])
def test_a_state_forked_mid_walk_continues_each_action_sequence_as_a_fresh_run(body, dt, size):
    """Three walkers take 30 ticks of random actions (rad targets for Reil, N m torques for Taga) through
    Episode.step; the state is forked and each copy takes its own 30 more.  Each copy equals, bit for
    bit, a fresh run fed that whole action sequence (physics, Taga ground contacts, task, outcome)."""
    ep = _outside(body, dt)
    rng = np.random.default_rng(5)
    mid = (ep.low + ep.high) / 2
    first, left, right = (np.clip(mid + size * rng.uniform(-1, 1, (30, 3, len(mid))), ep.low, ep.high)
                          for _ in range(3))

    def fresh(actions):
        state = ep.start(3)
        for a in actions:
            ep.step(state, a)
        return state

    state = fresh(first)
    fork = state.copy()
    for a in left:
        ep.step(state, a)
    for a in right:
        ep.step(fork, a)
    _same(state, fresh(np.concatenate([first, left])))
    _same(fork, fresh(np.concatenate([first, right])))
    assert state.ticks == fork.ticks == 60 and not np.array_equal(state.sims.qpos, fork.sims.qpos)
    for a, b in ((state, fresh(np.concatenate([first, left]))), (fork, fresh(np.concatenate([first, right])))):
        ra, rb = ep.result(a), ep.result(b)
        assert np.array_equal(ra.fitness, rb.fitness) and all(np.array_equal(ra.terms[k], rb.terms[k], equal_nan=True)
                                                              for k in ra.terms)


def test_a_controller_s_advance_is_its_actions_through_step():
    """``advance`` is the controller's actions through ``step``: feeding a controller-less episode the
    actions a Taga walker's ``advance`` applied (as its listener saw them) gives the same walk, bit for bit."""
    ep = EpisodeConfig(body="taga", controller="matsuoka", seconds=1.0).build()
    g = np.tile(preset_genome(ep.controller), (2, 1))

    seen = ActionRecorder()
    walked = ep.advance(ep.start(g), 1.0, listener=seen)
    outside = Episode(ep.body, None, ep.task, seconds=1.0, control_dt=ep.control_dt)
    fed = outside.start(2)
    for a in seen.seen:
        outside.step(fed, a)
    assert len(seen.seen) == 2000 and walked.alive.all()  # one action per 0.5 ms physics step
    assert np.array_equal(walked.sims.batch.state, fed.sims.batch.state)
    assert np.array_equal(ep.result(walked).fitness, outside.result(fed).fitness)


def test_restarted_rows_begin_anew_while_the_others_go_on():
    """Row 1 restarted at tick 20 equals, from then on, a walker started fresh; row 0 is untouched."""
    ep = _outside("reil", 0.02)
    rng = np.random.default_rng(2)
    acts = np.clip(rng.uniform(-0.3, 0.3, (40, 2, 6)), ep.low, ep.high)
    state = ep.start(2)
    for a in acts[:20]:
        ep.step(state, a)
    ep.restart(state, np.array([1]))
    assert state.born.tolist() == [0, 20] and state.alive.all()
    for a in acts[20:]:
        ep.step(state, a)
    alone = ep.start(2)
    for a in acts[20:]:
        ep.step(alone, a)
    whole = ep.start(2)
    for a in acts:
        ep.step(whole, a)
    assert np.array_equal(state.sims.qpos[1],
                          alone.sims.qpos[1]) and np.array_equal(state.sims.qpos[0], whole.sims.qpos[0])
    assert np.array_equal(ep.result(state).terms["forward"],
                          [ep.result(whole).terms["forward"][0], ep.result(alone).terms["forward"][1]])


def test_a_result_handed_out_stays_as_it_was_after_a_restart():
    """``Episode.result`` copies what it returns: restarting a row of the state later (a vector environment's autoreset,
    after the walker moved) leaves an earlier result's start positions and facings alone."""
    ep = _outside("reil", 0.02)
    rng = np.random.default_rng(3)
    state = ep.start(2)
    for a in np.clip(rng.uniform(-0.3, 0.3, (30, 2, 6)), ep.low, ep.high):
        ep.step(state, a)
    first = ep.result(state)
    kept = (first.start_position.copy(), first.start_facing.copy())
    state.sims.qpos[1, :2] += 0.5  # the walker somewhere else, turned, when its row begins anew
    state.sims.qpos[1, 3:7] = (np.cos(0.3), 0.0, 0.0, np.sin(0.3))
    state.sims.forward()
    ep.restart(state, np.array([1]), pose=lambda sims,
               ids: (sims.qpos.__setitem__((ids, slice(0, 2)), 0.7), sims.forward(ids)))
    assert not np.array_equal(state.start_position[1], kept[0][1])  # the state's own start moved
    assert np.array_equal(first.start_position, kept[0]) and np.array_equal(first.start_facing, kept[1])
