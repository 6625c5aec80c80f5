"""The login of one browser page, the same on a chart's panel (``web.view.panel``) and a
program's page (``web.view.program_view``).

Every page is a session of its own: its ``User`` and ``Password`` fields in a Login
folder, ``Log in`` / ``Log out``, and the token the CPU gave it, never seen by another
page. The password is cleared from the page as soon as it is read; a page that goes away
revokes its token. Until it logs in a page is a viewer. Verdicts come back as
notifications on this page only. The login signs the page's commands and its watch
requests (:meth:`PageLogin.watch_token`).
"""

from __future__ import annotations

import threading
from abc import ABC, abstractmethod
from typing import Any

import viser

from s7graph.web.bus.protocol import LoginReply
from s7graph.web.view import texts

__all__ = ["PageLogin", "page_origin"]


def page_origin(client: viser.ClientHandle) -> str:
    """``page <id> (<address>)`` for the audit: which browser page gave a command."""
    address = ""
    try:
        ws: Any = client._viser_server._websock_server  # viser 1.1.1 (pinned)
        conn = ws._live_connections.get(client.client_id)
        if conn is not None and conn.remote_address:
            address = str(conn.remote_address[0])
    except Exception:
        address = ""
    where = f" ({address})" if address else ""
    return f"page {client.client_id}{where}"[:160]


class PageLogin(ABC):
    """A page's login state and folder; the page says how it logs in and out at the CPU
    (``_login``, ``_logout``) and which buttons its role enables (``_enable``)."""

    def _init_login(self, client: viser.ClientHandle, demo: bool) -> None:
        self._page = client
        self._demo = demo
        self.user = self.token = ""
        self.role, self.verified = "viewer", True
        self._lock = threading.Lock()
        self._shown: dict[str, str] = {}
        self.origin = page_origin(client)

    def _build_login(self) -> None:
        """The Login folder: user, password (hidden in demo mode), the two buttons."""
        gui = self._page.gui
        with gui.add_folder("Login"):
            self.user_field = gui.add_text("User", "")
            self.password = gui.add_text("Password", "", visible=not self._demo)
            # viser has no password input: mask the one whose label points at this field
            # (Chromium, Safari, Firefox >= 127 honour -webkit-text-security)
            uid = self.password._impl.uuid
            rule = f".mantine-Flex-root:has(label[for='{uid}']) input{{-webkit-text-security:disc}}"
            gui.add_html(f"<style>{rule}</style>")
            self.login_button = gui.add_button("Log in")
            self.logout_button = gui.add_button("Log out", disabled=True)
            self.who = gui.add_html(texts.login_html("", "", True, self._demo))
        self.login_button.on_click(lambda _: self._log_in())
        self.logout_button.on_click(lambda _: self._log_out())

    def watch_token(self) -> str:
        """The token that signs this page's watch requests: its login's ("": none), so
        the CPU keeps them in its user's own share of the watch queue."""
        with self._lock:
            return self.token

    @abstractmethod
    def _login(self, user: str, password: str) -> LoginReply: ...

    @abstractmethod
    def _logout(self, token: str, user: str) -> None: ...

    @abstractmethod
    def _enable(self) -> None: ...

    def _show_login(self) -> None:
        """The Login folder as the page's state is: logged in or not, as whom."""
        self.login_button.disabled = bool(self.token)
        self.logout_button.disabled = not self.token
        self.user_field.disabled = bool(self.token)
        self.who.content = texts.login_html(
            self.user if self.token else "", self.role, self.verified, self._demo
        )

    def _log_in(self) -> None:
        # the name as typed, on every page: "olga " is refused, never trimmed to "olga"
        user, password = str(self.user_field.value), str(self.password.value)
        self.password.value = ""  # type: ignore[misc]  # never left on the page
        reply = self._login(user, password)
        if not reply.ok:
            self._notify("login refused", reply.reason, ok=False)
            self.who.content = texts.login_html("", "", True, self._demo, reply.reason)
            return
        with self._lock:
            self.user, self.token, self.role = reply.user, reply.token, reply.role
            self.verified = reply.verified
        self._enable()
        self._notify(
            "logged in", texts.login_notice(reply.user, reply.role, reply.verified), ok=True
        )

    def _log_out(self) -> None:
        self._revoke(viewer=True)
        self._enable()

    def _revoke(self, *, viewer: bool = False) -> None:
        """Revoke this page's token at the CPU (the page logs out, or went away);
        ``viewer``: the page is a viewer again."""
        with self._lock:
            token, user, self.token = self.token, self.user, ""
            if viewer:
                self.user, self.role = "", "viewer"
        if token:
            self._logout(token, user)

    def _notify(self, title: str, body: str, *, ok: bool) -> None:
        self._page.add_notification(
            title, body, auto_close_seconds=4.0, color="green" if ok else "red"
        )

    def update_html(self, handle: Any, key: str, content: str) -> None:
        """Send ``content`` to ``handle`` only when it changed."""
        if self._shown.get(key) != content:
            handle.content = content
            self._shown[key] = content
