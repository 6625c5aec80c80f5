"""What the scan thread publishes, encoded and put on the bus by a thread of its own.

The scan thread only decides that a message goes out and queues it (a few hundred
nanoseconds); :class:`Outbox`'s thread encodes it (``seq`` set then, if given) and puts it
on its zenoh publisher, in the order queued. A put that blocks — a congested link, a slow
subscriber under ``CongestionControl.BLOCK`` — holds up this thread, never a scan. While
more than ``limit`` messages wait, new ones are dropped and counted (``dropped``): a view
sees the gap in ``seq`` and goes on from the next state, which is whole.
"""

from __future__ import annotations

import queue
import threading
from typing import Any, Protocol

import msgspec

from s7graph.web.bus.protocol import encode

__all__ = ["OUTBOX_LIMIT", "Outbox", "Sink"]

OUTBOX_LIMIT = 20_000
"""Messages waiting at most (at 200 deltas a scan, 100 scans' worth)."""

_STOP = None


class Sink(Protocol):
    """Where the outbox puts a message: a zenoh publisher, or a query answered later
    (``web.bus.publisher.QueryReply``)."""

    def put(self, payload: bytes) -> object: ...


class Outbox:
    """A queue of ``(sink, message, seq)`` and the thread that sends it; :meth:`close`
    sends what is queued, then stops the thread."""

    def __init__(self, *, limit: int = OUTBOX_LIMIT, name: str = "s7graph-bus-out") -> None:
        self._queue: queue.SimpleQueue[tuple[Sink, msgspec.Struct, int | None] | None]
        self._queue = queue.SimpleQueue()
        self._limit = limit
        self.sent = 0
        self.dropped = 0
        self.failed = 0
        self._thread = threading.Thread(target=self._run, name=name, daemon=True)
        self._thread.start()

    def post(self, publisher: Sink, message: Any, seq: int | None = None) -> bool:
        """Queue ``message`` (with ``seq`` replaced, if given) for ``publisher``; False if
        it was dropped because too many wait."""
        q = self._queue
        if q.qsize() >= self._limit:
            self.dropped += 1
            return False
        q.put((publisher, message, seq))
        return True

    def pending(self) -> int:
        """Messages queued and not yet sent (about)."""
        return self._queue.qsize()

    def close(self, timeout: float = 2.0) -> None:
        """Send what is queued (for at most ``timeout`` s), then end the thread."""
        if self._thread.is_alive():
            self._queue.put(_STOP)
            self._thread.join(timeout)

    def _run(self) -> None:
        get = self._queue.get
        replace = msgspec.structs.replace
        while True:
            item = get()
            if item is None:
                return
            publisher, message, seq = item
            try:
                publisher.put(encode(message if seq is None else replace(message, seq=seq)))
            except Exception:  # a closed session, an undeclared publisher: never raise here
                self.failed += 1
                continue
            self.sent += 1
