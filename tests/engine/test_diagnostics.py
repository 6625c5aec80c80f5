"""The diagnostic buffer (Siemens' Program Design for S7-300/400, ch. 10)."""

from __future__ import annotations

import sqlite3
import time
from pathlib import Path

import pytest

from s7graph.engine import (
    CallContext,
    Cpu,
    CpuMode,
    DiagEntry,
    DiagnosticBuffer,
    EventId,
    SystemClock,
    VirtualClock,
    ob,
)
from s7graph.engine.diag_events import (
    EVENT_TEXTS,
    event_text,
    hex_id,
    priority_class,
    requested_ob,
    stop_cause,
)
from s7graph.engine.persistence import StateStore


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


def test_an_entry_carries_the_wall_clock_time_of_a_system_clock() -> None:
    """On the system clock each entry is stamped with the wall-clock time of its event (a
    programming device shows date and time); on a virtual clock with none (0)."""
    before = time.time_ns()
    cpu = Cpu(SystemClock())
    cpu.start()
    after = time.time_ns()
    entry = cpu.diagnostics.latest()[0]
    assert before - 50_000_000 <= entry.wall_ns <= after + 50_000_000
    assert Cpu(VirtualClock()).diagnostics.record(5, EventId.STOP_BY_REQUEST).wall_ns == 0


def test_a_programming_error_records_the_ob_whose_program_faulted(clock: VirtualClock) -> None:
    """The entry of a programming error names the OB that ran the faulty block: OB121 is
    requested in that OB's priority class (STEP 7's "Requested OB", "Priority class")."""

    @ob(1)
    def main(ctx: CallContext) -> None:
        pass

    @ob(35)
    def cyclic(ctx: CallContext) -> None:
        raise ZeroDivisionError("division by zero")

    cpu = Cpu(clock)
    cpu.load(main, cyclic)
    cpu.interrupts.configure(35, 100)
    cpu.start()
    for _ in range(15):
        clock.advance(10)
        cpu.scan()
    error = next(e for e in cpu.diagnostics if e.event_id == EventId.PYTHON_EXCEPTION)
    assert (error.ob, requested_ob(error), priority_class(error, cpu.priority_of)) == (35, 121, 12)
    assert cpu.stop_entry is not None and stop_cause(cpu.diagnostics, cpu.stop_entry) is error
    stop = cpu.stop_entry
    assert (stop.event_id, requested_ob(stop), event_text(stop.event_id)) == (
        EventId.STOP_OB121_MISSING,
        121,
        "STOP caused by a programming error (OB121 not loaded)",
    )


def test_every_event_the_runtime_writes_has_its_text_and_unknown_ones_their_class() -> None:
    """Each event ID of ``EventId`` has a text (an asynchronous error its OB's); others the
    text of their class; IDs as STEP 7 writes them (``16#4302``)."""
    assert [e for e in EventId if e not in EVENT_TEXTS] == [EventId.ASYNC_ERROR]
    assert event_text(EventId.ASYNC_ERROR) == "Asynchronous error for OB80"
    assert event_text(0x2599) == "Programming error" and event_text(0x3903) == (
        "Asynchronous error for OB83"
    )
    assert hex_id(0x4302) == "16#4302" and event_text(0x1234) == "Event"


@pytest.mark.parametrize(
    ("event", "block", "ob", "pk"),
    [
        (EventId.CYCLE_TIME_EXCEEDED, "OB1", 80, 26),
        (EventId.ASYNC_ERROR | 2, "OB82", 82, 26),
        (EventId.STOP_TO_STARTUP, "OB100", 100, 27),
        (EventId.STOP_OB80_MISSING, "OB80", 80, 26),
        (EventId.INTERRUPT_OB_MISSING, "OB35", 85, 26),
        (EventId.STARTUP_TO_RUN, "", 0, 0),
        (EventId.FORCE_STARTED, "", 0, 0),
        (0x2522, "FC3", 121, 1),
    ],
)
def test_each_event_requests_its_ob_in_its_priority_class(
    event: int, block: str, ob: int, pk: int
) -> None:
    entry = DiagEntry(0, event, block, "")
    assert (requested_ob(entry), priority_class(entry)) == (ob, pk)


def test_the_wall_time_and_ob_of_an_entry_survive_the_state_file(tmp_path: Path) -> None:
    """The state file keeps each entry's wall-clock time and OB, so the buffer a restart
    reads back shows when each event happened in the run before."""
    cpu = Cpu(VirtualClock())
    entry = DiagEntry(7, 0x2522, "FC3", "area", "MW300", ob=35, wall_ns=123)
    cpu.diagnostics.add(entry)
    store = StateStore(tmp_path / "s.sqlite")
    store.save(cpu)
    store.close()
    again = Cpu(VirtualClock())
    store = StateStore(tmp_path / "s.sqlite")
    store.load(again)
    store.close()
    assert again.diagnostics.latest()[0] == entry


def test_a_state_file_written_before_the_wall_time_column_gets_it(tmp_path: Path) -> None:
    """A state file from before the ``ob`` and ``wall_ns`` columns is read (its entries
    without a wall time) and written with them from then on."""
    path = tmp_path / "old.sqlite"
    store = StateStore(path)
    store.save(Cpu(VirtualClock()))
    store.close()
    con = sqlite3.connect(path)
    con.executescript(
        "DROP TABLE diagnostics;"
        "CREATE TABLE diagnostics (seq INTEGER PRIMARY KEY, t_ns INTEGER, event_id INTEGER,"
        " block TEXT, message TEXT, address TEXT);"
        "INSERT INTO diagnostics VALUES (0, 5, 17156, '', 'STOP requested', '');"
    )
    con.close()
    cpu = Cpu(VirtualClock())
    store = StateStore(path)
    store.load(cpu)
    assert [(e.event_id, e.wall_ns) for e in cpu.diagnostics] == [(0x4304, 0)]
    cpu.diagnostics.add(DiagEntry(9, 0x4301, "OB100", "warm restart", wall_ns=99))
    store.save(cpu)
    store.close()
    con = sqlite3.connect(path)
    rows = con.execute("SELECT event_id, wall_ns FROM diagnostics ORDER BY seq").fetchall()
    con.close()
    assert rows == [(0x4304, 0), (0x4301, 99)]


def test_an_entry_shows_its_requested_ob_in_the_class_the_cpu_runs_that_ob_in(
    clock: VirtualClock,
) -> None:
    """One rule (``interrupts.class_at_start``) for the class an OB starts in and the class
    an entry shows for the OB it requests: OB121 after an error of OB35 parametrised to
    class 15 runs in 15 and the error entry says 15; OB80 requested by an event of a
    startup OB runs in 28, not its RUN class 26."""
    from s7graph.engine import fc
    from s7graph.sfb import install

    seen: dict[int, int] = {}

    @fc(60, IN={"EVENTN": "WORD"})
    def note(ctx: CallContext, p: dict[str, object]) -> None:
        ctx.call("WR_USMSG", SEND=False, EVENTN=p["EVENTN"], INFO1="", INFO2="")

    @ob(100)
    def startup(ctx: CallContext) -> None:
        seen[80] = cpu.priority_class(80)

    @ob(35)
    def cyclic(ctx: CallContext) -> None:
        raise ValueError("in OB35")

    @ob(121)
    def prog_error(ctx: CallContext) -> None:
        ctx.call(note, EVENTN=0xA121)

    @ob(1)
    def main(ctx: CallContext) -> None:
        pass

    cpu = Cpu(clock)
    install(cpu)
    cpu.load(note, startup, cyclic, prog_error, main)
    cpu.ob_priority[35] = 15
    cpu.interrupts.configure(35, 100)
    cpu.start()
    clock.advance(100)
    cpu.scan()
    error = next(e for e in cpu.diagnostics if e.event_id == EventId.PYTHON_EXCEPTION)
    in_ob121 = next(e for e in cpu.diagnostics if e.event_id == 0xA121)
    assert (error.ob, in_ob121.priority, priority_class(error, cpu.priority_of)) == (35, 15, 15)
    late = DiagEntry(0, EventId.CYCLE_TIME_EXCEEDED, "OB100", "", ob=100, priority=27)
    assert seen[80] == priority_class(late, cpu.priority_of) == 28
    in_run = DiagEntry(0, EventId.CYCLE_TIME_EXCEEDED, "OB1", "", ob=1, priority=1)
    assert priority_class(in_run, cpu.priority_of) == 26
