"""Figures: bounded pixel size whatever the episode length, side views along the initial facing."""

import numpy as np
import pytest

from evobiped.episode import EpisodeConfig
from evobiped.record.png import figures
from evobiped.record.trajectory import record

pytest.importorskip("matplotlib")
# + the tight bounding box's margins
MAX_PX = (figures.MAX_SIZE[0] * figures.DPI + 200, figures.MAX_SIZE[1] * figures.DPI + 200)


def png_size(path) -> tuple[int, int]:
    with open(path, "rb") as f:
        head = f.read(24)
    assert head[:8] == b"\x89PNG\r\n\x1a\n"
    return int.from_bytes(head[16:20], "big"), int.from_bytes(head[20:24], "big")


@pytest.fixture(scope="module")
def long_walk():
    """A walker that cannot fall, 40 s: the length that made the stick figure thousands of pixels wide."""
    ep = EpisodeConfig(seconds=40.0, body_options={"fall_height": 0.01, "fall_tilt": 3.14159}).build()
    lay = ep.controller.layout
    g = lay.sample(np.random.default_rng(5))
    return record(ep, g)[1]


def test_every_replay_figure_has_a_bounded_size(long_walk, tmp_path):
    history = {"generation": np.arange(300), "best": np.linspace(0, 3, 300), "mean": np.linspace(0, 1, 300)}
    paths = figures.replay_figures(long_walk, tmp_path, history=history)
    assert len(paths) == 5
    for p in paths:
        w, h = png_size(p)
        assert 300 < w <= MAX_PX[0] and 200 < h <= MAX_PX[1], (p.name, w, h)


def test_save_figure_shrinks_an_oversized_figure(tmp_path):
    plt = figures.pyplot()
    fig, ax = plt.subplots(figsize=(80, 3))
    ax.plot([0, 1], [0, 1])
    w, h = png_size(figures.save_figure(fig, tmp_path / "wide.png"))
    assert w <= MAX_PX[0] and h < 3 * figures.DPI


def test_side_views_look_along_the_initial_facing_not_the_travel(long_walk):
    np.testing.assert_allclose(figures._side_axis(long_walk), long_walk.start_facing)
    np.testing.assert_allclose(np.linalg.norm(long_walk.start_facing), 1.0)
    # the text every figure carries agrees with the displacement it describes
    d = long_walk.planar[-1] - long_walk.planar[0]
    assert figures.walk_text(long_walk).startswith(f"{np.linalg.norm(d):.2f} m, ")


@pytest.fixture
def captured(monkeypatch):
    """The matplotlib figures the figure functions save, kept open for inspection (nothing written)."""
    import evobiped.record.png.robustness_figure as rf  # imported unpatched: it binds figures.save_figure when imported

    figs = []

    def keep(fig, path, **kw):
        figs.append(fig)
        return path

    monkeypatch.setattr(figures, "save_figure", keep)
    monkeypatch.setattr(rf, "save_figure", keep)
    yield figs
    figures.pyplot().close("all")


def _px_per_m(ax) -> tuple[float, float]:
    ax.figure.canvas.draw()
    (x0, y0), (x1, _), (_, y1) = ax.transData.transform([[0, 0], [1, 0], [0, 1]])
    return x1 - x0, y1 - y0


def test_a_path_on_the_ground_has_equal_scales(long_walk, captured):
    figures.ground_trajectory(long_walk, "g.png", who="walker W, run seed 3")
    ax = captured[0].axes[0]
    sx, sy = _px_per_m(ax)
    assert sx == pytest.approx(sy, rel=1e-6)  # a 3 deg drift looks like 3 deg
    assert "walker W, run seed 3" in ax.get_title()
    # the start and end markers sit above the path
    lines = ax.get_lines()
    path_z = max(l.get_zorder() for l in lines if len(l.get_xdata()) > 2)
    assert all(l.get_zorder() > path_z for l in lines if len(l.get_xdata()) == 1 and l.get_alpha() != 0.0)


def test_the_fitness_graph_ends_on_a_tick_at_the_last_generation(captured):
    h = {"generation": np.arange(150), "best": np.linspace(0, 30, 150), "mean": np.linspace(0, 10, 150)}
    figures.fitness_graph(h, "f.png", ylabel="fitness (m): (forward + 5 m) × time up / T", who="w")
    ax = captured[0].axes[0]
    ticks = ax.get_xticks()
    assert ticks[-1] == 149 and ax.get_xlim() == (0, 149) and list(ticks) == sorted(set(ticks))
    assert "×" in ax.get_ylabel() and " x " not in ax.get_ylabel()


def test_the_motion_sequence_is_one_steady_stride_in_one_window(captured):
    """A walker that steps: the frames span one stride after 10 s, exactly evenly spaced (the spacing in the
    title), every panel the same x window."""
    from evobiped.files.genome_file import load_genome
    from pathlib import Path

    genome, cfg, _ = load_genome(Path(
        __file__).resolve().parent.parent / "docs" / "walkers" / "simbicon_cma_seed5.json")
    _, traj = record(cfg.build(), genome, seconds=12.5)
    t0, t1, what = figures.steady_stride(traj)
    assert 10.0 <= t0 < t1 < 12.5 and 0.3 < t1 - t0 < 2.0 and what.startswith("one stride")
    figures.motion_sequence(traj, "m.png")
    fig = captured[0]
    panels = [ax for ax in fig.axes if ax.axison]
    times = [float(ax.get_title().split("=")[1].split()[0]) for ax in panels]
    gaps = np.diff(times)
    assert times[0] == pytest.approx(t0, abs=0.02) and t1 - gaps[0] < times[-1] <= t1 + 1e-9
    assert np.allclose(gaps, gaps[0], atol=1e-6) and f"one frame every {gaps[0]:.2f} s" in fig._suptitle.get_text()
    assert len({ax.get_xlim() for ax in panels}) == 1  # one shared window
    assert "joint target" not in fig._suptitle.get_text().lower()
    # a controller that commands joint targets is labelled so, not as neurons
    figures.motor_activations(traj, "n.png")
    assert "Joint target angles" in captured[1]._suptitle.get_text()


def test_stick_figures_are_spaced_apart(long_walk, captured):
    figures.stick_figure(long_walk, "s.png", spacing=0.3)
    ax = captured[0].axes[0]
    n = int(ax.get_title().split("(")[1].split()[0])  # "(K in the ...)"
    assert 2 <= n <= 16


def test_the_robustness_figure_decodes_its_markers_and_spreads_the_survivors(captured):
    from evobiped.record.png.robustness_figure import robustness_figure
    from evobiped.analysis.robustness import Trial

    trials = [Trial("push 5 N", f"p{i}", True, 30.0, 10.0, 10.0) for i in range(20)]
    trials += [Trial("push 5 N", "down", False, 12.0, 3.0, 3.0), Trial("friction", "mu = 0.5", True, 30.0, 9.0, 9.0),
               Trial("slope", "+3 % (uphill)", False, 20.0, 5.0, 5.0)]
    robustness_figure(trials, "r.png", title="battery", seconds=30.0)
    b = captured[0].axes[1]
    labels = [t.get_text() for t in b.get_legend().get_texts()]
    assert {"push 5 N", "friction", "slope", "still up at the end", "fell (at its time up)"} <= set(labels)
    up = np.concatenate([c.get_offsets()[:, 0] for c in b.collections if len(c.get_offsets())
                         and c.get_offsets()[0, 1] in (10.0, 9.0)])
    assert len(np.unique(up)) == 21 and up.min() >= 30.0  # 21 survivors, 21 distinct places in the band
    a = captured[0].axes[0]
    said = "\n".join(t.get_text() for t in a.texts) + "\n".join(t.get_text() for t in a.get_yticklabels())
    assert "mu = 0.5: up" in said and "+3 % (uphill): fell at 20.0 s" in said


def test_the_study_fitness_plot_tells_its_runs_apart(monkeypatch):
    from evobiped.experiments.reil import study_figures

    figs = []
    monkeypatch.setattr(study_figures, "save_figure", lambda fig, path: figs.append(fig) or path)
    h = {"generation": np.arange(5), "best": np.arange(5.0)}
    study_figures.fitness_graphs({"forward": [h, h, h]}, "f.png", seeds=[0, 1, 2])
    ax = figs[0].axes[0]
    assert len({tuple(l.get_color()) for l in ax.get_lines()}) == 3
    assert [t.get_text() for t in ax.get_legend().get_texts()] == ["seed 0", "seed 1", "seed 2"]
    assert "\n" not in ax.get_title()  # one title per panel, under the one figure title
    assert "×" in ax.get_ylabel()
    figures.pyplot().close("all")
