"""Streaming to a running Rerun viewer: addresses, a reachability check, a bounded flush.

Rerun's gRPC sink retries silently and its flush waits forever when no
viewer listens, so we check the address first and flush with a time limit;
both failures are a :class:`~evobiped.core.errors.UserError` (one line, exit 2).
"""

from __future__ import annotations

from urllib.parse import urlparse

from ...core.errors import UserError
from ...core.net import connect_error

DEFAULT_ADDR = "127.0.0.1:9876"
#: seconds to wait for a viewer to take the data
FLUSH_TIMEOUT = 30.0


def connect_url(addr: str | None) -> str:
    """``host:port`` (default 127.0.0.1:9876) or a full ``rerun+http://host:port/proxy`` URL -> the URL."""
    addr = addr or DEFAULT_ADDR
    return addr if "://" in addr else f"rerun+http://{addr}/proxy"


def require_viewer(url: str, *, timeout: float = 2.0) -> None:
    """UserError unless something accepts TCP connections at the URL's host and port."""
    u = urlparse(url)
    try:
        host, port = u.hostname, u.port or 9876
    except ValueError:
        raise UserError(f"bad viewer address {url!r} (expected HOST:PORT)") from None
    if not host:
        raise UserError(f"bad viewer address {url!r} (expected HOST:PORT)")
    why = connect_error(host, port, timeout)
    if why is not None:
        raise UserError(f"no Rerun viewer at {host}:{port} ({why}); start one with `rerun` or use --spawn")


def require_display() -> None:
    """UserError (at once) when a spawned viewer could not open a window: Linux without X11 or Wayland."""
    import os
    import sys

    if sys.platform.startswith("linux") and not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        raise UserError("cannot spawn a Rerun viewer: no display here (DISPLAY and WAYLAND_DISPLAY are unset); "
                        "write a file with --out and open it with `rerun FILE` where there is a screen, or --connect "
                        "to a viewer")


def flush(rec, *, streaming: bool) -> None:
    """Flush ``rec`` (bounded when streaming to a viewer) and close its sinks."""
    try:
        if streaming:
            rec.flush(timeout_sec=FLUSH_TIMEOUT)
        else:
            rec.flush()
    except RuntimeError as exc:
        raise UserError(f"could not send the recording to the viewer: {str(exc).splitlines()[0]}") from None
    rec.disconnect()
