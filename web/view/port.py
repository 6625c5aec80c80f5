"""Whether a page's port is free, before anything is started on it — without the view
itself (viser): the CPU's process of ``s7graph run --web`` checks the port its view's
process will serve on."""

from __future__ import annotations

import socket

__all__ = ["PortError", "check_port"]


class PortError(ValueError):
    """A page port out of range or taken."""


def check_port(host: str, port: int) -> None:
    """:class:`PortError` if ``port`` is out of range or taken on ``host`` (0: any free one)."""
    if not 0 <= port <= 65535:
        raise PortError(f"--port {port} is out of range (0-65535; 0 picks a free one)")
    if port == 0:
        return
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    with socket.socket(family, socket.SOCK_STREAM) as s:
        # as the page's server binds: connections of a view that just ended (TIME_WAIT)
        # do not make the port busy, a listening server does
        s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            s.bind((host, port))
        except OSError as exc:
            raise PortError(f"port {port} on {host} is in use ({exc.strerror})") from None
