"""The face's end of the bus: what it follows, and the threads between zenoh and the OPC
UA server's event loop.

:class:`BusLink` holds the face's zenoh session and a :class:`BusClient` for its queries;
:meth:`BusLink.follow` subscribes (with a client of its own, made again when the CPU
comes back: its change counters start anew) to each FB's state deltas and chart, the
status, the message list, the operands and the diagnostic buffer's new entries, and hands
every message to an :class:`Inbox`; blocking calls — a query, a command waiting for its
durable answer — run on a small pool of threads, never in the event loop. A login
(:meth:`BusLink.login`) makes the session's own :class:`BusClient` (``web.bus.client``:
its public ``login`` and ``send``), whose commands carry that login's token.
"""

from __future__ import annotations

import asyncio
import collections
import contextlib
import functools
import threading
from collections.abc import Callable, Iterable
from concurrent.futures import ThreadPoolExecutor
from typing import Any, Final, TypeVar

import zenoh

from s7graph.web.bus.client import BusClient
from s7graph.web.bus.protocol import AuditEntry, Command, CommandReply, Refusal, refusal_reply
from s7graph.web.opcua.sessions import FaceUser

__all__ = ["BusLink", "Inbox"]

LOGIN_TIMEOUT_S: Final = 3.0
"""How long an OPC UA session's activation waits for the CPU to check its login."""
COMMAND_TIMEOUT_S: Final = 30.0
"""How long a command waits for its answer (a download compiles and waits for a scan)."""
INBOX_LIMIT: Final = 10_000

T = TypeVar("T")


class Inbox:
    """Messages from the bus's threads to the event loop ``loop``, in arrival order; at
    most ``limit`` wait (the oldest go, counted in ``dropped``)."""

    def __init__(self, loop: asyncio.AbstractEventLoop, limit: int = INBOX_LIMIT) -> None:
        self._loop = loop
        self._lock = threading.Lock()
        self._items: collections.deque[tuple[str, str, Any]] = collections.deque()
        self._limit = limit
        self._woken = False
        self._event = asyncio.Event()
        self.dropped = 0

    def put(self, kind: str, key: str, message: Any) -> None:
        """Hand ``message`` (of ``kind``, about ``key``: an FB or "") to the loop; any
        thread."""
        with self._lock:
            if len(self._items) >= self._limit:
                self._items.popleft()
                self.dropped += 1
            self._items.append((kind, key, message))
            wake, self._woken = not self._woken, True
        if wake:
            with contextlib.suppress(RuntimeError):  # the loop is closed: nobody waits
                self._loop.call_soon_threadsafe(self._event.set)

    async def take(self) -> list[tuple[str, str, Any]]:
        """What came since the last call, oldest first (waits for at least one)."""
        await self._event.wait()
        self._event.clear()
        with self._lock:
            items = list(self._items)
            self._items.clear()
            self._woken = False
        return items


class BusLink:
    """The face's bus: ``session`` (the caller's to close) and CPU ``cpu``."""

    def __init__(self, session: zenoh.Session, cpu: str, *, workers: int = 8) -> None:
        self.session = session
        self.cpu = cpu
        self.reader = BusClient(session, cpu)
        self._follower: BusClient | None = None
        self._lock = threading.Lock()
        self._pool = ThreadPoolExecutor(max_workers=workers, thread_name_prefix="s7graph-opcua-bus")

    async def ask(self, fn: Callable[..., T], *args: Any) -> T:
        """``fn(*args)`` on a thread of the pool (a blocking query of the bus)."""
        return await asyncio.get_running_loop().run_in_executor(self._pool, fn, *args)

    def watch_alive(self, inbox: Inbox) -> None:
        """``("alive", "", up)`` into ``inbox`` when the CPU's bus comes or goes."""
        self.reader.on_alive(lambda up: inbox.put("alive", "", up))

    def follow(self, inbox: Inbox, fbs: Iterable[str]) -> None:
        """Follow the CPU anew (blocking: each FB's state is fetched): every message into
        ``inbox`` as ``(kind, fb or "", message)``; a former following ends."""
        client = BusClient(self.session, self.cpu)
        with self._lock:
            old, self._follower = self._follower, client
        if old is not None:
            old.close()
        client.on_status(lambda s: inbox.put("status", "", s))
        client.on_alarms(lambda a: inbox.put("alarms", "", a))
        client.on_operands(lambda v: inbox.put("operands", "", v))
        client.on_diag(lambda d: inbox.put("diag", "", d))
        client.on_audit(functools.partial(_acknowledged, inbox))  # others' comments
        for fb in fbs:
            client.on_chart(fb, functools.partial(inbox.put, "chart", fb))
            client.follow(fb, functools.partial(inbox.put, "state", fb))

    def login(self, user: str, password: str, origin: str) -> FaceUser | str:
        """Log ``user`` in at the CPU (blocking, at most ``LOGIN_TIMEOUT_S``): the
        session's user, with a bus client of its own, or why not."""
        client = BusClient(self.session, self.cpu, timeout=LOGIN_TIMEOUT_S)
        reply = client.login(user, password, origin=origin)
        if not reply.ok:
            client.close()
            return reply.reason or "refused"
        return FaceUser(
            name=user,
            bus_role=reply.role,
            token=reply.token,
            verified=reply.verified,
            client=client,
            origin=origin,
        )

    def logout(self, user: FaceUser) -> None:
        """End ``user``'s login at the CPU (on the pool: never waits)."""
        client = user.client
        if not isinstance(client, BusClient) or not user.token:
            return
        token, user.token = user.token, ""

        def out() -> None:
            with contextlib.suppress(Exception):
                client.logout(token, user=user.name or "", origin=user.origin)
            client.close()

        with contextlib.suppress(RuntimeError):  # the pool is shut down
            self._pool.submit(out)

    async def send(self, user: FaceUser, command: Command) -> CommandReply:
        """``command`` under ``user``'s login, answered when the CPU says (durable)."""
        client = user.client
        if not isinstance(client, BusClient):
            return refusal_reply(Refusal("access", "not logged in: log in first (no token)"))
        return await self.ask(lambda: client.send(command, timeout=COMMAND_TIMEOUT_S))

    def close(self) -> None:
        with self._lock:
            follower, self._follower = self._follower, None
        if follower is not None:
            follower.close()
        self.reader.close()
        self._pool.shutdown(wait=False, cancel_futures=True)


def _acknowledged(inbox: Inbox, row: AuditEntry) -> None:
    """An applied acknowledgement's audit row into ``inbox`` as ``("audit", "", row)``;
    the other rows never (a flood of commands must not push state deltas out)."""
    if row.op == "ack_msg" and row.outcome == "applied":
        inbox.put("audit", "", row)
