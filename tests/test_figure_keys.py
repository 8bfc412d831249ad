"""Every figure's words match what it draws: keys of what is there, names the body has, the progress lines' words."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from evobiped.files.genome_file import load_genome
from evobiped.record.png import figures
from evobiped.record.trajectory import record

pytest.importorskip("matplotlib")
WALKER = Path(__file__).resolve().parent.parent / "docs" / "walkers" / "simbicon_cma_seed5.json"


@pytest.fixture
def captured(monkeypatch):
    import evobiped.record.png.robustness_figure as rf  # imported first: it binds figures.save_figure when imported

    figs = []
    monkeypatch.setattr(figures, "save_figure", lambda fig, path, **kw: figs.append(fig) or Path(path))
    monkeypatch.setattr(rf, "save_figure", lambda fig, path, **kw: figs.append(fig) or Path(path))
    yield figs
    figures.pyplot().close("all")


@pytest.fixture(scope="module")
def walk():
    genome, cfg, _ = load_genome(WALKER)
    return record(cfg.build(), genome, seconds=3.0)[1]


def legend_texts(fig) -> list[str]:
    return [t.get_text() for ax in fig.axes if ax.get_legend() for t in ax.get_legend().get_texts()]


def test_the_ground_path_key_names_only_what_is_drawn_in_its_colour(walk, captured):
    figures.ground_trajectory(walk, "g.png")
    texts = legend_texts(captured[0])
    assert "end, stayed up" in texts and "end, fell" not in texts  # it did not fall
    ax = captured[0].axes[0]
    path_colour = ax.get_lines()[0].get_color()
    arrow = [h for h in ax.get_legend().legend_handles if h.get_label() == "initial facing"][0]
    from matplotlib.colors import to_rgba

    assert np.allclose(to_rgba(arrow.get_color()), to_rgba(path_colour))


def test_side_views_name_the_bodies_between_the_legs_as_the_model_does(walk, captured):
    figures.stick_figure(walk, "s.png")
    figures.motion_sequence(walk, "m.png")
    for fig in captured:
        texts = legend_texts(fig)
        assert "pelvis" in texts and "trunk" not in texts, texts  # the Reil body has a pelvis, no trunk


def test_the_motor_figure_is_named_for_what_it_shows(walk):
    assert figures.motor_file(walk) == "joint_targets.png"  # the balance controller has no neurons


def test_the_fitness_graph_says_best_as_the_progress_lines_do(captured):
    history = {"generation": np.arange(5), "best": np.arange(5.0), "mean": np.arange(5.0) / 2}
    figures.fitness_graph(history, "f.png")
    texts = legend_texts(captured[0])
    assert texts == ["best of the generation", "mean of the generation"]


def test_the_stick_figure_times_are_readable(walk, captured):
    figures.stick_figure(walk, "s.png")
    times = [t for t in captured[0].axes[0].texts if t.get_text().endswith(" s")]
    assert times and min(t.get_fontsize() for t in times) >= 8


def test_survivors_sit_in_a_column_without_a_time_scale(captured):
    from evobiped.record.png.robustness_figure import robustness_figure
    from evobiped.analysis.robustness import Trial

    trials = [Trial("push 5 N", f"d{i}", i % 2 == 0, 30.0 if i % 2 == 0 else 5.0 + i, 1.0 + i, 1.0 + i)
              for i in range(8)]
    robustness_figure(trials, "r.png", title="t", seconds=30.0)
    b = captured[0].axes[1]
    labels = [t.get_text() for t in b.get_xticklabels()]
    numbers = [float(x) for x in labels if x.replace(".", "").isdigit()]
    assert max(numbers) <= 30 and labels[-1] == "up all\n30 s"
    up = np.concatenate([c.get_offsets()[:, 0] for c in b.collections if len(c.get_offsets())])
    assert (up > 30).sum() == 4  # the four survivors, right of the time axis
