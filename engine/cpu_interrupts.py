"""Which interrupt OBs are due in a cycle, and running them in S7 order.

Time-of-day OB10–17, delay OB20–23 and cyclic OB30–38 run highest priority first and,
within one priority, in the order of their start events; a missing OB calls its error OB
or stops the CPU. ``InterruptDispatch`` is a part of ``engine.cpu.Cpu``, which owns the
attributes and the OB runner it declares.
"""

from __future__ import annotations

from datetime import datetime, timedelta
from typing import Any

from s7graph.engine.cpu_part import CpuPart
from s7graph.engine.diagnostics import EventId
from s7graph.engine.interrupts import CyclicScheduler
from s7graph.engine.modes import CpuMode
from s7graph.engine.rtc import RealTimeClock
from s7graph.engine.timed import DelayInterrupts, TodInterrupts

__all__ = ["MISSING_STOP", "InterruptDispatch"]

MISSING_STOP = {
    80: EventId.STOP_OB80_MISSING,
    82: EventId.STOP_OB82_MISSING,
    83: EventId.STOP_OB83_MISSING,
    84: EventId.STOP_OB84_MISSING,
    85: EventId.STOP_OB85_MISSING,
    86: EventId.STOP_OB86_MISSING,
    87: EventId.STOP_OB87_MISSING,
}
"""The STOP event of an asynchronous error whose OB is not loaded."""

Due = tuple[int, int, int, dict[str, Any], int]
"""(OB, start event ns, error OB when missing, start info, 0)."""


class InterruptDispatch(CpuPart):
    """The interrupt part of the scan: collect the due start events, run their OBs."""

    interrupts: CyclicScheduler
    delays: DelayInterrupts
    tod: TodInterrupts
    rtc: RealTimeClock
    _tod_seen: tuple[int, object] | None

    def _interrupts(self, now: int) -> None:
        """Run due interrupt OBs: priority first, then the order of their start events."""
        queue: list[Due] = []
        for ob, lost, at in self.interrupts.due_events(now):
            if lost:
                self.diagnostics.record(
                    self._raw, EventId.OB_REQUEST_ERROR, f"OB{ob}", f"{lost} start event(s) lost"
                )
            period = self.interrupts.active[ob]
            info = {"PHASE_OFFSET": period.phase_ns // 1_000_000, "LOST": lost}
            queue.append((ob, at, 85, info, 0))
        if self.delays.pending:
            for d in self.delays.due(now):
                queue.append((d.ob, d.due_ns, 80, {"SIGN": d.sign}, 0))
        if self.tod.table:
            queue.extend(self._tod_due(now))
        else:
            self._tod_seen = None
        if not queue or self.mode is not CpuMode.RUN:
            return
        queue.sort(key=lambda e: (-self.priority_of(e[0]), e[1], e[0]))
        for ob, _, error_ob, info, _ in queue:
            if self.mode is not CpuMode.RUN:
                return
            if ob in self.obs:
                self._run_ob(ob, info)
                continue
            self.diagnostics.record(
                self._raw, EventId.INTERRUPT_OB_MISSING, f"OB{ob}", "not loaded"
            )
            if error_ob in self.obs:
                self._run_ob(error_ob, {"OB": ob})
            else:
                event = MISSING_STOP[error_ob]
                self._go_stop(event, f"OB{error_ob}", f"not loaded (event for OB{ob})")

    def _tod_due(self, now: int) -> list[Due]:
        """Due time-of-day interrupts on the RTC; a clock set forward over some calls OB80
        (FLT_ID 16#05) first, then each skipped OB runs once unless OB80 cancelled it
        (Siemens' Program Design for S7-300/400)."""
        dt = self.rtc.read(self._raw)
        seen, self._tod_seen = self._tod_seen, (self.rtc.version, dt)
        jumped_from = None
        if seen is not None and seen[0] != self.rtc.version and isinstance(seen[1], datetime):
            jumped_from = seen[1] if dt > seen[1] else None
        events = self.tod.due(dt, jumped_from)
        skipped = sorted({e.ob for e in events if e.skipped})
        if skipped:
            self.diagnostics.record(
                self._raw, EventId.ASYNC_ERROR, "OB80", f"TOD interrupt(s) skipped: {skipped}"
            )
            info = {"FLT_ID": 0x05, "SKIPPED": tuple(skipped)}
            info["SKIPPED_MASK"] = sum(1 << (ob - 10) for ob in skipped)
            if 80 in self.obs:
                self._run_ob(80, info)
            else:
                self._go_stop(EventId.STOP_OB80_MISSING, "OB80", "not loaded (TOD skipped)")
                return []
        out: list[Due] = []
        for e in events:
            if self.tod.consume(e.ob, dt):
                at = now - (dt - e.due) // timedelta(microseconds=1) * 1000
                out.append((e.ob, at, 80, {"DATE_TIME": e.due, "SKIPPED": e.skipped}, 0))
        return out
