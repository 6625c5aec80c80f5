"""The one clock every time-dependent rule reads (docs/architecture.md, "The core is a function").

The CPU reads ``now_ns()`` once per scan. ``VirtualClock`` moves only when told, so every
scan is reproducible; ``SystemClock`` follows the monotonic clock for live runs.
"""

from __future__ import annotations

import time
from typing import Protocol, runtime_checkable


@runtime_checkable
class Clock(Protocol):
    """A source of monotonic time in nanoseconds."""

    def now_ns(self) -> int: ...


class VirtualClock:
    """A clock that advances only when told (tests, ``s7graph sim``)."""

    def __init__(self, start_ns: int = 0) -> None:
        self._now = start_ns

    def now_ns(self) -> int:
        return self._now

    def advance(self, ms: float = 0, *, ns: int = 0) -> int:
        """Move time forward by ``ms`` milliseconds plus ``ns`` nanoseconds; return the new time."""
        step = round(ms * 1_000_000) + ns
        if step < 0:
            raise ValueError("a virtual clock never goes back")
        self._now += step
        return self._now


class SystemClock:
    """Monotonic time for live runs (never the wall clock, which may jump)."""

    def __init__(self) -> None:
        self._origin = time.monotonic_ns()
        self._wall_origin = time.time_ns() - (time.monotonic_ns() - self._origin)

    def now_ns(self) -> int:
        return time.monotonic_ns() - self._origin

    def wall_ns(self, t_ns: int) -> int:
        """The wall-clock time (ns since the epoch) of clock time ``t_ns``, as the wall clock
        stood when this clock began: what the diagnostic buffer stamps its entries with."""
        return self._wall_origin + t_ns
