"""Cycle-time monitoring and cycle statistics (docs/runtime.md, "When a scan hangs or fails").

The cycle time is the process time between two OB1 starts. Above the maximum (default
150 ms) OB80 is called (FLT_ID 16#01) or, without OB80, the CPU stops; at twice the
maximum the CPU stops even with OB80. Each SFC43 RE_TRIGR in a cycle restarts the
monitoring, which — since the clock is read once per scan — credits one more maximum
cycle time to that cycle.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum

_MS = 1_000_000

COMM_LOAD_PCT = 20
"""The share of the cycle time the edge may spend on commands at each scan boundary, in
per cent: S7's "scan cycle load from communication" (HW Config, Cycle/Clock Memory; 20 by
default). Commands beyond it wait for the next boundary (``engine.runner``)."""


@dataclass(slots=True)
class CycleStatistics:
    """Last, minimum, maximum and mean cycle time in ns over the cycles measured."""

    count: int = 0
    last_ns: int = 0
    min_ns: int = 0
    max_ns: int = 0
    total_ns: int = 0

    def add(self, cycle_ns: int) -> None:
        self.count += 1
        self.last_ns = cycle_ns
        self.total_ns += cycle_ns
        if self.count == 1 or cycle_ns < self.min_ns:
            self.min_ns = cycle_ns
        self.max_ns = max(self.max_ns, cycle_ns)

    @property
    def mean_ns(self) -> float:
        return self.total_ns / self.count if self.count else 0.0

    def reset(self) -> None:
        self.count = self.last_ns = self.min_ns = self.max_ns = self.total_ns = 0

    def start_info_ms(self) -> dict[str, int]:
        """OB1 start info PREV_CYCLE / MIN_CYCLE / MAX_CYCLE in ms."""
        return {
            "PREV_CYCLE": self.last_ns // _MS,
            "MIN_CYCLE": self.min_ns // _MS,
            "MAX_CYCLE": self.max_ns // _MS,
        }


class Verdict(StrEnum):
    """What cycle monitoring decides about a finished cycle."""

    OK = "ok"
    OB80 = "ob80"
    STOP = "stop"


class Watchdog:
    """Maximum/minimum cycle time and RE_TRIGR credits."""

    def __init__(self, max_cycle_ms: float = 150.0, min_cycle_ms: float = 0.0) -> None:
        if min_cycle_ms < 0 or max_cycle_ms <= 0 or min_cycle_ms > max_cycle_ms:
            raise ValueError("need 0 <= min cycle time <= max cycle time, max > 0")
        self.max_cycle_ns = int(max_cycle_ms * _MS)
        self.min_cycle_ns = int(min_cycle_ms * _MS)
        self._retriggers = 0

    def retrigger(self) -> None:
        """SFC43 RE_TRIGR: restart the monitoring for the running cycle."""
        self._retriggers += 1

    def check(self, cycle_ns: int, *, has_ob80: bool) -> Verdict:
        """Judge a cycle of ``cycle_ns``; clears this cycle's RE_TRIGR credits."""
        budget = self.max_cycle_ns * (1 + self._retriggers)
        self._retriggers = 0
        if cycle_ns <= budget:
            return Verdict.OK
        if cycle_ns > budget + self.max_cycle_ns or not has_ob80:
            return Verdict.STOP
        return Verdict.OB80
