"""A bounded queue in which each source has its own share: one source that floods it fills
its share and is refused beyond, while every other source's requests still get in.

:class:`SharedQueue` holds at most ``total`` items, at most ``per_source`` of one source
(where a request came from by the transport: ``web.bus.origin.lockout_source``), and
hands them out oldest first. ``web.bus.watch`` queues its requests there.
"""

from __future__ import annotations

import collections
import threading
from typing import Generic, TypeVar

__all__ = ["SharedQueue"]

T = TypeVar("T")


class SharedQueue(Generic[T]):
    """At most ``total`` items waiting, at most ``per_source`` of one source; thread-safe."""

    def __init__(self, total: int, per_source: int) -> None:
        self.total = total
        self.per_source = per_source
        self._lock = threading.Lock()
        self._items: collections.deque[tuple[str, T]] = collections.deque()
        self._of: collections.Counter[str] = collections.Counter()

    def put(self, source: str, item: T) -> str:
        """Queue ``item`` of ``source``: "" when it is in, else why not — ``source`` has its
        share waiting (``"source"``) or the queue is full (``"full"``)."""
        with self._lock:
            if self._of[source] >= self.per_source:
                return "source"
            if len(self._items) >= self.total:
                return "full"
            self._items.append((source, item))
            self._of[source] += 1
        return ""

    def get(self) -> T | None:
        """The oldest item (None: none waits); its source's share has room again."""
        with self._lock:
            if not self._items:
                return None
            source, item = self._items.popleft()
            self._of[source] -= 1
            if not self._of[source]:
                del self._of[source]  # a source gone leaves nothing behind
        return item

    def __len__(self) -> int:
        with self._lock:
            return len(self._items)
