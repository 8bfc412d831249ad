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

A ``MUJOCO_GL`` that MuJoCo's import would stop at (a value it does not take, or
``egl``/``osmesa`` without its library) is set aside by :func:`choose`:
``MUJOCO_GL`` becomes ``disable``, so every command that renders nothing runs,
and a renderer says in one line what was set and how to fix it.
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


#: the ``MUJOCO_GL`` values MuJoCo's import takes (``DISABLED``: no rendering), and those of each system besides
DISABLED = ("disable", "disabled", "off", "false", "0")
VALID = (*DISABLED, "enable", "enabled", "on", "true", "1", "glfw", "")
SYSTEM_VALID = {"linux": ("glx", "egl", "osmesa"), "win32": ("wgl",), "darwin": ("cgl",)}
#: a ``MUJOCO_GL`` set aside by :func:`choose`: (the value, why MuJoCo's import would stop at it); None: none was
SET_ASIDE: tuple[str, str] | None = None


def rejected(value: str, platform: str | None = None, loadable=_loadable) -> str | None:
    """Why ``import mujoco`` would stop at ``MUJOCO_GL=value`` on ``platform`` (default ``sys.platform``): a value
    MuJoCo does not take, or a headless backend whose library does not load; None when it would not."""
    platform = sys.platform if platform is None else platform
    v = value.lower().strip()
    valid = VALID + next((extra for name, extra in SYSTEM_VALID.items() if platform.startswith(name)), ())
    if v not in valid:
        return f"MuJoCo takes {', '.join(x for x in valid if x)}"
    if v in LIBRARIES and platform.startswith("linux") and not loadable(LIBRARIES[v]):
        return f"{LIBRARIES[v][0]} does not load"
    return None


def choose() -> str | None:
    """Set ``MUJOCO_GL`` to :func:`pick`'s backend if it is unset and ``mujoco`` is not imported yet, or to
    ``disable`` if MuJoCo's import would stop at its value (:data:`SET_ASIDE`); the backend."""
    global SET_ASIDE
    if "mujoco" in sys.modules:
        return os.environ.get("MUJOCO_GL")
    if "MUJOCO_GL" in os.environ:
        why = rejected(os.environ["MUJOCO_GL"])
        if why is not None:
            SET_ASIDE = (os.environ["MUJOCO_GL"], why)
            os.environ["MUJOCO_GL"] = DISABLED[0]
        return os.environ["MUJOCO_GL"]
    backend = pick()
    if backend is not None:
        os.environ["MUJOCO_GL"] = backend
    return backend


#: how to get a renderer without a display
FIX = ("without a display install Mesa's EGL or OSMesa (apt-get install libegl1, or libosmesa6) "
       "or set MUJOCO_GL=egl or MUJOCO_GL=osmesa")


def no_backend_message(exc: BaseException) -> str:
    """The one line for a renderer that could not start (``exc``: what ``mujoco.Renderer`` raised)."""
    if SET_ASIDE is not None:
        value, why = SET_ASIDE
        return (f"cannot render frames: MUJOCO_GL={value} cannot be used here ({why}); unset MUJOCO_GL to have a "
                f"backend chosen, or {FIX}")
    first = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
    backend = os.environ.get("MUJOCO_GL")
    how = f"MUJOCO_GL={backend}" if backend else "MUJOCO_GL unset (import evobiped before mujoco to have it chosen)"
    return f"cannot render frames: no OpenGL context could be made ({how}: {first}); {FIX}"
