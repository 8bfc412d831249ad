"""Video of walkers without a display: MuJoCo's offscreen renderer, written as MP4 or GIF and logged to Rerun.

Frames are rendered on the CPU by ``mujoco.Renderer`` through whichever OpenGL
backend :mod:`evobiped.core.glbackend` chose (EGL or OSMesa headless).  Each frame
re-poses the model from a recorded :class:`~.trajectory.Trajectory` (its
``qpos`` rows), so the video shows exactly the replayed episode.  A camera of
type ``mjCAMERA_TRACKING`` follows the walker's trunk (the pelvis) in a raised
three-quarter view from behind (:data:`CAMERA`: 15 degrees above the pelvis, looking
70 degrees to the left of the direction the walker faced at the start, so from
behind it and to its right), and the world's lights move with it so its shadow
stays under its feet for the whole video; the ground
path of the trunk so far is drawn on the floor, a steering walker's sound
sources as orange posts, and the walker's name and the simulated time are
burned into the top-left corner.  Several trajectories (a steering walker's
presentations, one per source) are rendered side by side, at most
:data:`COLUMNS` per row; a walker whose episode ended (a fall) stays in its
last pose, marked "fell".

The file format follows the suffix: ``.mp4`` (H.264 through imageio-ffmpeg,
whose wheel ships an ffmpeg binary) or ``.gif`` (Pillow).  The file is written
whole or not at all (:func:`~evobiped.core.fileio.atomic_write`).
"""

from __future__ import annotations

import io
import os
import tempfile
import warnings
from pathlib import Path

import mujoco
import numpy as np

from ..bodies import body_class
from ..core.errors import UserError
from ..core.fileio import atomic_write
from ..core.glbackend import no_backend_message
from .trajectory import Trajectory

#: frames per second of simulated time (the videos play in real time)
FPS = 25.0
#: default panel size (width, height) in pixels
SIZE = (480, 360)
#: the file suffixes :func:`write_video` writes
SUFFIXES = (".mp4", ".gif")
#: panels per row
COLUMNS = 3
#: s between two points of the drawn ground path
PATH_DT = 0.2
#: camera distance (m), elevation (deg) and azimuth relative to the initial facing (deg)
CAMERA = (3.0, -15.0, 70.0)
_PATH_RGBA = np.array([0.9, 0.35, 0.1, 1.0], np.float32)
_SOURCE_RGBA = np.array([1.0, 0.55, 0.0, 1.0], np.float32)


def check_video_path(path: str | Path) -> Path:
    """``path`` if its suffix is one :func:`write_video` writes and its folder exists; else UserError."""
    path = Path(path)
    if path.suffix.lower() not in SUFFIXES:
        raise UserError(f"--video {path}: the file name must end in {' or '.join(SUFFIXES)} (that picks the format)")
    if path.is_dir():
        raise UserError(f"--video {path} is a directory")
    return path


def frame_times(trajs: list[Trajectory], fps: float = FPS, window: tuple[float, float] | None = None,
                frame_bytes: int = 0) -> np.ndarray:
    """``(F,)`` simulated times (s) of the frames: every 1/``fps`` s over ``window`` (start, end) s, by default
    the whole of the longest trajectory; UserError when ``F`` frames of ``frame_bytes`` each would not fit in a
    quarter of this machine's memory."""
    end = max(float(t.state_time[-1]) for t in trajs)
    t0, t1 = (0.0, end) if window is None else (max(0.0, window[0]), min(end, window[1]))
    if t1 < t0:
        raise UserError(f"--video-window {window[0]:g} {window[1]:g}: the episode ends at {end:g} s")
    return t0 + np.arange(check_frames(t1 - t0, fps, frame_bytes)) / fps


def check_frames(seconds: float, fps: float, frame_bytes: int) -> int:
    """The number of frames of ``seconds`` s of video at ``fps``; UserError when they would not fit, at
    ``frame_bytes`` each, in a quarter of this machine's memory."""
    n = np.floor(seconds * fps + 1e-9) + 1
    room = os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE") / 4
    if n * max(frame_bytes, 8) > room:
        raise UserError(f"--video-fps {fps:g}: {n:.3g} frames over {seconds:g} s would take "
                        f"{n * max(frame_bytes, 8) / 2**30:.3g} GiB, more than this machine can hold "
                        f"({room / 2**30:.3g} GiB): a lower --video-fps, a shorter --video-window or a smaller "
                        "--video-size")
    return int(n)


class FrameRenderer:
    """Renders panels of ``(height, width)`` pixels of trajectories of one model; call :meth:`close` when done."""

    def __init__(self, model: mujoco.MjModel, width: int, height: int):
        most = (int(model.vis.global_.offwidth), int(model.vis.global_.offheight))
        if width > most[0] or height > most[1]:  # MuJoCo's offscreen framebuffer, the model's: not OpenGL's doing
            raise UserError(f"--video-size {width} {height}: a panel may be at most {most[0]} x {most[1]} pixels "
                            "(the model's offscreen framebuffer)")
        try:
            with warnings.catch_warnings():  # GLFW warns before it fails; the failure is the one line below
                warnings.simplefilter("ignore")
                self.renderer = mujoco.Renderer(model, height=int(height), width=int(width))
        except Exception as exc:  # mujoco.FatalError (no context), ValueError (beyond the offscreen buffer), ...
            raise UserError(no_backend_message(exc)) from None
        self.model = model
        self.data = mujoco.MjData(model)
        self.camera = mujoco.MjvCamera()
        self.camera.type = mujoco.mjtCamera.mjCAMERA_TRACKING

    def panel(self, traj: Trajectory, t: float, name: str) -> np.ndarray:
        """``(height, width, 3)`` uint8: ``traj`` at simulated time ``t`` s (its last pose after it ends)."""
        m, d, cam = self.model, self.data, self.camera
        row = int(min(np.searchsorted(traj.state_time, t - 1e-9), len(traj.state_time) - 1))
        d.qpos[:] = traj.qpos[row]
        mujoco.mj_forward(m, d)
        trunk = m.body(body_class(traj.body_name).trunk).id
        # the world's lights travel with the walker: a light's shadow map covers only the ground around the light,
        # so a light left at the origin casts no shadow of a walker a few metres on (foot contact unseen)
        world = m.light_bodyid == 0
        d.light_xpos[world, :2] += d.xpos[trunk, :2]
        cam.trackbodyid = trunk
        distance, elevation, azimuth = CAMERA
        cam.distance, cam.elevation = distance, elevation
        cam.azimuth = float(np.degrees(np.arctan2(traj.start_facing[1], traj.start_facing[0]))) + azimuth
        self.renderer.update_scene(d, cam)
        _draw_path(self.renderer.scene, traj, row)
        image = self.renderer.render().copy()
        ended = t > traj.state_time[-1] + 1e-9
        note = "  fell" if ended and traj.fell else "  (episode over)" if ended else ""
        return _caption(image, [name, f"t = {min(t, traj.state_time[-1]):5.2f} s{note}"])

    def close(self) -> None:
        self.renderer.close()


def render_frames(trajs: list[Trajectory], names: list[str], *, fps: float = FPS, size: tuple[int, int] = SIZE,
                  window: tuple[float, float] | None = None, progress=None,
                  renderer: FrameRenderer | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Frames of the trajectories side by side -> ``(frames (F, H, W, 3) uint8, times (F,) s)``, each panel
    ``size`` = (width, height) pixels, at most :data:`COLUMNS` panels per row (empty panels grey).
    ``progress`` (optional, a :class:`~evobiped.core.progress.Progress`) hears the frames done (restarted here with
    their number); ``renderer`` (optional, of that size): one opened earlier (the caller closes it), else one opened and
    closed here."""
    width, height = size
    cols = min(COLUMNS, len(trajs))
    rows = -(-len(trajs) // cols)
    times = frame_times(trajs, fps, window, frame_bytes=rows * height * cols * width * 3)
    if progress is not None:
        progress.restart(len(times))
    frames = np.full((len(times), rows * height, cols * width, 3), 128, np.uint8)
    fr = renderer or FrameRenderer(trajs[0].model, width, height)
    try:
        for k, t in enumerate(times):
            for j, (traj, name) in enumerate(zip(trajs, names)):
                r, c = divmod(j, cols)
                frames[k, r * height:(r + 1) * height, c * width:(c + 1) * width] = fr.panel(traj, t, name)
            if progress is not None:
                progress.update(k + 1)
    finally:
        if renderer is None:
            fr.close()
    return frames, times


def write_video(path: str | Path, frames: np.ndarray, fps: float = FPS) -> Path:
    """Write ``frames`` ``(F, H, W, 3)`` uint8 to ``path`` (MP4 or GIF by its suffix) whole or not at all."""
    import imageio.v2 as imageio

    path = check_video_path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    if path.suffix.lower() == ".gif":
        buf = io.BytesIO()
        imageio.mimwrite(buf, list(frames), format="GIF", duration=1000.0 / fps, loop=0)
        atomic_write(path, buf.getvalue())
        return path
    # ffmpeg writes a file: a temporary one beside the video (a kill leaves it where the next replay removes it,
    # not in the system's temporary folder), moved into place whole
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp.mp4")
    os.close(fd)
    try:
        with imageio.get_writer(tmp, format="FFMPEG", fps=fps, codec="libx264", macro_block_size=2,
                                ffmpeg_log_level="error", output_params=["-pix_fmt", "yuv420p"]) as w:
            for frame in frames:
                w.append_data(frame)
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    finally:
        Path(tmp).unlink(missing_ok=True)
    return path


def log_frames(rec, frames: np.ndarray, times: np.ndarray, entity: str = "video", quality: int = 80) -> None:
    """The frames as JPEG images on the recording's ``sim_time`` timeline at ``times`` (s), under ``entity``."""
    import rerun as rr
    from PIL import Image

    from .recordings.rerun_recorder import TIMELINE

    blobs = []
    for frame in frames:
        buf = io.BytesIO()
        Image.fromarray(frame).save(buf, format="JPEG", quality=quality)
        blobs.append(buf.getvalue())
    rec.send_columns(entity, indexes=[rr.TimeColumn(TIMELINE, duration=np.asarray(times, float))],
                     columns=rr.EncodedImage.columns(blob=blobs, media_type=["image/jpeg"] * len(blobs)))


def _draw_path(scene, traj: Trajectory, row: int) -> None:
    """Add the trunk's ground path up to state ``row`` (one point per :data:`PATH_DT` s) and the sound
    sources to ``scene`` (an ``mjvScene`` after ``update_scene``), as far as it has room."""
    step = max(1, int(round(PATH_DT / max(traj.dt, 1e-9))))
    pts = traj.planar[: row + 1 : step]
    pts = np.concatenate([pts, traj.planar[row : row + 1]])
    z = 0.004
    for a, b in zip(pts[:-1], pts[1:]):
        if scene.ngeom >= scene.maxgeom or np.allclose(a, b):
            continue
        g = scene.geoms[scene.ngeom]
        mujoco.mjv_initGeom(g, mujoco.mjtGeom.mjGEOM_CAPSULE, np.zeros(3), np.zeros(3), np.zeros(9), _PATH_RGBA)
        mujoco.mjv_connector(g, mujoco.mjtGeom.mjGEOM_CAPSULE, 0.015, np.array([a[0], a[1], z]),
                             np.array([b[0], b[1], z]))
        scene.ngeom += 1
    for s in [] if traj.sources is None else traj.sources:
        if scene.ngeom >= scene.maxgeom:
            break
        g = scene.geoms[scene.ngeom]
        mujoco.mjv_initGeom(g, mujoco.mjtGeom.mjGEOM_CYLINDER, np.array([0.08, 0.08, 0.25]),
                            np.array([s[0], s[1], 0.25]), np.eye(3).ravel(), _SOURCE_RGBA)
        scene.ngeom += 1


def _caption(image: np.ndarray, lines: list[str]) -> np.ndarray:
    """``image`` with ``lines`` written white on a dark outline in its top-left corner."""
    from PIL import Image, ImageDraw, ImageFont

    h = image.shape[0]
    size = max(10, h // 20)
    try:
        font = ImageFont.load_default(size=size)
    except TypeError:  # Pillow < 10.1: the fixed bitmap font
        font = ImageFont.load_default()
    im = Image.fromarray(image)
    draw = ImageDraw.Draw(im)
    for i, line in enumerate(lines):
        draw.text((6, 4 + i * (size + 4)), line, fill=(255, 255, 255), font=font, stroke_width=2,
                  stroke_fill=(20, 20, 20))
    return np.asarray(im)
