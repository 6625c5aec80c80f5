"""The scan cycle: process images, outputs, programming errors (docs/runtime.md, "When a scan hangs
or fails", Siemens' Program Design for S7-300/400, ch. 3)."""

from __future__ import annotations

import dataclasses
import itertools

import pytest

from s7graph.engine import (
    CallContext,
    Cpu,
    CpuMode,
    EventId,
    InstanceDB,
    ScanRecord,
    VirtualClock,
    fb,
    fc,
    ob,
)


class CountingClock(VirtualClock):
    reads = 0

    def now_ns(self) -> int:
        self.reads += 1
        return super().now_ns()


def test_scan_reads_the_clock_once() -> None:
    """docs/architecture.md, "The core is a function": every time-dependent rule reads one clock,
    once per scan."""
    clock = CountingClock()

    @ob(1)
    def main(ctx: CallContext) -> None:
        ctx.mem.set("MW10", ctx.now_ns // 1_000_000)

    @ob(35)
    def cyclic(ctx: CallContext) -> None:
        pass

    cpu = Cpu(clock)
    cpu.load(main, cyclic)
    cpu.start()
    clock.advance(100)
    clock.reads = 0
    record = cpu.scan()
    assert clock.reads == 1 and record.ran == (1, 35)
    assert cpu.mem.get("MW10") == 100


def test_inputs_are_read_once_per_cycle_and_outputs_written_once(clock: VirtualClock) -> None:
    """PII updated once before OB1; input changes during OB1 are invisible until the next cycle; PIQ
    reaches the modules once, after OB1."""
    seen: list[bool] = []

    @ob(1)
    def main(ctx: CallContext) -> None:
        ctx.mem.periph_in[0] = 0  # the module changes mid-cycle
        seen.append(bool(ctx.mem.get("I0.0")))
        ctx.mem.set("Q0.0", True)
        seen.append(bool(ctx.mem.periph_out[0]))

    cpu = Cpu(clock)
    cpu.load(main)
    cpu.start()
    cpu.mem.periph_in[0] = 1
    record = cpu.scan()
    assert seen == [True, False]
    assert record.outputs == {"PQB0": 1} and cpu.mem.periph_out[0] == 1
    cpu.scan()
    assert seen[2] is False


def test_direct_peripheral_reads_see_the_module_mid_cycle(clock: VirtualClock) -> None:
    """PIW returns the module value at once; update_pii (SFC26) refreshes I."""
    seen: list[object] = []

    @ob(1)
    def main(ctx: CallContext) -> None:
        ctx.mem.periph_in[2:4] = b"\x12\x34"
        seen.append(ctx.mem.get("PIW2"))
        seen.append(ctx.mem.get("IW2"))
        ctx.cpu.update_pii()
        seen.append(ctx.mem.get("IW2"))

    cpu = Cpu(clock)
    cpu.load(main)
    cpu.start()
    cpu.scan()
    assert seen == [0x1234, 0, 0x1234]


def test_outputs_are_zero_outside_run(clock: VirtualClock) -> None:
    """docs/runtime.md, "Restarts: warm, hot, cold": module outputs are 0 in STOP; the record
    reports the change."""

    @ob(1)
    def main(ctx: CallContext) -> None:
        ctx.mem.set("QB1", 0xF0)

    cpu = Cpu(clock)
    cpu.load(main)
    cpu.start()
    assert cpu.scan().outputs == {"PQB1": 0xF0}
    cpu.stop()
    record = cpu.scan()
    assert record.outputs == {"PQB1": 0} and cpu.mem.periph_out[1] == 0
    assert cpu.scan().outputs == {}


def test_scan_record_is_frozen(clock: VirtualClock) -> None:
    """A ScanRecord is an immutable value (docs/architecture.md, "The core is a function")."""
    cpu = Cpu(clock)
    record = cpu.start()
    assert isinstance(record, ScanRecord)
    with pytest.raises(dataclasses.FrozenInstanceError):
        record.cycle = 5  # type: ignore[misc]


def test_ob1_start_info_reports_cycle_times(clock: VirtualClock) -> None:
    """OB1 start info gives previous, minimum and maximum cycle time in ms."""
    infos: list[dict[str, object]] = []

    @ob(1)
    def main(ctx: CallContext) -> None:
        infos.append(dict(ctx.start_info))

    cpu = Cpu(clock)
    cpu.load(main)
    cpu.start()
    for ms in (0, 20, 5, 40):
        clock.advance(ms)
        cpu.scan()
    assert infos[-1] == {"PREV_CYCLE": 40, "MIN_CYCLE": 5, "MAX_CYCLE": 40}
    assert cpu.stats.mean_ns == pytest.approx(65e6 / 3)


def test_minimum_cycle_time_delays_ob1_but_not_interrupts(clock: VirtualClock) -> None:
    """OB1 does not restart before T_min; interrupt OBs run during the wait."""

    @ob(1)
    def main(ctx: CallContext) -> None:
        pass

    @ob(38)
    def fast(ctx: CallContext) -> None:
        pass

    cpu = Cpu(clock, min_cycle_ms=50)
    cpu.load(main, fast)
    cpu.start()
    ran: list[tuple[int, ...]] = []
    for _ in range(10):
        clock.advance(10)
        ran.append(cpu.scan().ran)
    assert ran[0] == (1, 38)
    assert ran[1:5] == [(38,)] * 4
    assert ran[5] == (1, 38)
    assert cpu.cycle == 2


def test_clock_memory_bits_toggle_with_their_periods(clock: VirtualClock) -> None:
    """Clock-memory bits 0..7 have periods 0.1/0.2/0.4/0.5/0.8/1/1.6/2 s."""
    cpu = Cpu(clock, clock_memory=100)
    cpu.start()
    samples = []
    for _ in range(400):
        clock.advance(10)
        cpu.scan()
        samples.append(cpu.mem.markers[100])
    for bit, period_ms in enumerate((100, 200, 400, 500, 800, 1000, 1600, 2000)):
        bits = [(s >> bit) & 1 for s in samples]
        changes = sum(1 for a, b in itertools.pairwise(bits) if a != b)
        assert changes == pytest.approx(2 * 4000 / period_ms, abs=1), bit
        assert sum(bits) == pytest.approx(len(bits) / 2, abs=period_ms / 20)  # duty 1:1


def test_python_exception_goes_to_stop_without_ob121(clock: VirtualClock) -> None:
    """A programming error without OB121 → STOP with block and message."""

    @fc(3, IN={"x": "INT"}, RET="INT")
    def divide(ctx: CallContext, p: dict[str, object]) -> object:
        return 100 // int(p["x"])  # type: ignore[call-overload]

    @ob(1)
    def main(ctx: CallContext) -> None:
        ctx.call(divide, x=0)
        ctx.mem.set("Q0.0", True)

    cpu = Cpu(clock)
    cpu.load(main, divide)
    cpu.start()
    clock.advance(10)
    record = cpu.scan()
    assert record.mode is CpuMode.STOP and cpu.mem.periph_out[0] == 0
    error, stop = record.diagnostics
    assert error.block == "FC3" and "ZeroDivisionError" in error.message
    assert error.t_ns == 10_000_000
    assert stop.event_id == EventId.STOP_OB121_MISSING


def test_python_exception_calls_ob121_and_the_cpu_keeps_running(clock: VirtualClock) -> None:
    """With OB121 loaded the error is handled and the CPU stays in RUN."""
    faults: list[object] = []

    @ob(1)
    def main(ctx: CallContext) -> None:
        ctx.mem.set("Q0.1", True)
        ctx.call("FC9")  # not loaded

    @ob(121)
    def prog_error(ctx: CallContext) -> None:
        faults.append((ctx.start_info["BLOCK"], ctx.start_info["SW_FLT"]))

    cpu = Cpu(clock)
    cpu.load(main, prog_error)
    cpu.start()
    record = cpu.scan()
    assert record.mode is CpuMode.RUN and record.ran == (1, 121)
    assert faults == [("OB1", 0x3C)]
    assert record.diagnostics[0].event_id == EventId.FC_NOT_LOADED
    assert cpu.mem.periph_out[0] == 2
    cpu.scan()
    assert len(faults) == 2


def test_error_inside_ob121_stops_the_cpu(clock: VirtualClock) -> None:
    """OB121 that fails itself cannot recover: STOP."""

    @ob(1)
    def main(ctx: CallContext) -> None:
        raise ValueError("first")

    @ob(121)
    def prog_error(ctx: CallContext) -> None:
        raise ValueError("second")

    cpu = Cpu(clock)
    cpu.load(main, prog_error)
    cpu.start()
    assert cpu.scan().mode is CpuMode.STOP


def test_nesting_overflow_stops_and_allows_only_warm_restart(clock: VirtualClock) -> None:
    """Block-stack overflow → STOP; afterwards only a warm restart."""

    @fb(1)
    def recurse(ctx: CallContext, db: InstanceDB) -> None:
        ctx.call(recurse, db)

    @ob(1)
    def main(ctx: CallContext) -> None:
        ctx.call(recurse, 1)

    @ob(121)
    def prog_error(ctx: CallContext) -> None:
        pass

    cpu = Cpu(clock, max_nesting=8)
    cpu.load(main, recurse, prog_error)
    cpu.create_instance_db(1, recurse)
    cpu.start()
    record = cpu.scan()
    assert record.mode is CpuMode.STOP
    assert record.diagnostics[-1].event_id == EventId.STACK_OVERFLOW
    assert "STOP by an error (block stack overflow)" in cpu.hot_blockers
    cpu.start("hot")
    assert cpu.last_restart == "warm"


@pytest.mark.parametrize(("ob_number", "stops"), [(81, False), (82, True), (86, True)])
def test_missing_async_error_ob_stops_except_ob81(
    clock: VirtualClock, ob_number: int, stops: bool
) -> None:
    """OB82–OB87 missing → STOP on the event; OB81 missing → diag entry only."""
    cpu = Cpu(clock)
    cpu.start()
    cpu.raise_async_error(ob_number)
    assert (cpu.mode is CpuMode.STOP) is stops
    assert any(e.block == f"OB{ob_number}" for e in cpu.diagnostics)


def test_loaded_async_error_ob_handles_the_event(clock: VirtualClock) -> None:
    """With OB82 loaded the CPU stays in RUN."""
    got: list[object] = []

    @ob(82)
    def diag_int(ctx: CallContext) -> None:
        got.append(ctx.start_info["MDL_ADDR"])

    cpu = Cpu(clock)
    cpu.load(diag_int)
    cpu.start()
    cpu.raise_async_error(82, {"MDL_ADDR": 256})
    assert cpu.mode is CpuMode.RUN and got == [256]
