"""A bounded queue in which each source has its own share: one source that floods it fills
its share and is refused beyond, while every other source's requests still get in.

:class:`SharedQueue` holds two pools, each with a share of at most ``per_source`` items a
source, and hands the items of both out oldest first:

- the *proven* pool (``total`` items): sources the CPU established itself — a user whose
  request its session signed (``web.bus.watch``), this process;
- the *unproven* pool (``unproven`` items): every source that is only a claim — a link
  named by the sender's own ``source_info`` (``web.bus.origin.lockout_source``), and all
  requests that name no session, as one source.

A source of one pool never takes a place of the other: however many sources a peer makes
up, it fills the unproven pool at most, and a proven source's share is never used up by a
sender claiming its name (the two pools' names are apart). ``web.bus.watch`` queues its
requests there.
"""

from __future__ import annotations

import collections
import threading
from typing import Generic, Literal, TypeVar

__all__ = ["Refusal", "SharedQueue"]

T = TypeVar("T")
Refusal = Literal["", "source", "full"]
"""Why :meth:`SharedQueue.put` did not queue an item ("": it did)."""


class SharedQueue(Generic[T]):
    """At most ``total`` items of proven sources and ``unproven`` of the others waiting, at
    most ``per_source`` of one source; thread-safe."""

    def __init__(self, total: int, per_source: int, unproven: int | None = None) -> None:
        self.total = total
        self.per_source = per_source
        self.unproven = total if unproven is None else unproven
        self._lock = threading.Lock()
        self._items: collections.deque[tuple[tuple[bool, str], T]] = collections.deque()
        self._of: collections.Counter[tuple[bool, str]] = collections.Counter()
        self._in: collections.Counter[bool] = collections.Counter()  # items per pool

    def put(self, source: str, item: T, *, proven: bool = False) -> Refusal:
        """Queue ``item`` of ``source`` (``proven``: in the proven pool): "" when it is
        in, else why not — ``source`` has its share waiting (``"source"``) or its pool is
        full (``"full"``)."""
        key = (proven, source)
        room = self.total if proven else self.unproven
        with self._lock:
            if self._of[key] >= self.per_source:
                return "source"
            if self._in[proven] >= room:
                return "full"
            self._items.append((key, item))
            self._of[key] += 1
            self._in[proven] += 1
        return ""

    def get(self) -> T | None:
        """The oldest item of either pool (None: none waits); its source's share has room
        again."""
        with self._lock:
            if not self._items:
                return None
            key, item = self._items.popleft()
            self._in[key[0]] -= 1
            self._of[key] -= 1
            if not self._of[key]:
                del self._of[key]  # a source gone leaves nothing behind
        return item

    def waiting(self, *, proven: bool) -> int:
        """Items waiting in the proven (or the unproven) pool."""
        with self._lock:
            return self._in[proven]

    def __len__(self) -> int:
        with self._lock:
            return len(self._items)
