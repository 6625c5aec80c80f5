"""The CPU's side of the bus at the scan boundary.

:class:`CpuEdge` is what the scan thread does after each scan for the CPU itself — any CPU,
a chart's or a program of blocks': it publishes the CPU's state (with the STOP's reason and
diagnostic entries) and cycle statistics on ``status``, applies the commands received since
the last scan — the scan boundary: ``ack_msg`` to the CPU's message list (published on
``alarms`` when it changed, ``web.bus.alarm_feed``), ``stop``, ``start`` and ``mres`` to the
CPU's switch (``Runner.switch_stop``/``switch_start``, ``Cpu.memory_reset``), ``force`` to
the CPU's force table (``web.bus.forcing``) — publishes the force jobs when they changed
(``forces``), the diagnostic buffer's new entries (``diag``, ``web.bus.diagnostics``) and
answers the watch requests waiting (``watch``, ``web.bus.watch``).

:class:`ScanEdge` adds one running GraphFB: the scan's :class:`StepStateUpdate` (of a
:class:`~web.bus.live.LiveGraph`, built only when the FB may have changed:
``LiveGraph.changed``; out in the scan's one message on ``deltas``), the CPU's message
list when it changed (``alarms``), optionally the recording (a :class:`Recording`:
``web.recorder``'s rerun ``.rrd`` file), the FB's commands, and the operands when due
(``operands``, ``web.bus.operands``). ``web.wiring.live_edge`` gives it its bus, its
recording and, in one process, the view; ``web.wiring.program_edge`` gives a program of
blocks its bus.
"""

from __future__ import annotations

import contextlib
import functools
import time
from typing import TYPE_CHECKING, Protocol

from s7graph.engine.cpu import Cpu
from s7graph.engine.diagnostics import EventId
from s7graph.engine.modes import CpuMode
from s7graph.engine.profile import CycleBreakdown
from s7graph.engine.record import ScanRecord
from s7graph.engine.runner import Runner, stop_reason
from s7graph.engine.watchdog import CycleStatistics
from s7graph.sequencer.fb import position
from s7graph.sfb.alarms import MessageList
from s7graph.web.bus.alarm_feed import AlarmFeed
from s7graph.web.bus.diagnostics import DiagFeed
from s7graph.web.bus.live import LiveGraph
from s7graph.web.bus.protocol import (
    AlarmList,
    ChartLayout,
    Command,
    CycleReport,
    CycleStats,
    Refusal,
    StepStateUpdate,
)
from s7graph.web.bus.publisher import BusPublisher
from s7graph.web.bus.sync import Synchronizing
from s7graph.web.bus.watch import Watching
from s7graph.web.commands import AckMsg

if TYPE_CHECKING:
    from s7graph.web.bus.forcing import Forcing
    from s7graph.web.bus.online import OnlineChange
    from s7graph.web.bus.operands import OperandFeed

__all__ = ["CpuEdge", "Recording", "ScanEdge", "cycle_report", "cycle_stats"]

_MS = 1e6


def cycle_stats(
    cpu: CycleStatistics, runner: Runner | None = None, comm_limited: int = 0
) -> CycleStats:
    """The published statistics: the CPU's cycle time, the runner's execution time, its
    overruns and long cycles with the breakdowns of the longest and the last long one, its
    share for communication and how often that ran out (``comm_limited``), and where the
    scan thread runs (its real-time priority, the processor it keeps)."""
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
        priority=(runner.rt_priority or 0) if runner.realtime else 0,
        core=runner.core if runner.pinned and runner.core is not None else -1,
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


class CpuEdge:
    """What the scan thread does with the bus (``publisher``; None: no bus) after each scan
    for the CPU ``cpu`` (default: the force table's); close it when done."""

    def __init__(
        self,
        publisher: BusPublisher | None,
        *,
        forcing: Forcing | None = None,
        cpu: Cpu | None = None,
        messages: MessageList | None = None,
    ) -> None:
        self.publisher = publisher
        self.forcing = forcing
        self.cpu = cpu if cpu is not None else forcing.cpu if forcing is not None else None
        self.restart = "warm"
        """The startup the switch's ``start`` does (``--restart``)."""
        self._runner: Runner | None = None
        self._cpu_state: str | None = None
        self._starting = False  # a start applied at this boundary
        self.diag: DiagFeed | None = None
        self.watching: Watching | None = None
        self.alarms: AlarmFeed | None = None
        """The CPU's message list (``alarms``, ``ack_msg``), if it keeps one."""
        self._t_ns = 0  # CPU time of the last scan
        if publisher is not None and messages is not None:
            self.alarms = AlarmFeed(messages)
        if publisher is not None and self.cpu is not None:
            self.diag = DiagFeed(self.cpu, publisher)
            self.watching = Watching(self.cpu, publisher)

    def on_record(
        self,
        record: ScanRecord,
        *,
        stats: CycleStatistics | None = None,
        runner: Runner | None = None,
    ) -> StepStateUpdate | None:
        """Publish the CPU's side of the scan ``record`` and apply the pending commands
        (call in the scan thread); with ``runner``, within its share of the cycle for
        communication."""
        until_ns = self._begin(runner)
        publisher = self.publisher
        if publisher is None:
            return None
        self._t_ns = record.t_ns
        self._publish_cpu(record, stats, runner, publisher)
        publisher.scanned(record.cycle, record.t_ns // 1_000_000)
        self._publish_alarms(record, publisher)
        self._boundary(record, runner, until_ns, publisher)
        return None

    def _alarms_changed(self, record: ScanRecord) -> AlarmList | None:
        """The CPU's message list if it changed (None: it did not, or there is none)."""
        return self.alarms.changed(record.t_ns, record.cycle) if self.alarms is not None else None

    def _publish_alarms(self, record: ScanRecord, publisher: BusPublisher) -> None:
        """The message list on ``alarms`` when it changed."""
        alarms = self._alarms_changed(record)
        if alarms is not None:
            publisher.publish_alarms(alarms)

    def _begin(self, runner: Runner | None) -> int | None:
        """A scan boundary begins: the end of its share for communication, if limited."""
        self._runner = runner
        self._starting = False
        return time.perf_counter_ns() + runner.comm_budget_ns if runner is not None else None

    def _publish_cpu(
        self,
        record: ScanRecord,
        stats: CycleStatistics | None,
        runner: Runner | None,
        publisher: BusPublisher,
    ) -> None:
        """The CPU's state on a change (in STOP with why: its entries), the statistics."""
        state = str(record.mode)
        if state != self._cpu_state:
            self._cpu_state = state
            cpu = runner.cpu if runner is not None else self.cpu
            if record.mode is CpuMode.STOP and cpu is not None:
                stop, cause = self.diag.stop_events() if self.diag is not None else (None, None)
                publisher.set_cpu_state(state, stop_reason(cpu), stop=stop, cause=cause)
            else:
                publisher.set_cpu_state(state)
        if stats is not None:
            publisher.set_cycle_stats(cycle_stats(stats, runner, publisher.comm_limited))

    def _boundary(
        self,
        record: ScanRecord,
        runner: Runner | None,
        until_ns: int | None,
        publisher: BusPublisher,
    ) -> None:
        """The commands, then what they and the scan changed: force jobs, the diagnostic
        buffer's new entries, the watch requests waiting."""
        publisher.apply_commands(self.apply, cycle=record.cycle, durable=runner, until_ns=until_ns)
        if self.forcing is not None:
            forces = self.forcing.changed()
            if forces is not None:
                publisher.publish_forces(forces)
        if self.diag is not None:
            self.diag.at_boundary(runner)
        if self.watching is not None:  # within what the commands left of the share
            self.watching.at_boundary(record.t_ns // 1_000_000, until_ns)

    def apply(self, command: Command) -> tuple[bool, str, str]:
        """One command the gate let through, at the scan boundary: the switch's and MRES to
        the CPU, ``force`` to the force table."""
        where = type(command).where  # web.commands: who carries the op out
        if where == "cpu":
            return self._switch(command)
        if isinstance(command, AckMsg) and self.alarms is not None:
            return self._ack_msg(command)
        if where != "force":
            why = f"this CPU runs no GRAPH FB: {command.op} needs one"
            return False, Refusal("refused", why), ""
        if self.forcing is None:
            return False, Refusal("refused", "this CPU takes no force jobs"), ""
        return self.forcing.apply(command)

    def _ack_msg(self, command: AckMsg) -> tuple[bool, str, str]:
        """``ack_msg``: one message of the CPU's message list, as the command's user."""
        assert self.alarms is not None
        msg, why = self.alarms.acknowledge(command.msg_id, command.user or "?", self._t_ns)
        if msg is None:
            return False, why, ""
        return True, "", f"message {command.msg_id}: {msg.text}"

    def _switch(self, command: Command) -> tuple[bool, str, str]:
        """The CPU's RUN/STOP switch: ``stop`` now (outputs to 0), ``start`` from STOP by
        the configured restart at the next scan boundary (as S7's mode switch); ``mres``
        in STOP only (``Cpu.memory_reset``, the program kept)."""
        runner = self._runner
        if runner is None:
            return False, Refusal("refused", "this CPU has no RUN/STOP switch"), ""
        mode = runner.cpu.mode
        if command.op == "mres":
            return self._memory_reset(runner.cpu)
        if command.op == "stop":
            if mode is CpuMode.STOP:
                return False, Refusal("state", "the CPU is in STOP already"), ""
            runner.switch_stop(f"STOP by the switch ({command.user or 'no user'})")
            return True, "", f"{mode} → STOP"
        if mode is not CpuMode.STOP:
            return False, Refusal("state", f"the CPU is in {mode}, not in STOP"), ""
        runner.switch_start(self.restart)
        self._starting = True
        return True, "", f"STOP → RUN ({self.restart} restart)"

    def _memory_reset(self, cpu: Cpu) -> tuple[bool, str, str]:
        """MRES (docs/runtime.md, "Memory reset (MRES)"): refused unless in STOP."""
        if cpu.mode is not CpuMode.STOP:
            why = f"the CPU is in {cpu.mode}: a memory reset needs STOP (stop it first)"
            return False, Refusal("state", why), ""
        if self._starting:
            why = "a start came first at this scan boundary: the CPU is starting"
            return False, Refusal("state", why), ""
        jobs = len(cpu.forces)
        cpu.memory_reset(keep_program=True)
        gone = f", {jobs} force job{'s' if jobs != 1 else ''} deleted" if jobs else ""
        return True, "", f"memory reset in STOP: every area, DB and instance DB initial{gone}"

    def close(self) -> None:
        """Nothing to close here (the bus is the caller's)."""

    def __enter__(self) -> CpuEdge:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class ScanEdge(CpuEdge):
    """What the scan thread does with the bus (``publisher``; None: no bus) and the
    recording after each scan of one running GraphFB; close it when done."""

    def __init__(
        self,
        live: LiveGraph,
        publisher: BusPublisher | None,
        *,
        online: OnlineChange | None = None,
        forcing: Forcing | None = None,
        cpu: Cpu | None = None,
        operands: OperandFeed | None = None,
    ) -> None:
        super().__init__(publisher, forcing=forcing, cpu=cpu)
        self.live = live
        self.online = online
        self.operands = operands
        self.recorder: Recording | None = None
        self.sync: Synchronizing | None = None
        if publisher is not None and self.cpu is not None:
            self.sync = Synchronizing(live.graph, live.fb, self.cpu, publisher)
        if online is not None and publisher is not None:
            online.attach(publisher)
        if operands is not None and publisher is not None:
            operands.attach(publisher)

    def on_record(
        self,
        record: ScanRecord,
        *,
        stats: CycleStatistics | None = None,
        runner: Runner | None = None,
    ) -> StepStateUpdate | None:
        """Publish the scan ``record`` and apply the pending commands (call in the scan
        thread); with ``runner``, within its share of the cycle for communication. Returns
        the FB's update, None if the scan changed nothing of it."""
        until_ns = self._begin(runner)
        update = self.live.changed(record)
        if update is not None and self.recorder is not None and record.mode is CpuMode.RUN:
            if self.recorder.layout is not self.live.layout:  # an online change
                self.recorder.chart_changed(self.live.layout)
            self.recorder.record(update)
        publisher = self.publisher
        if publisher is None:
            return update
        self._publish_cpu(record, stats, runner, publisher)
        changed = [(self.live.fb, update)] if update is not None else []
        publisher.publish_scan(max(record.cycle, 0), max(record.t_ns // 1_000_000, 0), changed)
        self._publish_alarms(record, publisher)
        self._boundary(record, runner, until_ns, publisher)
        if self.sync is not None:  # one judgement for all the queries, at most every 0.2 s
            self.sync.at_boundary()
        if self.operands is not None:
            self.operands.at_boundary(record.cycle)
        if self.online is not None:
            self.online.at_boundary()
        return update

    def _alarms_changed(self, record: ScanRecord) -> AlarmList | None:
        """The message list as the FB's view gives it (``LiveGraph.alarms_changed``)."""
        return self.live.alarms_changed()

    def _memory_reset(self, cpu: Cpu) -> tuple[bool, str, str]:
        """The CPU's memory reset, the FB's position first written to the diagnostic
        buffer: nothing is destroyed silently, as before a warm or cold restart."""
        graph = self.live.graph
        if cpu.mode is CpuMode.STOP and not self._starting and graph.idb is not None:
            st = graph.state
            if st.calls:
                where = f"{graph.cc.name}/DB{graph.db_number}"
                cpu.diagnostics.record(
                    cpu.clock.now_ns(),
                    EventId.SEQUENCER_POSITION,
                    graph.fb.label,
                    f"memory reset clears {where}, {position(graph.cc, st)}",
                )
        return super()._memory_reset(cpu)

    def apply(self, command: Command) -> tuple[bool, str, str]:
        """One command the gate let through, at the scan boundary: the CPU's to the CPU,
        the others to the FB."""
        if type(command).where in ("cpu", "force"):
            return super().apply(command)
        return self.live.apply(command)

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
