"""Synchronous errors and priority classes (engine/cpu_errors.py; Siemens' Program Design for
S7-300/400, ch. 3-4 and 10): an I/O access error calls OB122 inside the access, SFC44 REPL_VAL
gives the failed read its value, PI is read-only to the program, and every diagnostic entry
carries the priority class of the OB in which its event happened."""

from __future__ import annotations

from datetime import datetime
from pathlib import Path

from s7graph.engine import CallContext, Cpu, CpuMode, EventId, VirtualClock, fc, ob
from s7graph.engine.persistence import StateStore
from s7graph.sfb import install
from s7graph.sfb.diag_read import encode_record

MISSING = "PIW2000"  # the peripheral areas end at byte 1023: no module answers there


def _cpu(clock: VirtualClock, *blocks: object) -> Cpu:
    cpu = Cpu(clock)
    install(cpu)
    cpu.load(*blocks)  # type: ignore[arg-type]
    cpu.start()
    return cpu


def test_a_read_of_a_missing_peripheral_address_runs_ob122_and_goes_on_with_repl_val(
    clock: VirtualClock,
) -> None:
    """OB122 runs at once, inside the read, in the faulting OB's class; REPL_VAL there is
    what the read returns (its low word for a PIW), and the block goes on after it."""
    infos: list[dict[str, object]] = []

    @ob(1)
    def main(ctx: CallContext) -> None:
        ctx.mem.set("MW10", ctx.mem.get(MISSING))
        ctx.mem.set("Q0.0", True)

    @ob(122)
    def io_error(ctx: CallContext) -> None:
        infos.append(dict(ctx.start_info))
        ret = ctx.call("REPL_VAL", VAL=0x0001_04D2)
        ctx.mem.set("MW20", ret["RET_VAL"])

    cpu = _cpu(clock, main, io_error)
    record = cpu.scan()
    assert record.mode is CpuMode.RUN and record.ran == (1, 122)
    assert cpu.mem.get("MW10") == 1234 and cpu.mem.get("MW20") == 0
    assert cpu.mem.get("Q0.0") is True  # the rest of OB1 ran
    assert infos[0]["SW_FLT"] == 0x42 and infos[0]["FAULT_OB"] == 1
    assert infos[0]["ADDRESS"] == MISSING
    (entry,) = record.diagnostics
    assert (entry.event_id, entry.address, entry.priority) == (EventId.IO_ACCESS_READ, MISSING, 1)


def test_a_read_without_repl_val_returns_0_and_a_failed_write_is_not_made(
    clock: VirtualClock,
) -> None:
    """Without REPL_VAL a failed read returns 0; a write to a missing PQ address calls OB122
    (SW_FLT 16#43) and changes nothing."""
    faults: list[object] = []

    @ob(1)
    def main(ctx: CallContext) -> None:
        ctx.mem.set("MW10", 7)
        ctx.mem.set("MW10", ctx.mem.get("PID2000"))
        ctx.mem.set("PQW2000", 5)

    @ob(122)
    def io_error(ctx: CallContext) -> None:
        faults.append(ctx.start_info["SW_FLT"])

    cpu = _cpu(clock, main, io_error)
    record = cpu.scan()
    assert record.mode is CpuMode.RUN and cpu.mem.get("MW10") == 0
    assert faults == [0x42, 0x43]
    assert [e.event_id for e in record.diagnostics] == [
        EventId.IO_ACCESS_READ,
        EventId.IO_ACCESS_WRITE,
    ]


def test_an_io_access_error_without_ob122_stops_the_cpu_not_ob121(clock: VirtualClock) -> None:
    """An I/O access error goes to OB122, never OB121: without OB122 the CPU stops."""
    ran: list[int] = []

    @ob(1)
    def main(ctx: CallContext) -> None:
        ctx.mem.get(MISSING)

    @ob(121)
    def prog_error(ctx: CallContext) -> None:
        ran.append(121)

    cpu = _cpu(clock, main, prog_error)
    record = cpu.scan()
    assert record.mode is CpuMode.STOP and ran == []
    error, stop = record.diagnostics
    assert error.event_id == EventId.IO_ACCESS_READ and error.address == MISSING
    assert stop.event_id == EventId.STOP_OB122_MISSING


def test_the_program_cannot_write_the_peripheral_inputs(clock: VirtualClock) -> None:
    """PI is the modules' side: a block writing it is a programming error (OB121, area error
    on write); the modules (a plant, a stimulus) write it between scans."""
    faults: list[object] = []

    @ob(1)
    def main(ctx: CallContext) -> None:
        ctx.mem.set("PIW0", 5)

    @ob(121)
    def prog_error(ctx: CallContext) -> None:
        faults.append(ctx.start_info["SW_FLT"])

    cpu = _cpu(clock, main, prog_error)
    record = cpu.scan()
    assert faults == [0x25] and cpu.mem.get("PIW0") == 0
    assert record.diagnostics[0].event_id == EventId.AREA_WRITE_ERROR
    cpu.mem.set("PIW0", 9)  # the module side, outside the program
    assert cpu.mem.get("PIW0") == 9


def test_diagnostic_entries_carry_the_priority_class_of_their_ob(
    clock: VirtualClock, tmp_path: Path
) -> None:
    """An entry carries the class of the OB in which its event happened: OB100 27, OB1 1,
    OB35 12, and OB121 the class of the OB whose error called it; 0 outside every OB. The
    state file keeps them (and SFC51 reads them)."""

    @fc(60, IN={"EVENTN": "WORD"})
    def note(ctx: CallContext, p: dict[str, object]) -> None:
        ctx.call("WR_USMSG", SEND=False, EVENTN=p["EVENTN"], INFO1="", INFO2="")

    @ob(100)
    def startup(ctx: CallContext) -> None:
        ctx.call(note, EVENTN=0xA100)

    @ob(1)
    def main(ctx: CallContext) -> None:
        ctx.call(note, EVENTN=0xA101)

    @ob(35)
    def cyclic(ctx: CallContext) -> None:
        ctx.call(note, EVENTN=0xA135)
        raise ValueError("in OB35")

    @ob(121)
    def prog_error(ctx: CallContext) -> None:
        ctx.call(note, EVENTN=0xA121)

    cpu = _cpu(clock, startup, main, cyclic, prog_error)
    clock.advance(100)
    cpu.scan()
    got = [(e.event_id, e.ob, e.priority) for e in cpu.diagnostics]
    assert got == [
        (EventId.STOP_TO_STARTUP, 0, 0),
        (0xA100, 100, 27),
        (EventId.STARTUP_TO_RUN, 0, 0),
        (0xA101, 1, 1),
        (0xA135, 35, 12),
        (EventId.PYTHON_EXCEPTION, 35, 12),
        (0xA121, 121, 12),
    ]
    store = StateStore(tmp_path / "s.sqlite")
    store.save(cpu)
    store.close()
    again = Cpu(VirtualClock())
    store = StateStore(tmp_path / "s.sqlite")
    assert store.load(again)
    assert [(e.event_id, e.ob, e.priority) for e in again.diagnostics] == got
    record = encode_record(list(cpu.diagnostics)[4], datetime(2026, 1, 1))
    assert record[2:4] == bytes([12, 35])  # priority class, OB number
