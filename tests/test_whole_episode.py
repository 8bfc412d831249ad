"""The whole episode compiled (evobiped.episode.compiled.whole) computes what the lock-step loop computes, to the last
bit: the fitness, the terms, where and when each walker fell, a blow-up, and the state the batch is left in."""

import dataclasses

import numpy as np
import pytest

from evobiped.episode import build_episode
from evobiped.episode.compiled import scope
from evobiped.optimizers import GA, GAOptions
from evobiped.physics.sim import Sims


def bits(a):
    return np.ascontiguousarray(a, float).view(np.int64)


def _pair(**config):
    """The same episode with the NumPy kernel (the lock-step loop) and compiled (the whole episode)."""
    return build_episode(kernel="numpy", **config), build_episode(kernel="compiled", **config)


def _same(a, b):
    for field in ("fitness", "end_position", "end_time", "fell", "unstable"):
        assert np.array_equal(bits(getattr(a, field)), bits(getattr(b, field))), field
    assert a.terms.keys() == b.terms.keys()
    for k in a.terms:
        assert np.array_equal(bits(a.terms[k]), bits(b.terms[k])), k


@pytest.mark.parametrize("stop_on_fall", [True, False])
def test_the_paper_s_episode_whole_is_the_lock_step_loop_to_the_last_bit(stop_on_fall):
    slow, fast = _pair(body="reil", seconds=4.0, stop_on_fall=stop_on_fall)
    genomes = GA(slow.controller.layout, GAOptions(population=12), seed=5).ask()[0]
    state = fast.start(genomes)
    assert scope.unsupported(fast, state) is None and scope.unsupported(slow, state) == "the kernel is numpy"
    fast.advance(state, 1.5)  # in two calls, the batch's state handed on between them
    fast.advance(state, 2.5)
    a, b = slow.run(genomes), fast.result(state)
    _same(a, b)
    assert a.fell.any() if stop_on_fall else not a.fell.any()
    # the batch is left where the loop leaves it
    ref = slow.start(genomes)
    slow.advance(ref, 4.0)
    assert ref.ticks == state.ticks
    assert np.array_equal(bits(ref.sims.qpos), bits(state.sims.qpos))
    assert np.array_equal(bits(ref.sims.xpos), bits(state.sims.xpos))


def test_a_walker_that_blows_up_is_unstable_in_both():
    slow, fast = _pair(body="reil", seconds=1.0)
    genomes = GA(slow.controller.layout, GAOptions(population=4), seed=1).ask()[0]
    results = []
    for ep in (slow, fast):
        state = ep.start(genomes)
        state.sims.qpos[2, 0] = np.nan  # MuJoCo resets it with a warning whose info is DOF 0
        ep.advance(state, 1.0)
        results.append(ep.result(state))
    _same(*results)
    assert results[0].unstable.tolist() == [False, False, True, False]
    assert results[0].end_time[2] == slow.control_dt


def test_a_bad_position_at_dof_0_is_a_blow_up():
    """MuJoCo resets a simulation whose qpos is not finite and warns with the DOF as its info: at DOF 0 the info is
    0, so the warning's count, not its info, says it happened."""
    ep = build_episode(body="reil", seconds=1.0)
    sims = Sims(ep.model, 3)
    sims.reset()
    sims.qpos[1, 0] = np.nan
    sims.qpos[2, 3] = np.inf
    bad = sims.step(np.arange(3), 2)
    assert bad.tolist() == [False, True, True]
    assert np.isfinite(sims.qpos).all()  # reset: only the warning tells


def test_what_the_whole_episode_does_not_know_runs_the_loop():
    ep = build_episode(body="reil", seconds=1.0, kernel="compiled", task_options={"fitness": "weighted"})
    state = ep.start(GA(ep.controller.layout, GAOptions(population=2), seed=1).ask()[0])
    assert scope.unsupported(ep, state) is None
    assert scope.unsupported(ep, state, listener=object()) == "a listener watches every tick"
    assert scope.unsupported(build_episode(body="taga", seconds=1.0, kernel="compiled"), state) == "the body 'taga'"


@pytest.mark.parametrize("name", ["ctrnn_walk_seed1", "ctrnn_es_seed5", "ctrnn_distilled_seed5",
                                  "ctrnn_command_seed1", "simbicon_seed1", "steer_simbicon_seed0"])
def test_a_shipped_walker_s_episode_whole_is_the_loop_to_the_last_bit(name):
    """The walkers' episodes read the senses, mirror them into the stance frame, normalise them, count steps and
    measure the gait, step a CTRNN or the SIMBICON-style controller (deaf, or hearing its source): every term the same
    bits either way, over the whole episode."""
    import dataclasses
    from pathlib import Path

    from evobiped.files.genome_file import load_genome

    genome, config, _ = load_genome(Path(__file__).parents[1] / "docs" / "walkers" / f"{name}.json")
    config = dataclasses.replace(config, seconds=min(config.seconds, 12.0))
    genomes = np.stack([genome, genome + 0.01])
    slow, fast = (dataclasses.replace(config, kernel=k).build() for k in ("numpy", "compiled"))
    assert scope.unsupported(fast, fast.start(genomes)) is None
    a, b = slow.run(genomes), fast.run(genomes)
    _same(a, b)
    assert a.end_time[0] == config.seconds and len(a.terms) >= 2


@pytest.mark.parametrize("name", ["ctrnn_command_seed1", "ctrnn_walk_seed1", "steer_ctrnn_es_seed0"])
def test_a_generation_s_presentations_whole_are_the_loop_s(name):
    """As evolution presents them: a generation's pose noise, the command task's drawn commands, the steer task's
    random sources, with the running normaliser's senses collected (the route presets' pose noise)."""
    import dataclasses
    from pathlib import Path

    from evobiped.episode import Context
    from evobiped.episode.disturbances import draw_trials
    from evobiped.files.genome_file import load_genome
    from evobiped.flags import run_config

    genome, config, _ = load_genome(Path(__file__).parents[1] / "docs" / "walkers" / f"{name}.json")
    noise = run_config(preset="walker-ctrnn-walk").episode.perturbations
    config = dataclasses.replace(config, seconds=11.0, perturbations=noise)
    genomes = np.stack([genome, genome + 0.005])
    out = []
    for k in ("numpy", "compiled"):
        ep = dataclasses.replace(config, kernel=k).build()
        trials = draw_trials(config.perturbations, ep.task, (3, 7), seconds=config.seconds,
                             n_actuators=len(ep.body.actuator_names), n_genes=genomes.shape[1])
        assert trials is not None
        if k == "compiled":
            assert scope.unsupported(ep, ep.start(genomes, trials=trials)) is None
        out.append(ep.run(genomes, trials=trials, context=Context(observe=True)))
    _same(*out)
    assert out[0].senses.keys() == out[1].senses.keys() == {"count", "total", "squares"}
    for k, v in out[0].senses.items():
        assert np.array_equal(bits(v), bits(out[1].senses[k])), k


def test_a_commanded_walker_stopped_and_turned_whole_is_the_loop_to_the_last_bit():
    """A piecewise schedule with a stop (the stand term) and turns both ways (the commanded facing's leash)."""
    import dataclasses
    from pathlib import Path

    from evobiped.files.genome_file import load_genome

    genome, config, _ = load_genome(Path(__file__).parents[1] / "docs" / "walkers" / "ctrnn_command_seed1.json")
    schedule = {"schedule": "piecewise", "times": [0.0, 3.0, 6.0, 9.0], "speed": [0.5, 0.0, 0.4, 0.6],
                "turning": [0.0, 0.0, 0.35, -0.35]}
    options = dataclasses.replace(config.task_options, **schedule)
    config = dataclasses.replace(config, seconds=12.0, task_options=options)
    slow, fast = (dataclasses.replace(config, kernel=k).build() for k in ("numpy", "compiled"))
    genomes = np.stack([genome, genome + 0.01])
    a, b = slow.run(genomes), fast.run(genomes)
    _same(a, b)
    assert a.terms["stand"][0] > 0 and a.end_time[0] == 12.0


def test_a_steering_walker_near_its_sources_whole_is_the_loop_to_the_last_bit():
    """The ears' sense clipped, the ticks within reach of a source counted, the gait lab's terms weighed."""
    import dataclasses
    from pathlib import Path

    from evobiped.files.genome_file import load_genome

    genome, config, _ = load_genome(Path(__file__).parents[1] / "docs" / "walkers" / "steer_ctrnn_es_seed0.json")
    options = dataclasses.replace(config.task_options, sources=((2.0, 0.3), (1.5, -0.5)), reach=0.8, random_sources=0,
                                  gait_weights={"airborne": -100.0, "sliding": -100.0}, gait_sampling="physics_step")
    config = dataclasses.replace(config, seconds=10.0, task_options=options)
    slow, fast = (dataclasses.replace(config, kernel=k).build() for k in ("numpy", "compiled"))
    genomes = np.stack([genome, genome + 0.01])
    states = [ep.start(genomes) for ep in (slow, fast)]
    assert scope.unsupported(fast, states[1]) is None
    for ep, state in zip((slow, fast), states):
        ep.advance(state, config.seconds)
    _same(slow.result(states[0]), fast.result(states[1]))
    near = [state.task.near for state in states]
    assert np.array_equal(near[0], near[1]) and near[0].max() > 0 and states[0].task.ticks == states[1].task.ticks
    assert "sliding" in slow.result(states[0]).terms


def test_a_walker_on_another_ground_runs_whole_on_that_ground_s_model():
    """A presentation on another floor, slope and gravity runs on its own model (the episode's grounds), whole as in
    the loop."""
    from pathlib import Path

    from evobiped.files.genome_file import load_genome
    from evobiped.physics.trials import Trials

    genome, config, _ = load_genome(Path(__file__).parents[1] / "docs" / "walkers" / "ctrnn_walk_seed1.json")
    out = []
    for k in ("numpy", "compiled"):
        ep = dataclasses.replace(config, seconds=6.0, kernel=k).build()
        trials = Trials.nominal(1, 6, friction=0.3, slope=0.05, gravity=0.5)
        out.append(ep.run(np.stack([genome, genome + 0.01]), trials=trials))
    _same(*out)
    assert out[0].end_time.max() > 1.0


def test_ctrl_c_stops_a_long_whole_episode_with_a_keyboard_interrupt():
    """Signals are handled between the compiled calls (each a fraction of a second) and a pending one is raised as
    the KeyboardInterrupt it is (numba's boxing of a returned array turned it into a SystemError)."""
    import signal
    import subprocess
    import sys
    import time

    code = ("import signal; signal.signal(signal.SIGINT, signal.default_int_handler)\n"
            "import numpy as np\nfrom evobiped.episode import build_episode\n"
            "from evobiped.optimizers import GA, GAOptions\n"
            "ep = build_episode(body='reil', seconds=600.0, stop_on_fall=False, kernel='compiled')\n"
            "g = GA(ep.controller.layout, GAOptions(population=20), seed=5).ask()[0]\n"
            "ep.run(g[:2], seconds=1.0)\nprint('go', flush=True)\n"
            "try:\n    ep.run(g)\nexcept KeyboardInterrupt:\n    print('interrupted', flush=True)\n")
    proc = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    try:
        assert proc.stdout.readline().strip() == "go"
        time.sleep(1.0)
        sent = time.monotonic()
        proc.send_signal(signal.SIGINT)
        out, _ = proc.communicate(timeout=60)
        assert out.strip() == "interrupted" and time.monotonic() - sent < 10.0
    finally:
        proc.kill()
        proc.wait()
