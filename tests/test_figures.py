"""Figures: bounded pixel size whatever the episode length, side views along the initial facing."""

import numpy as np
import pytest

from evobiped.episode import EpisodeConfig
from evobiped.record import figures
from evobiped.record.trajectory import record

pytest.importorskip("matplotlib")
MAX_PX = (figures.MAX_SIZE[0] * figures.DPI + 200, figures.MAX_SIZE[1] * figures.DPI + 200)  # + the tight bounding box's margins


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
