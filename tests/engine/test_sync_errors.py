"""Synchronous errors (engine/cpu_errors.py; Siemens' Program Design for S7-300/400, ch. 3-4): an
I/O access error calls OB122 inside the access, SFC44 REPL_VAL gives the failed read its
value, and PI is read-only to the program."""

from __future__ import annotations

from s7graph.engine import CallContext, Cpu, CpuMode, EventId, VirtualClock, ob
from s7graph.sfb import install

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
    """OB122 runs at once, inside the read; REPL_VAL there is what the read returns (its low
    word for a PIW), and the block goes on after it."""
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
    assert (entry.event_id, entry.address) == (EventId.IO_ACCESS_READ, MISSING)


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
