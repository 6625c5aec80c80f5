"""CPU modes, key switch, mode requests, HOLD and memory reset (docs/runtime.md, "Restarts: warm,
hot, cold", Siemens' Program Design for S7-300/400, ch. 9)."""

from __future__ import annotations

import pytest

from s7graph.engine import (
    DB,
    CallContext,
    Cpu,
    CpuMode,
    EventId,
    InstanceDB,
    KeySwitch,
    ModeRequest,
    VirtualClock,
    fb,
    ob,
)
from s7graph.engine.errors import BlockError


def _counting_cpu(clock: VirtualClock, **kw: object) -> Cpu:
    @ob(1)
    def main(ctx: CallContext) -> None:
        ctx.mem.set("MW20", int(ctx.mem.get("MW20")) + 1)

    cpu = Cpu(clock, **kw)  # type: ignore[arg-type]
    cpu.load(main)
    return cpu


def test_power_on_enters_stop_and_runs_nothing(clock: VirtualClock) -> None:
    """Power-on always enters STOP first; scans in STOP run no OB."""
    cpu = _counting_cpu(clock)
    assert cpu.mode is CpuMode.STOP
    clock.advance(10)
    record = cpu.scan()
    assert record.mode is CpuMode.STOP and record.ran == ()
    assert cpu.mem.get("MW20") == 0


def test_run_request_with_key_in_stop_is_refused(clock: VirtualClock) -> None:
    """STOP→STARTUP only with the key on RUN/RUN-P; a PG RUN request is refused."""
    cpu = _counting_cpu(clock, key=KeySwitch.STOP)
    record = cpu.start()
    assert cpu.mode is CpuMode.STOP
    assert [e.event_id for e in record.diagnostics] == [EventId.STARTUP_REFUSED]
    cpu.set_key(KeySwitch.RUN)
    cpu.start()
    assert cpu.mode is CpuMode.RUN


def test_key_switch_to_stop_stops_a_running_cpu(clock: VirtualClock) -> None:
    """Turning the key to STOP stops the CPU."""
    cpu = _counting_cpu(clock)
    cpu.start()
    cpu.set_key(KeySwitch.STOP)
    assert cpu.mode is CpuMode.STOP
    assert cpu.diagnostics.latest()[0].event_id == EventId.STOP_BY_SWITCH


@pytest.mark.parametrize(
    ("requests", "expected"),
    [
        ([CpuMode.RUN, CpuMode.STOP, CpuMode.HOLD], CpuMode.STOP),
        ([CpuMode.RUN, CpuMode.HOLD], CpuMode.HOLD),
        ([CpuMode.HOLD, CpuMode.STOP], CpuMode.STOP),
    ],
)
def test_simultaneous_mode_requests_resolve_by_priority(
    clock: VirtualClock, requests: list[CpuMode], expected: CpuMode
) -> None:
    """Requests at one scan boundary resolve STOP > HOLD > STARTUP > RUN."""
    cpu = _counting_cpu(clock)
    cpu.start()
    for mode in requests:
        cpu.submit(ModeRequest(mode))
    assert cpu.mode is CpuMode.RUN  # nothing happens before the boundary
    clock.advance(10)
    assert cpu.scan().mode is expected


def test_commands_apply_at_the_scan_boundary(clock: VirtualClock) -> None:
    """Commands go through one queue and are applied before the next scan's OB1."""
    cpu = _counting_cpu(clock)
    cpu.start()
    pending = cpu.submit(lambda c: c.mem.set("MW20", 100))
    assert not pending.done and cpu.mem.get("MW20") == 0
    cpu.scan()
    assert pending.done and cpu.mem.get("MW20") == 101
    bad = cpu.submit(lambda c: 1 // 0)
    cpu.scan()
    assert bad.done and cpu.mode is CpuMode.RUN
    assert bad.error.startswith("an internal error in the CPU while applying a command: ")
    assert "modulo by zero" in bad.error and "ZeroDivisionError" not in bad.error


def test_run_request_in_stop_starts_with_a_warm_restart(clock: VirtualClock) -> None:
    """A RUN request from STOP goes STOP→STARTUP→RUN."""
    cpu = _counting_cpu(clock)
    cpu.submit(ModeRequest(CpuMode.RUN))
    record = cpu.scan()
    assert record.mode is CpuMode.RUN
    assert [e.event_id for e in record.diagnostics] == [
        EventId.STOP_TO_STARTUP,
        EventId.STARTUP_TO_RUN,
    ]


def test_hold_freezes_timers_while_the_clock_runs(clock: VirtualClock) -> None:
    """In HOLD timers are frozen, the real-time clock keeps running."""
    seen: list[int] = []

    @ob(1)
    def main(ctx: CallContext) -> None:
        seen.append(ctx.now_ns)
        ctx.mem.set("Q0.0", True)

    cpu = Cpu(clock)
    cpu.load(main)
    cpu.start()
    clock.advance(10)
    cpu.scan()
    assert cpu.mem.periph_out[0] == 1
    cpu.hold()
    clock.advance(5000)
    record = cpu.scan()
    assert record.mode is CpuMode.HOLD and record.ran == ()
    assert cpu.mem.periph_out[0] == 0  # outputs disabled in HOLD
    assert record.t_ns == 5_010_000_000  # diagnostics/record keep the real clock
    cpu.resume()
    clock.advance(10)
    cpu.scan()
    assert seen[-1] - seen[-2] == 10_000_000  # the 5 s in HOLD never reached the timers
    assert cpu.mem.periph_out[0] == 1


def test_memory_reset_clears_program_and_areas_but_keeps_diagnostics(clock: VirtualClock) -> None:
    """MRES clears program and operand areas; the diagnostic buffer survives."""
    cpu = _counting_cpu(clock)
    cpu.start()
    cpu.mem.set("MW0", 7)  # retentive
    cpu.stop()
    before = len(cpu.diagnostics)
    cpu.memory_reset()
    assert cpu.blocks == {} and cpu.mem.get("MW0") == 0
    assert len(cpu.diagnostics) == before + 1
    assert cpu.diagnostics.latest()[0].event_id == EventId.MEMORY_RESET


def test_memory_reset_is_refused_in_run(clock: VirtualClock) -> None:
    """MRES is possible only in STOP."""
    cpu = _counting_cpu(clock)
    cpu.start()
    with pytest.raises(BlockError):
        cpu.memory_reset()


def test_stop_in_startup_ob_aborts_the_startup(clock: VirtualClock) -> None:
    """A STOP (SFC46 STP) in OB100 moves the CPU to STOP instead of RUN."""

    @ob(100)
    def startup(ctx: CallContext) -> None:
        ctx.cpu.stop("STP in OB100")

    cpu = _counting_cpu(clock)
    cpu.load(startup)
    cpu.start()
    assert cpu.mode is CpuMode.STOP
    assert "aborted warm restart" in cpu.hot_blockers


def test_emitted_events_land_in_the_scan_record(clock: VirtualClock) -> None:
    """Blocks report what happened through ``ctx.emit`` (or ``emit_all``, several in
    order); the record carries it."""

    @ob(1)
    def main(ctx: CallContext) -> None:
        ctx.emit(("S1", ctx.cycle))
        ctx.emit_all([("S0", ctx.cycle), ("V1", ctx.cycle)])

    cpu = Cpu(clock)
    cpu.load(main)
    cpu.start()
    assert cpu.scan().events == (("S1", 1), ("S0", 1), ("V1", 1))
    assert cpu.scan().events == (("S1", 2), ("S0", 2), ("V1", 2))


def test_memory_reset_keeping_the_program_puts_every_area_and_db_to_its_initial_values(
    clock: VirtualClock,
) -> None:
    """MRES with the program kept (its load memory: an S7-300's memory card): the blocks
    stay; retentive and other flags, timers, counters, DBs and instance DBs go back to
    their initial values, a DB created at run time goes, force jobs are deleted; the
    diagnostic buffer stays, the CPU stays in STOP and only a warm restart follows."""

    @fb(5, "Count", STAT={"n": "INT"})
    def count(ctx: CallContext, db: InstanceDB) -> None:
        db.n = int(db.n) + 1  # type: ignore[call-overload]

    @ob(1)
    def main(ctx: CallContext) -> None:
        ctx.call(count, 6)
        ctx.mem.set("MW0", int(ctx.mem.get("MW0")) + 1)  # retentive

    cpu = Cpu(clock)
    cpu.load(main, count, DB(20, 4, init=b"\x00\x07"))
    cpu.create_instance_db(6, count)
    cpu.start()
    for _ in range(3):
        clock.advance(10)
        cpu.scan()
    cpu.mem.set("DB20.DBW0", 99)
    cpu.mem.create_db(30, 2, created=True)
    cpu.mem.counters[0].set_value(5)
    cpu.force("I0.3", True)
    cpu.stop("the switch")
    before = len(cpu.diagnostics)
    cpu.memory_reset(keep_program=True)
    assert cpu.mode is CpuMode.STOP and set(cpu.blocks) >= {"OB1", "FB5", "DB20"}
    assert cpu.mem.get("MW0") == 0 and cpu.instance_dbs[6].n == 0
    assert cpu.mem.get("DB20.DBW0") == 7 and 30 not in cpu.mem.dbs
    assert cpu.mem.counters[0].value == 0 and not cpu.forces and cpu.cycle == 0
    assert [e.event_id for e in cpu.diagnostics.latest()[:2]] == [
        EventId.FORCE_ENDED,
        EventId.MEMORY_RESET,
    ]
    assert len(cpu.diagnostics) == before + 2 and "memory reset" in cpu.hot_blockers
    cpu.start("hot")
    assert cpu.last_restart == "warm" and cpu.mode is CpuMode.RUN
    clock.advance(10)
    cpu.scan()
    assert cpu.mem.get("MW0") == 1 and cpu.instance_dbs[6].n == 1
