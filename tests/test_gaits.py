"""The gait classifier on synthetic square waves of known phase and duty."""

import numpy as np
import pytest

from evobiped.experiments.g3 import gaits


def square_waves(phases, duty=0.3, period=4.0, t_end=60.0, dt=0.01):
    """Channels that are 1 for ``duty`` of each cycle starting at phase*period, else 0."""
    t = np.arange(0.0, t_end, dt)
    x = np.stack([(np.mod(t / period - p, 1.0) < duty).astype(float) for p in phases], axis=1)
    return t, x


@pytest.mark.parametrize(
    "phases, label, sequence",
    [
        ((0, 0.5, 0.75, 0.25), "walk", "lateral"),
        ((0, 0.5, 0.25, 0.75), "walk", "diagonal"),
        ((0, 0.5, 0.5, 0.0), "trot", ""),
        ((0, 0.5, 0.0, 0.5), "pace", ""),
        ((0, 0.0, 0.5, 0.5), "gallop", ""),
        ((0, 0.0, 0.0, 0.0), "pronk", ""),
        ((0, 0.3, 0.6, 0.1), "none", ""),
    ],
)
def test_square_waves_are_classified_by_phase(phases, label, sequence):
    t, x = square_waves(np.array(phases) + 0.013)  # offset: no onset on a sample
    g = gaits.analyse_gait(t, x)
    assert g.oscillating
    assert g.period == pytest.approx(4.0, rel=1e-3)
    assert g.frequency == pytest.approx(0.25, rel=1e-3)
    assert np.all(gaits.circ_dist(g.phases, phases) < 0.01)
    assert np.allclose(g.duty, 0.3, atol=0.01)
    assert (g.label, g.sequence) == (label, sequence)


def test_phase_tolerance_and_duty():
    t, x = square_waves((0.013, 0.58, 0.013, 0.58), duty=0.12)  # pace, 0.067 of a cycle off
    g = gaits.analyse_gait(t, x)
    assert g.label == "pace" and np.allclose(g.duty, 0.12, atol=0.01)
    assert gaits.analyse_gait(t, x, tol=0.05).label == "none"


def test_onset_slightly_before_channel_0_counts_as_in_phase():
    t, x = square_waves((0.02, 0.01, 0.02, 0.015))
    g = gaits.analyse_gait(t, x)
    assert g.label == "pronk" and max(gaits.circ_dist(g.phases, 0)) < 0.02


def test_no_oscillation_is_none():
    t = np.arange(0, 50, 0.01)
    g = gaits.analyse_gait(t, np.full((t.size, 4), 0.2))
    assert (g.label, g.oscillating, g.frequency, g.n_cycles) == ("none", False, 0.0, 0)


def test_transient_is_reported_separately():
    t, x = square_waves((0.013, 0.013, 0.013, 0.013), t_end=100)
    t2, x2 = square_waves((0.013, 0.513, 0.513, 0.013), t_end=100)
    late = t >= 40
    x[late] = x2[late]  # pronk until t = 40, then a trot
    g = gaits.analyse_gait(t, x)
    assert (g.label, g.transient_label) == ("trot", "pronk")
    assert 36.0 <= g.settle_time <= 44.1
