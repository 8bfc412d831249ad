"""The rhythm generators' legs: with ``symmetric`` one set of genes serves both legs in the body's frame (the second
leg's units mirror the first's), and in the stance frame each leg's oscillator stays on its leg (``reframe``: the
units swap places when the stance leg changes, so the rhythm runs on while the genes it follows are the stance or
the swing leg's)."""

import numpy as np
import pytest

from evobiped.episode import EpisodeConfig

from .conftest import ActionRecorder

INPUTS = ["joint_angles", "joint_velocities", "foot_contact", "pelvis_tilt", "com_velocity", "stance_leg"]
MATSUOKA = {"feedback": "senses", "output": "angle", "reflex": True, "dt": 0.02, "integration": "exponential",
            "u0": 1.0, "initial_u": 0.5, "inputs": INPUTS}
G3 = {"feedback": "senses", "output": "angle", "go": 0.1, "inputs": INPUTS}


def _build(controller, options, seconds=1.0):
    """An episode on the Reil body that runs on after a fall (the feet keep touching down)."""
    return EpisodeConfig(body="reil", controller=controller, seconds=seconds, controller_options=options,
                         stop_on_fall=False).build()


@pytest.mark.parametrize("controller, options", [("matsuoka", MATSUOKA), ("g3", G3)])
def test_symmetric_genes_make_the_mirrored_body_give_the_mirrored_action(controller, options):
    """Independently of how the genes are spread: a symmetric controller stepped from the mirror image of a state
    with the mirror image of its inputs acts as the mirror image of what it does from the state itself."""
    ep = _build(controller, options | {"symmetric": True})
    c, full = ep.controller, _build(controller, options).controller
    assert c.layout.size < full.layout.size
    sym = c.bilateral
    assert list(sym.first) == [0, 1, 2] and list(sym.second) == [3, 4, 5]
    rng = np.random.default_rng(7)
    params = c.decode(c.layout.sample(rng, 3))
    per_unit = 2 if controller == "matsuoka" else 1
    leg_swap = (np.array([3, 4, 5, 0, 1, 2])[:, None] * per_unit + np.arange(per_unit)).ravel()
    state = {k: (rng.uniform(0, 0.6, v.shape) if isinstance(v, np.ndarray) else 1000)  # G3: its GO has arrived
             for k, v in c.initial_state(params).items()}
    mirrored = {k: (v[:, leg_swap] if isinstance(v, np.ndarray) else v) for k, v in state.items()}
    x = rng.normal(size=(3, c.n_inputs))
    x_m = x[:, sym.input_perm] * sym.input_sign
    s1, a = c.step(params, state, x)
    s2, b = c.step(params, mirrored, x_m)
    assert np.allclose(b, a[:, [3, 4, 5, 0, 1, 2]], rtol=0, atol=1e-12)
    for k, v in s1.items():
        if isinstance(v, np.ndarray):
            assert np.allclose(s2[k], v[:, leg_swap], rtol=0, atol=1e-12)
    assert not np.allclose(a[:, :3], a[:, 3:])  # the legs do differ: the test is not of a still body


@pytest.mark.parametrize("controller, options, genes", [
    ("matsuoka", MATSUOKA, {"p_e": 0.3, "p_f": 0.3}), ("g3", G3, {"gain": 0.6})])
def test_in_the_stance_frame_each_legs_oscillator_stays_on_its_leg(controller, options, genes):
    """With no feedback and the same genes for both legs, the stance frame's rhythm is the body frame's: the legs
    swap several times in the episode and the actions agree to rounding; without the swap they part at the first
    change of stance leg."""
    body, stance = _build(controller, options, 4.0), _build(controller, options | {"frame": "stance"}, 4.0)
    c = body.controller
    g = np.concatenate([np.full(b.size, genes.get(b.name, 0.0 if "gain" in b.name else b.init_mean))
                        for b in c.layout.blocks])
    a, b = ActionRecorder(row=0), ActionRecorder(row=0)
    body.run(g[None], listener=a)
    stance.run(g[None], listener=b)
    a, b = np.array(a.seen), np.array(b.seen)
    n = min(len(a), len(b))
    assert n == 200 and np.allclose(a[:n], b[:n], rtol=0, atol=1e-9)
    flips = []

    class Watch:
        def start(self, episode, sims):
            pass

        def tick(self, t, sims, ids, neurons, action, task_state):
            from evobiped.physics import gait
            flips.append(bool(gait.second_stands(stance.body.contacts(sims), sims)[0]))

        def end(self, result):
            pass

    stance.run(g[None], listener=Watch())
    assert np.count_nonzero(np.diff(flips)) >= 2  # the stance leg changed: the frame flipped and back
    stance.controller.reframe = lambda state, flip: state  # without the swap: the rhythm jumps between legs
    c_ = ActionRecorder(row=0)
    stance.run(g[None], listener=c_)
    c_ = np.array(c_.seen)
    assert not np.allclose(a[:n], c_[:n], rtol=0, atol=1e-3)



@pytest.mark.parametrize("preset, period", [("walker-matsuoka-walk", 1.2), ("walker-g3-walk", 0.9)])
def test_the_walking_presets_start_from_a_rhythm_of_the_documented_period(preset, period):
    """docs/rhythm_walkers.md: at the genes' initial means, with no senses (x = 0), the first generation's
    generator cycles at about 1.2 s (Matsuoka, tau 0.04 s, tau' 0.3 s) and 0.9 s (G3, GO 0.1 on half Fig. 4's time
    scale); Matsuoka's hips in antiphase (w_rl), its hip targets swinging by under 0.1 rad so the body starts
    upright (G3's channels start with equal couplings: their phases are set by the GO lags alone)."""
    from evobiped.flags import run_config

    cfg = run_config(preset=preset)
    ep = cfg.episode.nominal().build()
    c = ep.controller
    assert c.frame is not None and c.reflex and c.output_kind == "angle"
    params = c.decode(c.layout.init_mean[None])
    state, out = c.initial_state(params), []
    for _ in range(int(12.0 / ep.control_dt)):
        state, o = c.step(params, state, np.zeros((1, c.n_inputs)))
        out.append(o[0])
    out = np.array(out)[int(4.0 / ep.control_dt):]  # past the start
    hip, other = out[:, 0] - out[:, 0].mean(), out[:, 3] - out[:, 3].mean()
    ups = np.flatnonzero((hip[1:] > 0) & (hip[:-1] <= 0))
    assert np.diff(ups).mean() * ep.control_dt == pytest.approx(period, rel=0.1)
    if preset == "walker-matsuoka-walk":
        assert np.corrcoef(hip, other)[0, 1] < -0.9 and np.ptp(out[:, 0]) < 0.1
