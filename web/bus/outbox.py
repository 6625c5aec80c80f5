"""What the scan thread publishes, encoded and put on the bus by a thread of its own.

The scan thread only decides that a message goes out and queues it (a few hundred
nanoseconds); :class:`Outbox`'s thread encodes it (``seq`` set then, if given) and puts it
on its zenoh publisher, in the order queued. A put that blocks — a congested link, a slow
subscriber under ``CongestionControl.BLOCK`` — holds up this thread, never a scan. While
more than ``limit`` messages wait, new ones are dropped and counted (``dropped``): a view
sees the gap in ``seq`` and goes on from the next state, which is whole. A job
(:meth:`Outbox.run`: a scan's deltas, ``web.bus.deltas``) encodes and puts on this thread
what it carries, in the same order; it counts as the deltas it carries, against the limit
and, dropped, in ``dropped``.
"""

from __future__ import annotations

import queue
import threading
from collections.abc import Callable
from typing import Any, Protocol

import msgspec

from s7graph.web.bus.protocol import encode

__all__ = ["OUTBOX_LIMIT", "Job", "Outbox", "Sink"]

OUTBOX_LIMIT = 20_000
"""Messages waiting at most (at 200 deltas a scan, 100 scans' worth)."""

_STOP = None
Job = Callable[[], int]
"""Work for the outbox's thread: encodes and puts, returns how many messages it put."""


class Sink(Protocol):
    """Where the outbox puts a message: a zenoh publisher, or a query answered later
    (``web.bus.publisher.QueryReply``)."""

    def put(self, payload: bytes) -> object: ...


class Outbox:
    """A queue of ``(sink, message, seq)`` and the thread that sends it; :meth:`close`
    sends what is queued, then stops the thread."""

    def __init__(self, *, limit: int = OUTBOX_LIMIT, name: str = "s7graph-bus-out") -> None:
        self._queue: queue.SimpleQueue[tuple[Sink | None, Any, int] | None]
        self._queue = queue.SimpleQueue()
        self.limit = limit
        """Messages waiting at most; beyond, new ones are dropped and counted."""
        self._lock = threading.Lock()
        self._in = 0  # messages queued so far (a job: its weight), under the lock
        self._out = 0  # and taken off the queue (the thread's alone)
        self.sent = 0
        self.dropped = 0
        self.failed = 0
        self._thread = threading.Thread(target=self._run, name=name, daemon=True)
        self._thread.start()

    def post(self, publisher: Sink, message: Any, seq: int | None = None) -> bool:
        """Queue ``message`` (with ``seq`` replaced, if given) for ``publisher``; False if
        it was dropped because too many wait."""
        if not self._admit(1):
            return False
        self._queue.put((publisher, (message, seq), 1))
        return True

    def run(self, job: Job, weight: int = 1) -> bool:
        """Queue ``job`` to run on the outbox's thread, counting as ``weight`` messages
        (a scan's deltas: one each); False if it was dropped because too many wait."""
        if not self._admit(weight):
            return False
        self._queue.put((None, job, weight))
        return True

    def _admit(self, weight: int) -> bool:
        with self._lock:
            if self._in - self._out >= self.limit:
                self.dropped += weight
                return False
            self._in += weight
        return True

    def pending(self) -> int:
        """Messages queued and not yet sent (a job: its weight)."""
        return self._in - self._out

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
            publisher, what, weight = item
            try:
                if publisher is None:  # a job: it encodes and puts
                    self.sent += what()
                else:
                    message, seq = what
                    publisher.put(encode(message if seq is None else replace(message, seq=seq)))
                    self.sent += 1
            except Exception:  # a closed session, an undeclared publisher: never raise here
                self.failed += 1
            finally:
                self._out += weight
