"""Delay and time-of-day interrupts, DIS_AIRT/EN_AIRT, equal-priority queueing (Siemens'
Program Design for S7-300/400, ch. 4; STEP7 comprehensive guide vol. 2, ch. 12)."""

from __future__ import annotations

from collections.abc import Callable
from datetime import datetime
from typing import Any

from s7graph.engine.blocks import OB
from s7graph.engine.clock import VirtualClock
from s7graph.engine.cpu import CallContext, Cpu
from s7graph.engine.modes import CpuMode
from s7graph.engine.timed import Period, next_occurrence
from s7graph.sfb import install
from s7graph.sfb.catalogue import as_int

T0 = datetime(2026, 3, 2, 9, 59, 0)


def make_cpu(clock: VirtualClock, *blocks: OB, rtc: datetime = T0) -> Cpu:
    cpu = Cpu(clock, max_cycle_ms=100_000)
    install(cpu)
    cpu.load(*blocks)
    cpu.rtc.set(rtc, clock.now_ns())
    return cpu


def recorder(number: int, log: list[tuple[int, dict[str, Any]]]) -> OB:
    def body(ctx: CallContext) -> None:
        log.append((number, dict(ctx.start_info)))

    return OB(number, f"OB{number}", body)


def once(action: Callable[[CallContext], None]) -> OB:
    done: list[bool] = []

    def main(ctx: CallContext) -> None:
        if not done:
            done.append(True)
            action(ctx)

    return OB(1, "OB1", main)


def test_srt_dint_runs_ob20_once_after_dtime_with_its_sign(clock: VirtualClock) -> None:
    """SRT_DINT(OB_NR:=20, DTIME:=T#20S, SIGN:=w) calls OB20 once after 20 s
    with OB20_SIGN = w; QRY_DINT bit 2 is 1 while pending; CAN_DINT cancels."""
    log: list[tuple[int, dict[str, Any]]] = []
    status: list[int] = []

    def start(ctx: CallContext) -> None:
        assert ctx.call("SRT_DINT", OB_NR=20, DTIME=20_000, SIGN=0x1234)["RET_VAL"] == 0
        assert ctx.call("SRT_DINT", OB_NR=21, DTIME=5_000, SIGN=1)["RET_VAL"] == 0
        assert ctx.call("CAN_DINT", OB_NR=21)["RET_VAL"] == 0
        assert ctx.call("CAN_DINT", OB_NR=21)["RET_VAL"] == as_int(0x80A0)
        assert ctx.call("SRT_DINT", OB_NR=35, DTIME=5, SIGN=0)["RET_VAL"] == as_int(0x8090)
        status.append(ctx.call("QRY_DINT", OB_NR=20, STATUS="MW0")["STATUS"])  # type: ignore[arg-type]

    cpu = make_cpu(clock, once(start), recorder(20, log), recorder(21, log))
    cpu.start()
    cpu.scan()
    assert status == [0x14]  # pending, OB loaded
    for _ in range(30):
        clock.advance(1000)
        cpu.scan()
    assert log == [(20, {"SIGN": 0x1234})]
    assert cpu.delays.status(20) == 0


def test_tod_interrupt_set_is_inactive_until_act_tint_and_repeats_each_minute(
    clock: VirtualClock,
) -> None:
    """SET_TINT sets but does not activate; ACT_TINT activates; PERIOD W#16#0201 repeats every
    minute on the CPU's real-time clock; CAN_TINT stops it."""
    log: list[tuple[int, dict[str, Any]]] = []
    start = datetime(2026, 3, 2, 10, 0, 0)

    def main(ctx: CallContext) -> None:
        if ctx.cycle == 1:
            assert ctx.call("SET_TINT", OB_NR=10, SDT=start, PERIOD=0x0201)["RET_VAL"] == 0
        if ctx.cycle == 3:
            assert ctx.call("ACT_TINT", OB_NR=10)["RET_VAL"] == 0

    cpu = make_cpu(clock, OB(1, "OB1", main), recorder(10, log))
    cpu.start()
    cpu.scan()
    clock.advance(70_000)  # 10:00:10: set, due, but not active
    cpu.scan()
    assert cpu.tod.status(10) == 0 and log == []
    cpu.scan()
    assert cpu.tod.status(10) == 0x04 and log == []
    for _ in range(200):  # 200 s on the virtual clock
        clock.advance(1000)
        cpu.scan()
    assert [info["DATE_TIME"] for _, info in log] == [
        datetime(2026, 3, 2, 10, m) for m in range(1, 4)
    ]
    cpu.tod.cancel(10)
    clock.advance(120_000)
    cpu.scan()
    assert len(log) == 3


def test_activated_tod_interrupts_are_inactive_after_a_warm_restart(clock: VirtualClock) -> None:
    """After a warm restart program-activated TOD interrupts stay inactive until re-activated
    (Siemens' Program Design for S7-300/400); a HW-configured active one comes back by itself."""
    log: list[tuple[int, dict[str, Any]]] = []
    at = datetime(2026, 3, 2, 10, 0, 0)

    def activate(ctx: CallContext) -> None:
        ctx.call("SET_TINT", OB_NR=11, SDT=at, PERIOD=0x1001)
        ctx.call("ACT_TINT", OB_NR=11)

    cpu = make_cpu(clock, once(activate), recorder(11, log), recorder(12, log))
    cpu.tod.configure(12, at, Period.DAY, active=True)
    cpu.start()
    cpu.scan()
    assert cpu.tod.status(11) == 0x04
    cpu.stop()
    cpu.start("warm")
    clock.advance(120_000)  # 10:01
    cpu.scan()
    assert [n for n, _ in log] == [12]
    assert cpu.tod.status(11) == 0 and cpu.tod.status(12) == 0x04


def test_tod_interrupt_due_during_startup_runs_only_after_the_transition_to_run(
    clock: VirtualClock,
) -> None:
    """A TOD interrupt due during STARTUP runs after STARTUP → RUN."""
    log: list[tuple[int, dict[str, Any]]] = []

    def ob100(ctx: CallContext) -> None:
        ctx.call("SET_TINT", OB_NR=10, SDT=datetime(2026, 3, 2, 9, 59, 1), PERIOD=0)
        assert ctx.call("ACT_TINT", OB_NR=10)["RET_VAL"] == 0
        clock.advance(5000)  # a long startup: the interrupt falls due here
        log.append((100, {}))

    cpu = make_cpu(clock, OB(100, "OB100", ob100), recorder(10, log), OB(1, "OB1", lambda c: None))
    record = cpu.start()
    assert record.mode is CpuMode.RUN and record.ran == (100,)
    assert [n for n, _ in log] == [100]
    assert cpu.scan().ran == (1, 10)
    assert cpu.tod.status(10) == 0  # once-only: elapsed


def test_clock_set_forward_calls_ob80_then_runs_the_first_skipped_one_once(
    clock: VirtualClock,
) -> None:
    """Setting the clock forward past pending TOD interrupts calls OB80 (FLT_ID 16#05) with the
    skipped ones; one not cancelled there runs exactly once; one OB80 cancels does not run; setting
    the clock back never repeats an executed one."""
    log: list[tuple[int, dict[str, Any]]] = []
    jump: list[datetime] = []

    def main(ctx: CallContext) -> None:
        if jump:
            ctx.call("SET_CLK", PDT=jump.pop())

    def ob80(ctx: CallContext) -> None:
        log.append((80, dict(ctx.start_info)))
        ctx.call("CAN_TINT", OB_NR=11)

    cpu = make_cpu(
        clock, OB(1, "OB1", main), OB(80, "OB80", ob80), recorder(10, log), recorder(11, log)
    )
    cpu.start()
    cpu.tod.set(10, datetime(2026, 3, 2, 10, 0), Period.MINUTE)
    cpu.tod.set(11, datetime(2026, 3, 2, 10, 0), Period.ONCE)
    now = cpu.rtc.read(clock.now_ns())
    assert cpu.tod.activate(10, now) == 0 and cpu.tod.activate(11, now) == 0
    cpu.scan()
    jump.append(datetime(2026, 3, 2, 11, 0, 30))  # skips 60 occurrences of OB10, OB11 once
    clock.advance(10)
    cpu.scan()
    assert [n for n, _ in log] == [80, 10]
    assert log[0][1]["FLT_ID"] == 0x05 and log[0][1]["SKIPPED"] == (10, 11)
    assert log[1][1]["DATE_TIME"] == datetime(2026, 3, 2, 10, 0) and log[1][1]["SKIPPED"]
    jump.append(datetime(2026, 3, 2, 10, 30))  # back: 10:31 … 11:00 already done once
    clock.advance(10)
    cpu.scan()
    for _ in range(40):
        clock.advance(60_000)
        cpu.scan()
    runs = [info["DATE_TIME"] for n, info in log if n == 10]
    assert runs[1] == datetime(2026, 3, 2, 11, 1) and len(runs) == len(set(runs))


def test_clock_set_forward_without_ob80_stops_the_cpu(clock: VirtualClock) -> None:
    """The skipped-TOD time error needs OB80; without it the CPU stops."""
    cpu = make_cpu(clock, OB(1, "OB1", lambda c: None), recorder(10, []))
    cpu.start()
    cpu.tod.set(10, datetime(2026, 3, 2, 10, 0), Period.ONCE)
    cpu.tod.activate(10, cpu.rtc.read(clock.now_ns()))
    cpu.scan()
    cpu.rtc.set(datetime(2026, 3, 2, 12, 0), clock.now_ns())
    assert cpu.scan().mode is CpuMode.STOP


def test_equal_priority_tod_interrupts_run_in_the_order_of_their_start_events(
    clock: VirtualClock,
) -> None:
    """OB10..OB17 share priority 2 and queue in order of their start events
    (Siemens' Program Design for S7-300/400), not by OB number."""
    log: list[tuple[int, dict[str, Any]]] = []
    cpu = make_cpu(clock, OB(1, "OB1", lambda c: None), recorder(10, log), recorder(11, log))
    cpu.start()
    cpu.tod.set(10, datetime(2026, 3, 2, 10, 0, 1), Period.ONCE)
    cpu.tod.set(11, datetime(2026, 3, 2, 10, 0, 0), Period.ONCE)
    now = cpu.rtc.read(clock.now_ns())
    cpu.tod.activate(10, now)
    cpu.tod.activate(11, now)
    cpu.scan()
    clock.advance(62_000)
    assert cpu.scan().ran == (1, 11, 10)


def test_dis_airt_delays_interrupts_instead_of_dropping_them(clock: VirtualClock) -> None:
    """SFC41 DIS_AIRT delays (never discards) interrupt OBs until EN_AIRT or
    the end of the OB; RET_VAL counts the delays in force, EN_AIRT without one is 8080."""
    rets: list[int] = []

    def main(ctx: CallContext) -> None:
        rets.append(ctx.call("DIS_AIRT")["RET_VAL"])  # type: ignore[arg-type]
        rets.append(ctx.call("DIS_AIRT")["RET_VAL"])  # type: ignore[arg-type]
        rets.append(ctx.call("EN_AIRT")["RET_VAL"])  # type: ignore[arg-type]
        if ctx.cycle == 1:
            ctx.call("SRT_DINT", OB_NR=20, DTIME=1, SIGN=0)

    cpu = make_cpu(clock, OB(1, "OB1", main), recorder(20, []))
    cpu.start()
    cpu.scan()
    clock.advance(5)
    assert cpu.scan().ran == (1, 20)  # OB1 left DIS_AIRT in force: OB20 runs after it
    assert rets[:3] == [1, 2, 1] and cpu.airt_disabled == 0
    assert cpu.en_airt() is None


def test_next_occurrence_skips_months_without_the_start_day() -> None:
    """Monthly from 31 Jan runs only in months with 31 days (Siemens' Program Design for
    S7-300/400); ``W#16#2001`` runs at each month's end."""
    start = datetime(2026, 1, 31, 8, 0)
    assert next_occurrence(start, Period.MONTH, datetime(2026, 2, 1)) == datetime(2026, 3, 31, 8)
    end = next_occurrence(datetime(2026, 1, 15, 8), Period.MONTH_END, datetime(2026, 2, 1))
    assert end == datetime(2026, 2, 28, 8)
    assert next_occurrence(start, Period.ONCE, datetime(2026, 2, 1)) is None
