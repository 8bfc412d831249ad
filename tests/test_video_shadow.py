"""The walker's shadow in a video stays under its feet wherever it walks (it was gone a few metres from the start)."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from evobiped.files.genome_file import load_genome

WALKER = Path(__file__).resolve().parent.parent / "docs" / "walkers" / "simbicon_cma_seed5.json"


@pytest.fixture(scope="module")
def walk():
    from evobiped.record.trajectory import record

    genome, cfg, _ = load_genome(WALKER)
    _, traj = record(cfg.build(), genome, seconds=1.0)
    return traj


def test_thirty_metres_on_the_frame_is_the_same_shadow_included(walk):
    """The same pose 30 m further along x (the floor's checks repeat every metre or two) renders the same frame:
    the light went with the walker."""
    from evobiped.record.video import FrameRenderer

    far = walk.qpos.copy()
    far[:, 0] += 30.0  # the free joint's x
    moved = dataclasses.replace(walk, qpos=far)
    fr = FrameRenderer(walk.model, 160, 120)
    try:
        here, there = fr.panel(walk, 0.5, ""), fr.panel(moved, 0.5, "")
    finally:
        fr.close()
    below = slice(40, 120)  # the floor around the feet, under the caption and the horizon
    diff = np.abs(here[below].astype(float) - there[below].astype(float)).mean(axis=-1)
    assert (diff > 30).mean() < 0.002, (diff > 30).mean()
