"""The Gymnasium environments: the checker, seeding, the vector env against single envs, rewards (the task's
fitness increments), bad input."""

import os
import subprocess
import sys
import warnings

import numpy as np
import pytest

gymnasium = pytest.importorskip("gymnasium")

# importing registers the environments
from evobiped.envs import ReilBipedEnv, ReilBipedVectorEnv, TagaBipedEnv, TagaBipedVectorEnv  # noqa: E402
from evobiped.core.errors import ConfigError  # noqa: E402

IDS = ["evobiped/ReilBiped-v0", "evobiped/TagaBiped-v0"]
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


@pytest.mark.parametrize("env_id", IDS)
def test_gymnasium_env_checker_passes(env_id):
    from gymnasium.utils.env_checker import check_env

    env = gymnasium.make(env_id, seconds=1.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # advice only: unbounded observations, unnormalised actions
        check_env(env.unwrapped, skip_render_check=True)
    env.close()


def _episode(env, seed, steps):
    """Observations and rewards of ``steps`` steps of a seeded reset with seeded random actions."""
    obs, _ = env.reset(seed=seed)
    env.action_space.seed(seed)
    out, rewards = [obs], []
    for _ in range(steps):
        obs, r, te, tr, _ = env.step(env.action_space.sample())
        out.append(obs)
        rewards.append(r)
        if te or tr:
            break
    return np.array(out), np.array(rewards)


@pytest.mark.parametrize("cls", [ReilBipedEnv, TagaBipedEnv])
def test_a_seeded_reset_gives_the_same_episode_twice(cls):
    env = cls(seconds=0.3)
    a, ra = _episode(env, 7, 30)
    b, rb = _episode(env, 7, 30)
    c, _ = _episode(env, 8, 30)
    assert a.shape == b.shape and np.array_equal(a, b) and np.array_equal(ra, rb)
    assert not np.array_equal(a[0], c[0])  # the reset noise follows the seed


def _single_runs(cls, n, seed, actions, **kw):
    """n single envs seeded seed + i, with next-step autoreset as the vector env does it."""
    obs, rew, term, trunc = [], [], [], []
    for i in range(n):
        env = cls(**kw)
        o, _ = env.reset(seed=seed + i)
        rows = [(o, 0.0, False, False)]
        done = False
        for a in actions[:, i]:
            if done:
                o, _ = env.reset()
                rows.append((o, 0.0, False, False))
                done = False
                continue
            o, r, te, tr, _ = env.step(a)
            rows.append((o, r, te, tr))
            done = te or tr
        obs.append([x[0] for x in rows])
        rew.append([x[1] for x in rows])
        term.append([x[2] for x in rows])
        trunc.append([x[3] for x in rows])
    return tuple(np.swapaxes(np.array(x), 0, 1) for x in (obs, rew, term, trunc))


@pytest.mark.parametrize("single, vector, steps, kw", [
    (ReilBipedEnv, ReilBipedVectorEnv, 60, dict(seconds=0.8)),
    (TagaBipedEnv, TagaBipedVectorEnv, 12, dict(seconds=0.1)),
])
def test_the_vector_env_gives_the_trajectories_of_single_envs(single, vector, steps, kw):
    n, seed = 3, 11
    venv = vector(n, **kw)
    rng = np.random.default_rng(0)
    lo, hi = venv.single_action_space.low, venv.single_action_space.high
    actions = rng.uniform(lo, hi, size=(steps, n, len(lo))).astype(np.float32)
    o, _ = venv.reset(seed=seed)
    got = [(o, np.zeros(n), np.zeros(n, bool), np.zeros(n, bool))]
    for a in actions:
        o, r, te, tr, _ = venv.step(a)
        got.append((o, r, te, tr))
    got = tuple(np.array([g[k] for g in got]) for k in range(4))
    want = _single_runs(single, n, seed, actions, **kw)
    for g, w in zip(got, want):
        assert np.array_equal(g, w.astype(g.dtype))
    ends = got[2] | got[3]
    assert (ends.sum(axis=0) >= 1).all()  # every walker's episode ended (a fall or the time limit) and restarted


def test_the_episode_state_holds_the_environment_s_episode_a_restored_copy_replays_it():
    """The reward baseline, each row's reset-noise generator and which rows wait for a reset are the environment's
    state's, beside its episode's: a copy taken mid-episode, put back, replays the same actions (autoresets included)
    exactly."""
    venv = ReilBipedVectorEnv(3, seconds=0.2, reset_noise_scale=0.05)  # 10 control ticks: every row resets below
    rng = np.random.default_rng(2)
    lo, hi = venv.single_action_space.low, venv.single_action_space.high
    actions = rng.uniform(lo, hi, size=(30, 3, len(lo)))
    venv.reset(seed=4)
    for a in actions[:6]:
        venv.step(a)
    saved = venv.walkers.state.copy()
    runs = []
    for _ in range(2):
        steps = [venv.step(a) for a in actions[6:]]
        runs.append([np.concatenate([s[0].ravel(), s[1], s[2], s[3]]) for s in steps])
        venv.walkers.state = saved.copy()
    assert np.array_equal(np.array(runs[0]), np.array(runs[1]))
    assert np.concatenate([s[2] | s[3] for s in steps]).sum() >= 3 and np.abs(np.array([s[1] for s in steps])).sum() > 0


def test_rewards_are_the_increments_of_the_task_fitness_and_info_carries_its_terms():
    """The default task: the walk task's forward fitness F = (forward + credit) * t_up / T, credit 5 m.
    The rewards sum to F at the end minus F at reset (the credit); at the fall the walker loses the
    credit for the time it will not be up."""
    T, dt = 2.0, 0.02
    env = ReilBipedEnv(seconds=T, reset_noise_scale=0.0)
    env.reset(seed=0)
    start = env.walkers.info()["position"][0].copy()
    facing = env.walkers.state.episode.start_facing[0].copy()
    lean = np.array([0.4, 0, -0.2, 0.4, 0, -0.2], np.float32)  # both hips flexed: it topples forward
    rewards, forwards = [], [0.0]
    while True:
        _, r, te, tr, info = env.step(lean)
        rewards.append(r)
        forwards.append(info["forward"])
        if te or tr:
            break
    assert te and not tr and len(rewards) < 100  # it fell before the end
    forward = float(np.dot(info["position"] - start, facing))
    assert info["forward"] == pytest.approx(forward, abs=1e-12) and abs(forward) > 0.05
    assert info["distance"] == pytest.approx(float(np.linalg.norm(info["position"] - start)), abs=1e-12)
    assert "cyclicity" not in info  # undefined without the cyclic criterion
    t_fall = len(rewards) * dt
    assert info["fitness"] == pytest.approx((forward + 5.0) * t_fall / T, abs=1e-12)
    assert sum(rewards) == pytest.approx(info["fitness"] - 5.0, abs=1e-12)
    # while it is up a step pays its forward progress; the fall costs the credit of the time lost
    assert np.allclose(rewards[:-1], np.diff(forwards[:-1]), rtol=0, atol=1e-12)
    assert rewards[-1] == pytest.approx(forward - forwards[-2] - (forward + 5.0) * (1 - t_fall / T), abs=1e-12)


def test_the_task_and_its_options_are_environment_options():
    env = ReilBipedEnv(seconds=1.0, task_options={"fitness": "distance"}, reset_noise_scale=0.0)
    env.reset(seed=0)
    back = np.array([-0.4, 0, -0.2, -0.4, 0, -0.2], np.float32)
    total = 0.0
    for _ in range(20):
        _, r, te, tr, info = env.step(back)
        total += r
        if te:
            break
    assert total == pytest.approx(info["distance"], abs=1e-12) and info["fitness"] == info["distance"] > 0
    with pytest.raises(ConfigError, match="neurons"):
        ReilBipedEnv(task_options={"cyclic_weight": 1.0})
    with pytest.raises(ConfigError, match="task_options.fitness"):
        ReilBipedEnv(task_options={"fitness": "far"})


def test_truncated_at_the_episode_length_while_standing():
    env = ReilBipedEnv(seconds=0.2, reset_noise_scale=0.0)
    env.reset(seed=0)
    stand = np.zeros(6, np.float32)  # straight legs, hips level
    flags = [env.step(stand)[2:4] for _ in range(10)]
    assert flags[:9] == [(False, False)] * 9 and flags[9] == (False, True)
    with pytest.raises(RuntimeError, match="reset"):
        env.step(stand)


@pytest.mark.parametrize("bad, words", [(np.zeros(5), "shape"), (np.full(6, np.nan), "NaN"), ("left", "float array")])
def test_a_bad_action_raises_and_leaves_the_simulation_untouched(bad, words):
    env = ReilBipedEnv()
    env.reset(seed=0)
    qpos = env.walkers.sims.qpos.copy()
    with pytest.raises(ValueError, match=words):
        env.step(bad)
    venv = ReilBipedVectorEnv(2)
    venv.reset(seed=0)
    with pytest.raises(ValueError, match="shape"):
        venv.step(np.zeros((3, 6)))
    assert np.array_equal(env.walkers.sims.qpos, qpos) and env.walkers.steps[0] == 0


@pytest.mark.parametrize("kw, words", [
    (dict(stiffness=3), "unknown option"),
    (dict(seconds=-1), "seconds: must be > 0"),
    (dict(control_dt=0.007), "not a multiple"),
    (dict(render_mode="human"), "render_mode"),
    (dict(actions="normalised"), "actions"),
])
def test_bad_options_raise_one_clear_error(kw, words):
    with pytest.raises(ConfigError, match=words):
        gymnasium.make("evobiped/ReilBiped-v0", **kw) if "render_mode" not in kw else ReilBipedEnv(**kw)
    with pytest.raises(ConfigError, match=words):
        ReilBipedVectorEnv(2, **kw)


@pytest.mark.parametrize("cls", [ReilBipedEnv, TagaBipedEnv])
def test_unit_actions_are_the_body_s_bounds_mapped_linearly(cls):
    """``actions="unit"``: the space is [-1, 1]^n_act (what RL libraries expect), and a unit action a drives the
    body exactly as the native action low + (a + 1) / 2 (high - low) does; beyond [-1, 1] it is clipped."""
    unit, native = cls(seconds=0.2, actions="unit"), cls(seconds=0.2)
    low, high = native.walkers.low, native.walkers.high  # the body's bounds (float64; the space holds float32)
    assert (unit.action_space.low == -1).all() and (unit.action_space.high == 1).all()
    assert unit.action_space.shape == native.action_space.shape and not np.allclose(low, -1)
    unit.reset(seed=3), native.reset(seed=3)
    rng = np.random.default_rng(0)
    for k in range(8):
        a = rng.uniform(-1.5, 1.5, unit.action_space.shape)  # beyond the box too: clipped to its edges
        o1, r1, *_ = unit.step(a)
        o2, r2, *_ = native.step(low + 0.5 * (np.clip(a, -1, 1) + 1) * (high - low))
        assert np.array_equal(o1, o2) and r1 == r2, k
    unit.reset(seed=4), native.reset(seed=4)  # a unit 0 is the middle of every bound (Reil's not the native 0)
    assert np.array_equal(unit.step(np.zeros(len(low)))[0], native.step(low + 0.5 * (high - low))[0])


def _python(code: str, **env) -> subprocess.CompletedProcess:
    """Run ``code`` in a fresh Python without a display; MUJOCO_GL only as given in ``env``."""
    e = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY", "MUJOCO_GL")}
    e.update(PYTHONPATH=ROOT, **env)
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=e, timeout=120)


def test_rendering_without_an_opengl_context_is_one_clear_error():
    code = ("import gymnasium, evobiped.envs\ntry:\n    gymnasium.make('evobiped/ReilBiped-v0', "
            "render_mode='rgb_array')\nexcept Exception as e:\n    print(type(e).__name__, e)")
    out = _python(code, MUJOCO_GL="glfw").stdout
    assert out.startswith("ConfigError rgb_array: cannot render frames: no OpenGL context") and out.count("\n") == 1
    assert "MUJOCO_GL=glfw" in out and "libosmesa6" in out


def test_rgb_array_frames_where_egl_exists():
    """MUJOCO_GL unset and no display: importing evobiped picks EGL by itself (Gymnasium's check_env then passes)."""
    code = (
        "import gymnasium, numpy as np, evobiped.envs\n"
        "for i in ('evobiped/ReilBiped-v0', 'evobiped/TagaBiped-v0'):\n"
        "    e = gymnasium.make(i, render_mode='rgb_array', width=64, height=48); e.reset(seed=0)\n"
        "    f = e.render(); print(f.shape, f.dtype, int(f.std() > 5))\n"
    )
    r = _python(code)
    if "OpenGL context" in r.stderr:
        pytest.skip("no EGL on this machine")
    assert r.stdout.split("\n")[:2] == ["(48, 64, 3) uint8 1"] * 2, r.stderr


def test_a_blow_up_ends_the_episode_and_the_next_reset_is_clean():
    """PD gains far beyond what a 5 ms step can integrate: the first step blows up."""
    env = ReilBipedEnv(kp=1e7, kv=0.0, reset_noise_scale=0.0)
    first, _ = env.reset(seed=0)
    obs, r, te, tr, info = env.step(np.array([1.6, 0.8, -1.4, -1.3, -0.8, 0.0], np.float32))
    assert te and not tr and info["unstable"] and np.isfinite(obs).all()
    assert r == pytest.approx(-5.0 * (1 - 0.02 / 50.0), abs=1e-12)  # it did not move: it lost the survival credit
    again, _ = env.reset(seed=0)
    assert np.array_equal(again, first) and np.isfinite(env.walkers.sims.qpos).all()
