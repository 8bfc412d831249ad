"""The one TCP reachability check (a Ray cluster, a Rerun viewer) before a library waits on an address for long."""

from __future__ import annotations

import socket


def connect_error(host: str, port: int, timeout: float) -> str | None:
    """Why nothing accepts a TCP connection at ``host:port`` within ``timeout`` s; None when something does."""
    try:
        with socket.create_connection((host, int(port)), timeout=timeout):
            return None
    except OSError as exc:
        return exc.strerror or str(exc)
