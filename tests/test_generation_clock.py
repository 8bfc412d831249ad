"""evolve's time left: every walker's episode modelled, measured against the quick start."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from evobiped.core.progress import GenerationClock

RUNS = json.loads((Path(__file__).with_name("quickstart_clock.json")).read_text())


def episodes(total: float, longest: float, rows: int = 16) -> list[float]:
    """``rows`` end times summing to ``total`` with the longest ``longest`` (one walker that long, the rest alike)."""
    rest = (total - longest) / (rows - 1)
    assert -1e-9 <= rest <= longest + 1e-9
    return [longest] + [max(rest, 0.0)] * (rows - 1)


def feed(clock: GenerationClock, S, L, W) -> None:
    for s, l, w in zip(S, L, W):
        clock.episodes(episodes(s, l))
        clock.generation(w)


def test_the_cost_of_a_generation_is_fitted_from_every_episode_and_the_longest():
    a, b = 0.002, 0.008
    S, L = [100.0, 300.0, 500.0, 700.0, 420.0], [20.0, 50.0, 50.0, 50.0, 35.0]
    clock = GenerationClock(100, 50.0)
    feed(clock, S, L, [a * s + b * l for s, l in zip(S, L)])
    assert clock.cost() == pytest.approx((a, b))


def test_walkers_that_all_stay_up_cost_their_full_episodes():
    clock = GenerationClock(10, 50.0)
    for _ in range(4):
        clock.episodes([50.0] * 16)
        clock.generation(2.0)
    assert clock.left(4) == pytest.approx(2.0 * 6)
    assert clock.left(10) == 0.0
    assert math.isnan(GenerationClock(10, 50.0).left(0))


def test_short_episodes_now_are_expected_to_lengthen():
    """Walkers that fall early now: the rest is forecast longer than as short as now, shorter than all up."""
    clock = GenerationClock(150, 50.0)
    for _ in range(15):
        clock.episodes([5.0] * 15 + [50.0])
        clock.generation(0.01 * 125 + 0.01 * 50)
    a, b = clock.cost()
    now, all_up = (a * 125 + b * 50) * 135, (a * 800 + b * 50) * 135
    assert now < clock.left(15) < all_up


def forecast_errors(run: str) -> np.ndarray:
    """A recorded run: from 10 % of its generations on, the forecast work still to go (at the rate the clock
    fitted) against the work the rest of the run then did, at that same rate, less 1."""
    S, L, W = (np.array(RUNS[run][k]) for k in "SLW")
    n = len(W)
    errors = []
    for g in range(n // 10, n):
        clock = GenerationClock(n, 50.0)
        feed(clock, S[:g], L[:g], W[:g])
        a, b = clock.cost()
        errors.append(clock.left(g) / (a * S[g:].sum() + b * L[g:].sum()) - 1)
    return np.array(errors)


@pytest.mark.parametrize("run", ["quickstart_seed5", "quickstart_seed3"])
def test_from_10_percent_of_the_quick_start_on_the_forecast_is_within_30_percent(run):
    errors = forecast_errors(run)
    assert np.abs(errors).max() <= 0.3, (errors.min(), errors.max())


def test_a_short_run_is_forecast_no_lower_than_it_runs():
    """30 generations, most of them while the walkers still learn to stay up: the forecast errs long, never short."""
    errors = forecast_errors("generations30_seed1")
    assert errors.min() >= 0 and errors.max() < 0.6, (errors.min(), errors.max())


def test_a_run_that_may_stop_early_says_its_time_left_is_a_bound(tmp_path):
    """With a stopping rule the run may end before its last generation: the progress lines say "left at most", the
    opening line says it may take fewer generations; a run without a rule keeps "left ~"."""
    import subprocess
    import sys

    def lines(*extra):
        out = subprocess.run([sys.executable, "-m", "evobiped", "evolve", "--preset", "walker-ctrnn-walk",
                              "--generations", "2", "--population", "4", "--seconds", "0.2", "--workers", "1", *extra],
                             capture_output=True, text=True, timeout=300)
        assert out.returncode == 0, out.stderr
        return (out.stdout + out.stderr).splitlines()

    bounded = lines("--out", str(tmp_path / "a"))
    assert any("2 generations (or fewer: it stops once its walker walks)" in x for x in bounded)
    mid = [x for x in bounded if x.startswith("evolve:  50%")]
    assert mid and "left at most " in mid[0], bounded
    (tmp_path / "plain.toml").write_text('[stop]\nwhen = ""\n')
    plain = lines("--config", str(tmp_path / "plain.toml"), "--out", str(tmp_path / "b"))
    mid = [x for x in plain if x.startswith("evolve:  50%")]
    assert mid and "left ~" in mid[0] and not any("or fewer" in x for x in plain), plain
