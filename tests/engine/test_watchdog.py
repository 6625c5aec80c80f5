"""Cycle-time monitoring (docs/runtime.md, "When a scan hangs or fails")."""

from __future__ import annotations

import pytest

from s7graph.engine import CallContext, Cpu, CpuMode, EventId, VirtualClock, ob
from s7graph.engine.watchdog import CycleStatistics, Verdict, Watchdog

flt: list[object] = []


@ob(1)
def main(ctx: CallContext) -> None:
    pass


@ob(80)
def time_error(ctx: CallContext) -> None:
    flt.append(ctx.start_info["FLT_ID"])


def _run(clock: VirtualClock, *blocks: object, cycles_ms: tuple[int, ...]) -> Cpu:
    flt.clear()
    cpu = Cpu(clock)
    cpu.load(main, *blocks)  # type: ignore[arg-type]
    cpu.start()
    cpu.scan()
    for ms in cycles_ms:
        clock.advance(ms)
        cpu.scan()
    return cpu


def test_cycle_over_150ms_without_ob80_stops(clock: VirtualClock) -> None:
    """Default maximum 150 ms; exceeded without OB80 → STOP."""
    cpu = _run(clock, cycles_ms=(150,))
    assert cpu.mode is CpuMode.RUN
    clock.advance(151)
    record = cpu.scan()
    assert record.mode is CpuMode.STOP
    assert [e.event_id for e in record.diagnostics] == [
        EventId.CYCLE_TIME_EXCEEDED,
        EventId.STOP_OB80_MISSING,
    ]


def test_cycle_over_max_calls_ob80_with_flt_id_1(clock: VirtualClock) -> None:
    """With OB80 loaded it is called with FLT_ID 16#01 and the CPU runs on."""
    cpu = _run(clock, time_error, cycles_ms=(200,))
    assert cpu.mode is CpuMode.RUN and flt == [0x01]


def test_twice_the_maximum_stops_even_with_ob80(clock: VirtualClock) -> None:
    """Exceeding 2 × T_max in one cycle → STOP even with OB80."""
    cpu = _run(clock, time_error, cycles_ms=(301,))
    assert cpu.mode is CpuMode.STOP and flt == []


def test_re_trigr_restarts_the_monitoring(clock: VirtualClock) -> None:
    """SFC43 RE_TRIGR in a long cycle grants it another T_max."""

    @ob(1)
    def long_loop(ctx: CallContext) -> None:
        ctx.cpu.retrigger()

    cpu = _run(clock, long_loop, cycles_ms=(250,))
    assert cpu.mode is CpuMode.RUN


def test_configured_maximum_applies(clock: VirtualClock) -> None:
    """The maximum cycle time is a parameter."""
    cpu = Cpu(clock, max_cycle_ms=20)
    cpu.load(main)
    cpu.start()
    cpu.scan()
    clock.advance(21)
    assert cpu.scan().mode is CpuMode.STOP


def test_watchdog_verdicts() -> None:
    """OK up to T_max, OB80 above, STOP above 2 × T_max or without OB80."""
    wd = Watchdog(100)
    assert wd.check(100_000_000, has_ob80=True) is Verdict.OK
    assert wd.check(150_000_000, has_ob80=True) is Verdict.OB80
    assert wd.check(150_000_000, has_ob80=False) is Verdict.STOP
    assert wd.check(200_000_001, has_ob80=True) is Verdict.STOP
    with pytest.raises(ValueError):
        Watchdog(10, 20)


def test_cycle_statistics_keep_last_min_max_mean() -> None:
    """Cycle statistics as reported in OB1 start info."""
    stats = CycleStatistics()
    for ns in (30, 10, 20):
        stats.add(ns * 1_000_000)
    assert (stats.last_ns, stats.min_ns, stats.max_ns) == (20_000_000, 10_000_000, 30_000_000)
    assert stats.mean_ns == 20_000_000
