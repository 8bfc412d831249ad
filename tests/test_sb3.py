"""An RL library as a client: Stable-Baselines3's PPO learns on this project's Gymnasium environment through its
public interface (``actions="unit"``), with the settings of scripts/sb3_ppo.py (docs/gym.md)."""

import importlib.util
import warnings
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("gymnasium")
pytest.importorskip("stable_baselines3")

SCRIPT = Path(__file__).resolve().parent.parent / "scripts" / "sb3_ppo.py"


def _script():
    spec = importlib.util.spec_from_file_location("sb3_ppo", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize("env_id", ["evobiped/ReilBiped-v0", "evobiped/TagaBiped-v0"])
def test_sb3_s_checker_finds_nothing_to_advise_with_unit_actions(env_id):
    import gymnasium
    from stable_baselines3.common.env_checker import check_env

    import evobiped.envs  # noqa: F401

    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        check_env(gymnasium.make(env_id, seconds=0.5, actions="unit").unwrapped)
    assert not [str(w.message) for w in said], "SB3's checker advised"
    with warnings.catch_warnings(record=True) as said:  # the native box: SB3 recommends [-1, 1]
        warnings.simplefilter("always")
        check_env(gymnasium.make(env_id, seconds=0.5).unwrapped)
    assert any("normalized Box action space" in str(w.message) for w in said)


def test_ppo_learns_to_carry_the_reil_biped_forward():
    """Half-second episodes (25 control steps: the walker is still up when they end, so the return is the forward
    progress in m): 20,480 steps of PPO carry the body forward on held-out resets well beyond the untrained policy
    and a random one (measured: 0.17 m against 0.01 m untrained; docs/gym.md has the 10 s episodes' curve)."""
    curve = _script().train("evobiped/ReilBiped-v0", 20480, seconds=0.5, every=20480, episodes=10, say=lambda s: None,
                            ppo={"n_steps": 256, "batch_size": 256, "n_epochs": 5, "learning_rate": 1e-3})
    (steps, trained, up, _), = curve["rows"]
    assert steps == 20480 and up == 25  # every held-out episode ran its 25 steps
    assert trained > curve["untrained"][0] + 0.08 and trained > curve["random"][0] + 0.08, curve
    assert np.isfinite(trained) and trained < 1.0  # a half-second lunge, not a teleport
