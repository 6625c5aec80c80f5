"""The CPU's side of the bus at the scan boundary, for one running GraphFB.

:class:`ScanEdge` is called back after each scan, in the scan thread: it publishes the
scan's :class:`StepStateUpdate` (of a :class:`~web.bus.live.LiveGraph`), the CPU state and
cycle statistics, the CPU's message list when it changed (``alarms``), optionally records
the update (a :class:`Recording`: ``web.recorder``'s rerun ``.rrd`` file), then applies the
commands received since the last scan — the scan boundary: ``force`` to the CPU's force
table (``web.bus.forcing``), ``stop`` and ``start`` to the CPU's RUN/STOP switch
(``Runner.switch_stop``/``switch_start``), the others to the FB — and publishes the force
jobs when they changed (``forces``) and the operands when due (``web.bus.operands``).
``web.wiring.live_edge`` gives it its bus, its recording and, in one process, the view.
"""

from __future__ import annotations

import contextlib
import functools
import time
from typing import TYPE_CHECKING, Protocol

from s7graph.engine.modes import CpuMode
from s7graph.engine.profile import CycleBreakdown
from s7graph.engine.record import ScanRecord
from s7graph.engine.runner import Runner, stop_reason
from s7graph.engine.watchdog import CycleStatistics
from s7graph.web.bus.live import LiveGraph
from s7graph.web.bus.protocol import (
    ChartLayout,
    Command,
    CycleReport,
    CycleStats,
    StepStateUpdate,
)
from s7graph.web.bus.publisher import BusPublisher

if TYPE_CHECKING:
    from s7graph.web.bus.forcing import Forcing
    from s7graph.web.bus.online import OnlineChange
    from s7graph.web.bus.operands import OperandFeed

__all__ = ["Recording", "ScanEdge", "cycle_report", "cycle_stats"]

_MS = 1e6


def cycle_stats(
    cpu: CycleStatistics, runner: Runner | None = None, comm_limited: int = 0
) -> CycleStats:
    """The published statistics: the CPU's cycle time, the runner's execution time, its
    overruns and long cycles with the breakdowns of the longest and the last long one, its
    share for communication and how often that ran out (``comm_limited``)."""
    if runner is None:
        return CycleStats(
            last_ms=cpu.last_ns / _MS, min_ms=cpu.min_ns / _MS, max_ms=cpu.max_ns / _MS
        )
    profile = runner.profile
    recent = profile.recent
    return CycleStats(
        last_ms=cpu.last_ns / _MS,
        min_ms=cpu.min_ns / _MS,
        max_ms=cpu.max_ns / _MS,
        exec_ms=runner.exec_stats.mean_ns / _MS,
        overruns=runner.overruns,
        long=profile.long,
        long_over_ms=(profile.cycle_ns + profile.margin_ns) / _MS,
        longest=cycle_report(profile.longest) if profile.longest is not None else None,
        last_long=cycle_report(recent[-1]) if recent else None,
        comm_load=runner.comm_load_pct,
        comm_limited=comm_limited,
    )


@functools.lru_cache(maxsize=4)
def cycle_report(cycle: CycleBreakdown) -> CycleReport:
    """``cycle`` as published (made once: the same cycle is published at every scan)."""
    return CycleReport(
        scan=cycle.scan,
        at_ms=cycle.at_ns // 1_000_000,
        cycle_ms=cycle.cycle_ns / _MS,
        overrun=cycle.overrun,
        parts=cycle.parts_ms(),
    )


class Recording(Protocol):
    """Where the updates are recorded (``web.recorder.Recorder``)."""

    layout: ChartLayout

    def chart_changed(self, layout: ChartLayout) -> None: ...

    def record(self, update: StepStateUpdate) -> None: ...

    def close(self) -> object: ...


class ScanEdge:
    """What the scan thread does with the bus (``publisher``; None: no bus) and the
    recording after each scan of one running GraphFB; close it when done."""

    def __init__(
        self,
        live: LiveGraph,
        publisher: BusPublisher | None,
        *,
        online: OnlineChange | None = None,
        forcing: Forcing | None = None,
        operands: OperandFeed | None = None,
    ) -> None:
        self.live = live
        self.online = online
        self.forcing = forcing
        self.operands = operands
        self.recorder: Recording | None = None
        self.publisher = publisher
        if online is not None and publisher is not None:
            online.attach(publisher)
        if operands is not None and publisher is not None:
            operands.attach(publisher)
        self._cpu_state: str | None = None
        self.restart = "warm"
        """The startup the switch's ``start`` does (``--restart``)."""
        self._runner: Runner | None = None

    def on_record(
        self,
        record: ScanRecord,
        *,
        stats: CycleStatistics | None = None,
        runner: Runner | None = None,
    ) -> StepStateUpdate:
        """Publish the scan ``record`` and apply the pending commands (call in the scan
        thread); with ``runner``, within its share of the cycle for communication."""
        until_ns = time.perf_counter_ns() + runner.comm_budget_ns if runner is not None else None
        self._runner = runner
        update = self.live.update(record)
        if self.recorder is not None and record.mode is CpuMode.RUN:
            if self.recorder.layout is not self.live.layout:  # an online change
                self.recorder.chart_changed(self.live.layout)
            self.recorder.record(update)
        publisher = self.publisher
        if publisher is None:
            return update
        state = str(record.mode)
        if state != self._cpu_state:
            self._cpu_state = state
            stopped = record.mode is CpuMode.STOP
            reason = stop_reason(runner.cpu) if runner is not None and stopped else ""
            publisher.set_cpu_state(state, reason)
        if stats is not None:
            publisher.set_cycle_stats(cycle_stats(stats, runner, publisher.comm_limited))
        publisher.publish(self.live.fb, update)
        alarms = self.live.alarms_changed()
        if alarms is not None:
            publisher.publish_alarms(alarms)
        publisher.apply_commands(self.apply, cycle=record.cycle, durable=runner, until_ns=until_ns)
        if self.forcing is not None:
            forces = self.forcing.changed()
            if forces is not None:
                publisher.publish_forces(forces)
        if self.operands is not None:
            self.operands.at_boundary(record.cycle)
        if self.online is not None:
            self.online.at_boundary()
        return update

    def apply(self, command: Command) -> tuple[bool, str, str]:
        """One command the gate let through, at the scan boundary: ``force`` to the CPU's
        force table, the others to the FB."""
        where = type(command).where  # web.commands: who carries the op out
        if where == "cpu":
            return self._switch(command)
        if where != "force":
            return self.live.apply(command)
        if self.forcing is None:
            return False, "this CPU takes no force jobs", ""
        return self.forcing.apply(command)

    def _switch(self, command: Command) -> tuple[bool, str, str]:
        """The CPU's RUN/STOP switch: ``stop`` now (outputs to 0), ``start`` from STOP by
        the configured restart at the next scan boundary (as S7's mode switch)."""
        runner = self._runner
        if runner is None:
            return False, "this CPU has no RUN/STOP switch", ""
        mode = runner.cpu.mode
        if command.op == "stop":
            if mode is CpuMode.STOP:
                return False, "the CPU is in STOP already", ""
            runner.switch_stop(f"STOP by the switch ({command.user or 'no user'})")
            return True, "", f"{mode} → STOP"
        if mode is not CpuMode.STOP:
            return False, f"the CPU is in {mode}, not in STOP", ""
        runner.switch_start(self.restart)
        return True, "", f"STOP → RUN ({self.restart} restart)"

    def close(self) -> None:
        """Close the online change and the recording."""
        if self.online is not None:
            self.online.close()
        if self.recorder is not None:
            with contextlib.suppress(Exception):
                self.recorder.close()
            self.recorder = None

    def __enter__(self) -> ScanEdge:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
