"""The diagnostic buffer (Siemens' Program Design for S7-300/400, ch. 10)."""

from __future__ import annotations

from s7graph.engine import Cpu, CpuMode, DiagnosticBuffer, EventId, VirtualClock


def test_mode_transitions_are_entered_with_time(clock: VirtualClock) -> None:
    """Every mode transition creates an entry with its time stamp."""
    cpu = Cpu(clock)
    clock.advance(1000)
    cpu.start()
    clock.advance(500)
    cpu.stop("operator")
    entries = list(cpu.diagnostics)
    assert [(e.event_id, e.t_ns) for e in entries] == [
        (EventId.STOP_TO_STARTUP, 1_000_000_000),
        (EventId.STARTUP_TO_RUN, 1_000_000_000),
        (EventId.STOP_BY_REQUEST, 1_500_000_000),
    ]
    assert "16#4302" in str(entries[1]) and "operator" in str(entries[2])


def test_ring_buffer_overwrites_the_oldest() -> None:
    """A ring of fixed length, newest overwrites oldest; newest is No. 1."""
    buf = DiagnosticBuffer(3)
    for i in range(5):
        buf.record(i, 0xA100 + i, "OB1", f"user {i}")
    assert len(buf) == 3 and buf.total == 5
    assert [e.event_id for e in buf] == [0xA102, 0xA103, 0xA104]
    assert buf.latest()[0].message == "user 4"
    assert [e.t_ns for e in buf.since(3)] == [3, 4]


def test_buffer_survives_restart_and_memory_reset(clock: VirtualClock) -> None:
    """The program cannot clear it; it survives restarts and MRES."""
    cpu = Cpu(clock, diag_capacity=50)
    for kind in ("warm", "cold", "hot"):
        cpu.start(kind)
        cpu.stop()
    n = len(cpu.diagnostics)
    cpu.memory_reset()
    assert len(cpu.diagnostics) == n + 1 and cpu.mode is CpuMode.STOP
