"""STOPs by an error from outside the program: a block the runner aborted at twice the
maximum cycle time (cycle monitoring), and a state file that could not be written. Each
writes its entries into the diagnostic buffer and stops the CPU; after either, as after
any STOP by an error (``engine.restart.NO_HOT_AFTER_STOP``), S7 allows only a warm restart
(S7-400 "Programming with STEP 7", Operating Modes).

``ErrorStops`` is a part of ``engine.cpu.Cpu``, which owns the attributes it declares.
"""

from __future__ import annotations

from s7graph.engine.clock import Clock
from s7graph.engine.cpu_part import CpuPart
from s7graph.engine.diagnostics import EventId
from s7graph.engine.modes import CpuMode
from s7graph.engine.restart import error_blocker
from s7graph.engine.watchdog import Watchdog

__all__ = ["ErrorStops"]


class ErrorStops(CpuPart):
    """The runner's and the state file's ways to stop the CPU."""

    clock: Clock
    watchdog: Watchdog
    hot_blockers: set[str]
    abort_reason: str

    def stop_by_error(self, event: int, block: str, message: str) -> None:
        """Go to STOP because of an error outside the program (the state file could not be
        written): an entry with ``event``; outputs go to 0; then only a warm restart (S7)."""
        if self.mode is not CpuMode.STOP:
            self._go_stop(event, block, message)
        else:  # the entry and the blocker only
            self.hot_blockers.add(error_blocker(message))
            self.diagnostics.record(self.clock.now_ns(), event, block, message)

    def abort(self, block: str) -> None:
        """The runner aborted ``block`` (a block, the plant, the CPU itself) still running at
        twice the maximum cycle time: a time error entry naming it, then STOP."""
        limit = 2 * self.watchdog.max_cycle_ns // 1_000_000
        why = self.abort_reason or f"still running at twice the maximum cycle time ({limit} ms)"
        raw = self.clock.now_ns()
        self.diagnostics.record(raw, EventId.CYCLE_TIME_EXCEEDED, block, f"aborted: {why}")
        if self.mode is not CpuMode.STOP:
            self._go_stop(EventId.STOP_CYCLE_TIME, block, "block aborted by cycle monitoring")
        self.abort_reason = ""
