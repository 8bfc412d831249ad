"""Video without a display: the backend choice, frames of a real walker, the tracking camera, MP4/GIF files,
one clear line when no OpenGL context can be made, and a sky that leaves the physics alone."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import mujoco
import numpy as np
import pytest

from evobiped.core.errors import UserError
from evobiped.files.genome_file import load_genome
from evobiped.core.glbackend import pick
from evobiped.physics.models import model_path

from .conftest import cli

ROOT = Path(__file__).resolve().parent.parent
WALKER = ROOT / "docs" / "walkers" / "simbicon_cma_seed5.json"  # a forward walker: 1.5 m in its first 3 s


def _python(args: list[str], **env) -> subprocess.CompletedProcess:
    """``python ARGS`` without a display, MUJOCO_GL only as given."""
    e = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY", "MUJOCO_GL")}
    e.update(PYTHONPATH=str(ROOT), **env)
    return subprocess.run([sys.executable, *args], capture_output=True, text=True, env=e, timeout=120, cwd=ROOT)


@pytest.mark.parametrize("environ, libs, want", [
    ({"MUJOCO_GL": "osmesa", "DISPLAY": ":0"}, {"egl"}, "osmesa"),  # the user's choice wins
    ({"DISPLAY": ":0"}, {"egl", "osmesa"}, "glfw"),
    ({"WAYLAND_DISPLAY": "wayland-0"}, set(), "glfw"),
    ({}, {"egl", "osmesa"}, "egl"),
    ({}, {"osmesa"}, "osmesa"),
    ({}, set(), None),
])
def test_the_backend_is_a_displays_glfw_else_egl_else_osmesa(environ, libs, want):
    from evobiped.core.glbackend import LIBRARIES

    loadable = lambda names: any(names == LIBRARIES[b] for b in libs)  # noqa: E731
    assert pick(environ, "linux", loadable) == want
    assert pick({}, "darwin", loadable) is None  # macOS's own context needs no display


@pytest.fixture(scope="module")
def walk():
    """The first 2 s of a forward walker, recorded."""
    from evobiped.record.trajectory import record

    genome, cfg, _ = load_genome(WALKER)
    _, traj = record(cfg.build(), genome, seconds=2.0)
    return traj


def test_frames_show_the_walker_under_a_sky_and_the_camera_tracks_the_pelvis(walk):
    from evobiped.record.video import FrameRenderer

    fr = FrameRenderer(walk.model, 96, 72)
    pelvis = walk.model.body("pelvis").id
    try:
        first = fr.panel(walk, 0.0, "w")
        lookat0 = fr.camera.lookat.copy()
        assert np.allclose(lookat0, fr.data.subtree_com[pelvis])
        last = fr.panel(walk, 2.0, "w")
        lookat1 = fr.camera.lookat.copy()
        assert np.allclose(lookat1, fr.data.subtree_com[pelvis])
    finally:
        fr.close()
    moved = walk.body_pos[-1, pelvis, :2] - walk.body_pos[0, pelvis, :2]
    assert np.linalg.norm(moved) > 0.5  # the walker walked ...
    assert np.linalg.norm((lookat1 - lookat0)[:2] - moved) < 0.15  # ... and the camera went with it
    for image in (first, last):
        assert image.shape == (72, 96, 3) and image.dtype == np.uint8
        sky = image[int(0.25 * 72):int(0.3 * 72), 60:].astype(float)  # right of the caption, above the horizon
        assert sky.mean() > 150 and sky[..., 2].mean() > sky[..., 0].mean()  # light and bluish, not black
        assert image.std() > 20  # a scene, not a blank


def test_presentations_side_by_side_and_the_time_burned_in(walk):
    from evobiped.record.video import render_frames

    frames, times = render_frames([walk, walk], ["a", "b"], fps=2.0, size=(64, 48))
    assert np.allclose(times, [0.0, 0.5, 1.0, 1.5, 2.0])
    assert frames.shape == (5, 48, 128, 3)
    # the same walker twice: below the names, the same
    below = (frames[:, 30:, :64] != frames[:, 30:, 64:]).any(axis=-1)
    assert below.mean() < 0.002  # panels (but for a stray rasterised pixel)
    assert not np.array_equal(frames[:, :20, :64], frames[:, :20, 64:])  # each panel named
    corner = (slice(0, 24), slice(0, 40))  # where the name and the time are written
    assert not np.array_equal(frames[0][corner], frames[2][corner])
    frames2, times2 = render_frames([walk], ["a"], fps=4.0, size=(64, 48), window=(1.0, 1.5))
    assert np.allclose(times2, [1.0, 1.25, 1.5])
    assert (frames2[0] != frames[2, :, :64]).any(axis=-1).mean() < 0.002  # t = 1 s either way


@pytest.mark.parametrize("suffix", [".gif", ".mp4"])
def test_video_files_hold_every_frame(tmp_path, suffix):
    import imageio.v2 as imageio

    from evobiped.record.video import write_video

    frames = np.zeros((6, 48, 64, 3), np.uint8)
    frames[:, :, :, 2] = np.arange(6)[:, None, None] * 40  # blue rising frame by frame
    out = write_video(tmp_path / f"v{suffix}", frames, fps=10)
    back = np.stack([np.asarray(f)[..., :3] for f in imageio.mimread(out, memtest=False)])
    assert back.shape == frames.shape
    assert np.abs(back[..., 2].mean(axis=(1, 2)) - np.arange(6) * 40).max() < 8
    assert [p.name for p in tmp_path.iterdir()] == [out.name]  # no temporary left behind


def test_replay_video_end_to_end_and_into_the_recording(tmp_path, capsys):
    rc = cli("replay", WALKER, "--seconds", "0.4", "--out", tmp_path / "r.rrd", "--video", tmp_path / "w.gif",
             "--video-size", "64", "48", "--video-fps", "10", "--quiet")
    assert rc == 0
    import imageio.v2 as imageio

    assert len(imageio.mimread(tmp_path / "w.gif")) == 5  # t = 0, 0.1, ..., 0.4 s
    assert f"video: {tmp_path / 'w.gif'}" in capsys.readouterr().out
    assert b"image/jpeg" in (tmp_path / "r.rrd").read_bytes()  # the frames are in the recording too


@pytest.mark.parametrize("args, words", [
    (["--video", "w.avi"], "must end in .mp4 or .gif"),
    (["--video", "w.gif", "--video-size", "63", "48"], "must be even"),
    (["--video-fps", "5"], "give --video FILE too"),
    (["--video", "w.gif", "--video-window", "3", "1"], "0 <= T0 < T1"),
])
def test_bad_video_flags_are_one_line_and_write_nothing(tmp_path, capsys, args, words):
    os.chdir(tmp_path)
    assert cli("replay", WALKER, "--seconds", "0.2", "--out", tmp_path / "r.rrd", *args) == 2
    err = capsys.readouterr().err
    assert words in err and err.count("\n") == 1
    assert list(tmp_path.iterdir()) == []


def test_no_opengl_context_is_one_clear_line_and_no_file(tmp_path):
    """GLFW without a display is what a headless machine gives when nothing else is chosen."""
    r = _python(["-m", "evobiped", "replay", str(WALKER), "--seconds", "0.2", "--out", str(tmp_path / "r.rrd"),
                 "--video", str(tmp_path / "w.mp4"), "--quiet"], MUJOCO_GL="glfw")
    assert r.returncode == 2, r.stderr
    assert r.stderr.count("\n") == 1 and "cannot render frames: no OpenGL context" in r.stderr
    assert "MUJOCO_GL=glfw" in r.stderr and "libosmesa6" in r.stderr
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("stem", ["reil_biped", "taga_biped"])
def test_the_sky_and_the_floor_grid_leave_the_physics_alone(stem):
    """The model against itself without its <asset> block: only drawing fields (textures, materials, names) differ."""
    text = model_path(stem).read_text()
    bare = re.sub(r"<asset>.*?</asset>", "", text, flags=re.S).replace(' material="grid"', "")
    assert bare != text
    a, b = mujoco.MjModel.from_xml_string(text), mujoco.MjModel.from_xml_string(bare)
    assert a.ntex == 2 and b.ntex == 0
    drawing = ("tex_", "mat_", "name_", "names", "geom_matid", "ntex", "nmat", "nnames", "nbuffer", "signature")
    compared = 0
    for k in dir(a):
        if k.startswith("_") or k.startswith(drawing):
            continue
        x, y = getattr(a, k), getattr(b, k)
        if isinstance(x, np.ndarray):
            assert x.shape == y.shape and np.array_equal(x, y, equal_nan=True), k
            compared += 1
        elif isinstance(x, (int, float)):
            assert x == y, k
    assert compared > 100
    for k in ("timestep", "gravity", "integrator", "impratio", "cone"):
        assert np.array_equal(getattr(a.opt, k), getattr(b.opt, k))


def test_a_video_path_names_its_format():
    from evobiped.record.video import check_video_path

    assert check_video_path("a/b.MP4").suffix == ".MP4"
    with pytest.raises(UserError, match="must end in"):
        check_video_path("walker.webm")
