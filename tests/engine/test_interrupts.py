"""Cyclic interrupts OB30–OB38 and OB priorities (docs/runtime.md, "When a scan hangs or fails")."""

from __future__ import annotations

import pytest

from s7graph.engine import CallContext, Cpu, CpuMode, EventId, VirtualClock, ob
from s7graph.engine.interrupts import CYCLIC_DEFAULT_MS, CyclicScheduler, priority


def _times(clock: VirtualClock, cpu: Cpu, number: int, until_ms: int, step: int = 1) -> list[int]:
    out: list[int] = []
    for _ in range(until_ms // step):
        clock.advance(step)
        if number in cpu.scan().ran:
            out.append(clock.now_ns() // 1_000_000)
    return out


def _cyclic(number: int) -> object:
    @ob(number)
    def body(ctx: CallContext) -> None:
        pass

    return body


@pytest.mark.parametrize(("number", "period"), sorted(CYCLIC_DEFAULT_MS.items()))
def test_cyclic_ob_runs_at_its_default_period_from_stop_to_run(
    clock: VirtualClock, number: int, period: int
) -> None:
    """OB30..OB38 default 5000/…/10 ms, measured from the STOP→RUN transition."""
    clock.advance(3)  # the time reference is the transition, not zero
    cpu = Cpu(clock, max_cycle_ms=10_000)
    cpu.load(_cyclic(number))  # type: ignore[arg-type]
    cpu.start()
    step = 1 if period <= 100 else 10
    got = _times(clock, cpu, number, 3 * period, step)
    assert got == [3 + period, 3 + 2 * period, 3 + 3 * period]


def test_phase_offset_delays_each_call(clock: VirtualClock) -> None:
    """A phase offset m (0 <= m < n) delays every start by m ms."""
    cpu = Cpu(clock)
    cpu.interrupts.configure(35, 100, phase_ms=30)
    cpu.load(_cyclic(35))  # type: ignore[arg-type]
    cpu.start()
    assert _times(clock, cpu, 35, 400) == [130, 230, 330]
    with pytest.raises(ValueError):
        cpu.interrupts.configure(35, 100, phase_ms=100)


def test_due_interrupts_run_highest_priority_first(clock: VirtualClock) -> None:
    """OB38 (priority 15) before OB35 (12) before OB30 (7)."""
    cpu = Cpu(clock)
    cpu.interrupts.configure(30, 100)
    cpu.interrupts.configure(38, 100)
    cpu.load(_cyclic(30), _cyclic(35), _cyclic(38))  # type: ignore[arg-type]
    cpu.start()
    clock.advance(100)
    assert cpu.scan().ran == (38, 35, 30)


def test_default_priorities() -> None:
    """OB1 = 1, OB10–17 = 2, OB20..23 = 3..6, OB30..38 = 7..15, OB40..47 = 16..23, OB80–87 = 26,
    OB100/101 = 27."""
    assert priority(1) == 1 and priority(17) == 2
    assert [priority(n) for n in (20, 23, 30, 38, 40, 47)] == [3, 6, 7, 15, 16, 23]
    assert priority(80) == priority(87) == 26 and priority(100) == priority(101) == 27
    with pytest.raises(ValueError):
        priority(121)


def test_disabled_cyclic_interrupt_events_are_lost(clock: VirtualClock) -> None:
    """DIS_IRT(MODE 2, OB35) suppresses OB35 events; they are not queued."""
    cpu = Cpu(clock)
    cpu.load(_cyclic(35))  # type: ignore[arg-type]
    cpu.start()
    cpu.interrupts.disable(35)
    assert _times(clock, cpu, 35, 350, 10) == []
    cpu.interrupts.enable(35)
    assert _times(clock, cpu, 35, 100, 10) == [400]


def test_late_scan_runs_the_ob_once_and_reports_lost_events(clock: VirtualClock) -> None:
    """Events missed by a late scan are lost (diag entry), not repeated."""
    cpu = Cpu(clock, max_cycle_ms=1000)
    cpu.load(_cyclic(35))  # type: ignore[arg-type]
    cpu.start()
    clock.advance(350)
    record = cpu.scan()
    assert record.ran == (35,)
    assert [e.event_id for e in record.diagnostics] == [EventId.OB_REQUEST_ERROR]
    assert _times(clock, cpu, 35, 60, 10) == [400]


def test_configured_but_unloaded_interrupt_ob_goes_to_ob85_or_stop(clock: VirtualClock) -> None:
    """An event for a configured, unloaded OB: diag entry + OB85, else STOP."""
    cpu = Cpu(clock)
    cpu.interrupts.configure(36, 50)
    cpu.start()
    clock.advance(50)
    record = cpu.scan()
    assert record.mode is CpuMode.STOP
    assert [e.event_id for e in record.diagnostics] == [
        EventId.INTERRUPT_OB_MISSING,
        EventId.STOP_OB85_MISSING,
    ]
    cpu.load(_cyclic(85))  # type: ignore[arg-type]
    cpu.start()
    clock.advance(50)
    assert cpu.scan().ran == (85,) and cpu.mode is CpuMode.RUN


def test_loaded_but_deselected_ob_aborts_the_startup(clock: VirtualClock) -> None:
    """A deselected (period 0) OB in the program makes the startup abort."""
    cpu = Cpu(clock)
    cpu.interrupts.configure(35, 0)
    cpu.load(_cyclic(35))  # type: ignore[arg-type]
    record = cpu.start()
    assert record.mode is CpuMode.STOP
    assert record.diagnostics[-1].event_id == EventId.STARTUP_REFUSED


def test_scheduler_arms_only_given_obs() -> None:
    """Only loaded OBs get their default period."""
    sched = CyclicScheduler()
    sched.arm([35, 1, 100], 0)
    assert list(sched.active) == [35]
    assert sched.due(99_999_999) == [] and sched.due(100_000_000) == [(35, 0)]


def test_equal_priority_cyclic_obs_run_in_the_order_of_their_start_events(
    clock: VirtualClock,
) -> None:
    """OBs of equal priority never interrupt each other and queue in order of their start events
    (Siemens' Program Design for S7-300/400) — here OB35 (due at 60 ms) before OB36 (due at 100 ms)
    although OB36 has the higher default priority."""
    cpu = Cpu(clock, max_cycle_ms=10_000)
    cpu.load(ob(1)(lambda ctx: None), _cyclic(35), _cyclic(36))  # type: ignore[arg-type]
    cpu.interrupts.configure(35, 60)
    cpu.interrupts.configure(36, 100)
    cpu.start()
    clock.advance(100)
    assert cpu.scan().ran == (1, 36, 35)  # default priorities 13 > 12
    cpu.ob_priority.update({35: 10, 36: 10})
    clock.advance(100)  # OB35 due at 120 and 180, OB36 at 200
    assert cpu.scan().ran == (1, 35, 36)
