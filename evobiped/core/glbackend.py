"""Which OpenGL backend MuJoCo's offscreen renderer uses, chosen before ``mujoco`` is imported.

MuJoCo reads ``MUJOCO_GL`` once, when ``mujoco`` is imported, and builds its
rendering context from it (``glfw``: a window system; ``egl``: a headless GPU or
Mesa's software EGL; ``osmesa``: Mesa's software rasteriser).  Without it, MuJoCo
tries GLFW, which needs a display.  :func:`choose` fills it in when it is unset,
as dm_control does: a display's GLFW, else EGL, else OSMesa, whichever is
installed (``libEGL.so.1`` ships with most Linux desktops and with Mesa's
``libegl1``; OSMesa with ``libosmesa6``).  ``evobiped/__init__.py`` calls it, so
every entry point (the command, the Gymnasium environments, worker processes)
decides before anything imports ``mujoco``; a program that imported ``mujoco``
earlier keeps whatever MuJoCo chose then.

:func:`no_backend_message` is the one line a renderer that failed to start
becomes.
"""

from __future__ import annotations

import ctypes
import os
import sys

#: the libraries each headless backend loads (the first that opens wins)
LIBRARIES = {"egl": ("libEGL.so.1", "libEGL.so"), "osmesa": ("libOSMesa.so.8", "libOSMesa.so.6", "libOSMesa.so")}


def _loadable(names) -> bool:
    for name in names:
        try:
            ctypes.CDLL(name)
            return True
        except OSError:
            pass
    return False


def pick(environ=None, platform: str | None = None, loadable=_loadable) -> str | None:
    """The backend for ``environ`` (default ``os.environ``) on ``platform`` (default ``sys.platform``):
    ``MUJOCO_GL`` when set, else ``"glfw"`` with a display, else ``"egl"`` or ``"osmesa"`` if its library
    loads, else None (no headless backend: rendering will fail with :func:`no_backend_message`).
    Not Linux: None (MuJoCo's own default, a window system's context, works there without a display)."""
    environ = os.environ if environ is None else environ
    platform = sys.platform if platform is None else platform
    if environ.get("MUJOCO_GL"):
        return environ["MUJOCO_GL"]
    if not platform.startswith("linux"):
        return None
    if environ.get("DISPLAY") or environ.get("WAYLAND_DISPLAY"):
        return "glfw"
    for backend, names in LIBRARIES.items():
        if loadable(names):
            return backend
    return None


def choose() -> str | None:
    """Set ``MUJOCO_GL`` to :func:`pick`'s backend if it is unset and ``mujoco`` is not imported yet; the backend."""
    if "MUJOCO_GL" in os.environ or "mujoco" in sys.modules:
        return os.environ.get("MUJOCO_GL")
    backend = pick()
    if backend is not None:
        os.environ["MUJOCO_GL"] = backend
    return backend


def no_backend_message(exc: BaseException) -> str:
    """The one line for a renderer that could not start (``exc``: what ``mujoco.Renderer`` raised)."""
    first = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
    backend = os.environ.get("MUJOCO_GL")
    how = f"MUJOCO_GL={backend}" if backend else "MUJOCO_GL unset (import evobiped before mujoco to have it chosen)"
    return (f"cannot render frames: no OpenGL context could be made ({how}: {first}); "
            "without a display install Mesa's EGL or OSMesa (apt-get install libegl1, or libosmesa6) "
            "or set MUJOCO_GL=egl or MUJOCO_GL=osmesa")
