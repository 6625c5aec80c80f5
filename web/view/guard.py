"""What the page server refuses: websockets from a foreign ``Origin``, and viser's share tunnel.

A page from another site must not drive the view (and through it, a logged-in operator's
session) by opening a websocket to it: the browser sends that site's ``Origin`` with the
handshake. :func:`guard_server` closes every websocket whose ``Origin`` is not the page's
own (the ``Host`` it asked for, over http or https) or one of ``allowed_origins`` (the
public URL behind an HTTPS reverse proxy), before viser sends it anything; and turns off
viser's share-URL tunnel (it would publish the page through a third-party server). What
a websocket it lets in sends is screened before viser reads it (``web.view.inbound``).

viser 1.1.1 has no hook for the handshake, so the check is the first of its connect
callbacks (``_websock_server._client_connect_cb``), which run before any message is sent;
viser is pinned, and tests/web/access/test_access_browser.py holds this to a real websocket.
"""

from __future__ import annotations

import threading
from collections.abc import Iterable
from typing import Any
from urllib.parse import urlsplit

import viser

from s7graph.web.view.inbound import screen_connection

__all__ = ["OriginGuard", "guard_server", "page_open", "same_origin"]

POLICY_VIOLATION = 1008


def _origin_key(url: str) -> tuple[str, str] | None:
    parts = urlsplit(url.strip())
    if parts.scheme not in ("http", "https") or not parts.netloc:
        return None
    return parts.scheme, parts.netloc.lower()


def same_origin(origin: str | None, host: str | None, allowed: Iterable[str] = ()) -> bool:
    """Whether a websocket with ``Origin: origin`` and ``Host: host`` comes from the page
    itself (``http(s)://<host>``) or from one of the ``allowed`` origins."""
    if not origin:
        return False
    key = _origin_key(origin)
    if key is None:
        return False
    if host and key[1] == host.strip().lower():
        return True
    return key in {k for k in map(_origin_key, allowed) if k is not None}


class OriginGuard:
    """The client ids refused so far (a view skips building their panel)."""

    def __init__(self, allowed: Iterable[str] = ()) -> None:
        self.allowed = tuple(allowed)
        self._refused: set[int] = set()
        self._lock = threading.Lock()
        self.refusals = 0

    def refused(self, client_id: int) -> bool:
        with self._lock:
            return client_id in self._refused

    def _refuse(self, client_id: int) -> None:
        with self._lock:
            self._refused.add(client_id)
            self.refusals += 1


def guard_server(server: viser.ViserServer, allowed_origins: Iterable[str] = ()) -> OriginGuard:
    """Refuse foreign-Origin websockets on ``server`` and disable its share tunnel."""
    guard = OriginGuard(allowed_origins)
    ws: Any = server._websock_server  # viser 1.1.1 internals (pinned)

    async def check(connection: Any) -> None:
        live = ws._live_connections.get(connection.client_id)
        if live is None:
            return
        headers = live.request.headers if live.request is not None else {}
        if not same_origin(headers.get("Origin"), headers.get("Host"), guard.allowed):
            guard._refuse(connection.client_id)
            await live.close(POLICY_VIOLATION, "foreign Origin")
            return
        screen_connection(server, connection.client_id, live)

    ws._client_connect_cb.insert(0, check)

    def no_share(*_: object, **__: object) -> None:
        return None

    server.request_share_url = no_share  # type: ignore[method-assign]  # the client's "share" asks this
    server.gui.configure_theme(show_share_button=False)
    return guard


def page_open(page: viser.ClientHandle) -> bool:
    """Whether ``page`` is still connected. A page's connect callback builds its panel
    while the page may already have gone (a peer that connects and closes at once): viser
    runs the disconnect callbacks as the connection ends, so a panel registered after
    them would be kept, and painted, for ever. Check this under the lock that registers
    the panel: viser drops the page from its clients before its disconnect callbacks."""
    server: Any = page._viser_server  # viser 1.1.1 internals (pinned)
    return page.client_id in server._connected_clients
