"""How a watch keeps its CPU: :class:`Link` holds the session a watch joined and tells it,
each change once, when the CPU goes and comes back (its liveliness). A CPU of this machine
joined without ``--connect`` listens on a socket of its own run: one started again listens
on a new one and writes it to its endpoint file (``web.bus.local``). So while the CPU is
gone the link reads that file again every half second, and when it names another endpoint
where the CPU answers, joins there, says the CPU is there (``CPU cpu1 reachable``) and
lets the watch subscribe again on the new client before its lines go on. With
``--connect`` the endpoint stays, and zenoh reconnects by itself.
"""

from __future__ import annotations

import contextlib
import threading
from collections.abc import Callable

import zenoh

from s7graph.web.bus import local
from s7graph.web.bus.client import BusClient
from s7graph.web.bus.protocol import CpuStatus
from s7graph.web.bus.session import open_session, peer_problem
from s7graph.web.cli.net import NetOptions

__all__ = ["POLL_S", "PROBE_S", "Link", "answer"]

POLL_S = 0.5
"""How often a watch whose CPU is not there looks for it again."""
PROBE_S = 1.0
"""How long one look waits for the CPU's status."""


def answer(session: zenoh.Session, cpu: str) -> CpuStatus | None:
    """CPU ``cpu``'s status if it answers a query on ``session`` within :data:`PROBE_S`
    (None: no answer): how a watch's first look and its rejoin alike ask."""
    with BusClient(session, cpu, timeout=PROBE_S) as probe:
        return probe.status()


class Link:
    """The session of a watch on ``net.cpu``, joined at ``endpoint`` of this machine's
    endpoint file (None: at ``--connect``); its current client is :attr:`client`."""

    def __init__(self, net: NetOptions, session: zenoh.Session, endpoint: str | None) -> None:
        self.net, self.session, self.endpoint = net, session, endpoint
        self.client = BusClient(session, net.cpu)
        self._attach: Callable[[BusClient], None] = lambda _: None
        self._alive: Callable[[bool], None] = lambda _: None
        self._up: bool | None = None  # what was said last (None: nothing yet)
        self._said = threading.Lock()  # _up; a zenoh thread's and the looker's
        self._swapping = threading.Lock()  # session, client: the looker's and close's
        self._refused = ""  # an endpoint whose node is not the CPU: not tried again
        self._heard = threading.Event()  # the CPU's liveliness said a first word
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self.client.on_alive(self._seen)  # from the start: a CPU gone before keep is known

    def keep(self, attach: Callable[[BusClient], None], alive: Callable[[bool], None]) -> None:
        """Subscribe with ``attach`` on the client now, and on each new one a CPU started
        again is joined with; ``alive`` hears each change of the CPU's presence once, the
        first (the CPU there, or gone already) before ``attach``."""
        self._heard.wait(PROBE_S)  # it answered: its liveliness says so at once
        with self._said:
            self._alive = alive
            if self._up is not None:
                alive(self._up)
        self._attach = attach
        attach(self.client)
        if self.endpoint is not None:
            self._thread = threading.Thread(target=self._run, name="s7graph-rejoin", daemon=True)
            self._thread.start()

    def close(self) -> None:
        """End the looking, undeclare the client's subscribers and close the session."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=10.0)
        with self._swapping:
            self.client.close()
            self.session.close()  # type: ignore[no-untyped-call]  # zenoh's stub

    def _seen(self, up: bool) -> None:
        """The CPU is there (``up``) or gone: said once a change."""
        with self._said:
            if up == self._up:
                return
            self._up = up
            self._heard.set()
            self._alive(up)

    def _run(self) -> None:
        """While the CPU is not known to be there, look at its endpoint file every
        :data:`POLL_S`."""
        while not self._stop.wait(POLL_S):
            if self._up is True:
                continue
            endpoint = local.find(self.net.cpu)
            if endpoint is not None and endpoint not in (self.endpoint, self._refused):
                self._rejoin(endpoint)

    def _rejoin(self, endpoint: str) -> None:
        """Join the CPU at ``endpoint`` if it answers there; nothing said when not (yet)."""
        try:
            session = open_session(connect=[endpoint], tls=self.net.tls, login=self.net.login)
        except Exception:  # nothing answers there yet: the next look tries again
            return
        if peer_problem(session, self.net.cpu) is not None:
            self._refused = endpoint
        elif answer(session, self.net.cpu) is not None:
            self._swap(session, endpoint)
            return
        with contextlib.suppress(Exception):
            session.close()  # type: ignore[no-untyped-call]  # zenoh's stub

    def _swap(self, session: zenoh.Session, endpoint: str) -> None:
        """Go on with ``session``: the old one closed, the CPU said to be there, then the
        watch subscribed on the new client (its lines after that word)."""
        with self._swapping:
            if self._stop.is_set():
                session.close()  # type: ignore[no-untyped-call]  # zenoh's stub
                return
            self.client.close()
            with contextlib.suppress(Exception):
                self.session.close()  # type: ignore[no-untyped-call]  # zenoh's stub
            self.session, self.endpoint = session, endpoint
            self.client = BusClient(session, self.net.cpu)
        if self._up is None:  # it went before its liveliness said a word
            self._seen(False)
        self._seen(True)
        self._attach(self.client)
        self.client.on_alive(self._seen)
