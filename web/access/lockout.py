"""Failed logins counted per user *and source*, with back-off: no lever to lock anyone out.

A source is where a login comes from, as the bus names it (the transport's origin of the
peer; until the transport names it, the origin the client gives). Five wrong passwords
for ``olga`` from one source lock *that source* out for ``olga`` for 60 s; every further
failure from it, before a success, locks it again for twice as long (120 s, 240 s …, at
most an hour). A success from that source forgets its failures. Another source — the real
operator at her own client — is not held back at all, so wrong passwords sent by anyone
else cannot keep her out. A source that stays quiet for an hour after its lock ended
starts afresh.

The table is bounded (``capacity`` pairs of user and source): when it is full the pairs
that hold nothing back go first, then the oldest.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Final

__all__ = ["LOCKOUT_S", "LONGEST_LOCKOUT_S", "MAX_FAILURES", "Lockout"]

MAX_FAILURES: Final = 5
LOCKOUT_S: Final = 60.0
LONGEST_LOCKOUT_S: Final = 3600.0
CAPACITY: Final = 4096


@dataclass(slots=True)
class _Record:
    failures: int = 0  # wrong passwords since the last success (before the first lock)
    locks: int = 0  # locks since the last success: the next lasts 2**locks times longer
    until: float = 0.0  # monotonic end of the current lock
    seen: float = 0.0  # the last failure


class Lockout:
    """Failed logins per (user, source); thread-safe."""

    def __init__(
        self,
        *,
        max_failures: int = MAX_FAILURES,
        lockout_s: float = LOCKOUT_S,
        longest_s: float = LONGEST_LOCKOUT_S,
        capacity: int = CAPACITY,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.max_failures = max_failures
        self.lockout_s = lockout_s
        self.longest_s = longest_s
        self.capacity = capacity
        self._clock = clock
        self._lock = threading.Lock()
        self._records: dict[tuple[str, str], _Record] = {}

    def __len__(self) -> int:
        return len(self._records)

    def locked_for(self, user: str, source: str) -> float:
        """Seconds ``source`` is still locked out for ``user`` (0: it may try)."""
        now = self._clock()
        with self._lock:
            record = self._current((user, source), now)
            return max(record.until - now, 0.0) if record is not None else 0.0

    def failed(self, user: str, source: str) -> float:
        """Count a wrong password; the seconds of the lock it starts (0: none yet)."""
        now = self._clock()
        key = (user, source)
        with self._lock:
            record = self._current(key, now) or _Record()
            self._records.pop(key, None)
            self._make_room()
            self._records[key] = record  # the newest last: the oldest are evicted first
            record.seen = now
            if record.locks == 0:
                record.failures += 1
                if record.failures < self.max_failures:
                    return 0.0
            record.locks += 1
            length = min(self.lockout_s * (1 << min(record.locks - 1, 32)), self.longest_s)
            record.until = now + length
            return length

    def succeeded(self, user: str, source: str) -> None:
        """A right password: ``source``'s failures for ``user`` are forgotten."""
        with self._lock:
            self._records.pop((user, source), None)

    def _current(self, key: tuple[str, str], now: float) -> _Record | None:
        record = self._records.get(key)
        if record is not None and self._stale(record, now):
            del self._records[key]
            return None
        return record

    def _stale(self, record: _Record, now: float) -> bool:
        return now > max(record.until, record.seen) + self.longest_s

    def _make_room(self) -> None:
        if len(self._records) < self.capacity:
            return
        now = self._clock()
        for key in [k for k, r in self._records.items() if self._stale(r, now)]:
            del self._records[key]
        over = len(self._records) - self.capacity + 1
        if over > 0:  # the oldest of those that lock nothing now
            free = [k for k, r in self._records.items() if r.until <= now]
            for key in free[:over]:
                del self._records[key]
        while len(self._records) >= self.capacity:
            del self._records[next(iter(self._records))]
