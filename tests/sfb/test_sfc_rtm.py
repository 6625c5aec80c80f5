"""Run-time meters SFC2/3/4 and SFC101 (STEP7 comprehensive guide vol. 2, ch. 12)."""

from __future__ import annotations

from s7graph.engine.blocks import OB
from s7graph.engine.clock import VirtualClock
from s7graph.engine.cpu import CallContext, Cpu
from s7graph.engine.rtm import NS_PER_HOUR
from s7graph.sfb import install
from s7graph.sfb.catalogue import as_int

HOUR_MS = NS_PER_HOUR // 1_000_000


def make_cpu(clock: VirtualClock, reads: list[dict[str, object]]) -> Cpu:
    def main(ctx: CallContext) -> None:
        reads.append(ctx.call("READ_RTM", NR=1, CQ="M0.0", CV="MW2"))

    cpu = Cpu(clock, max_cycle_ms=2**31 - 1)
    install(cpu)
    cpu.load(OB(1, "OB1", main))
    return cpu


def _call(cpu: Cpu, block: str, **params: object) -> dict[str, object]:
    out: list[dict[str, object]] = []
    cpu.submit(lambda c: out.append(c._ctx.call(block, **params)))
    cpu.scan()
    return out[0]


def test_run_time_meter_stops_in_stop_keeps_its_value_across_mres_and_restarts(
    clock: VirtualClock,
) -> None:
    """SET_RTM/CTRL_RTM/READ_RTM count hours only outside STOP; the value survives MRES; a warm
    restart leaves the meter stopped, a hot restart resumes it."""
    reads: list[dict[str, object]] = []
    cpu = make_cpu(clock, reads)
    cpu.start()
    assert _call(cpu, "SET_RTM", NR=1, PV=20)["RET_VAL"] == 0
    assert _call(cpu, "CTRL_RTM", NR=1, S=True)["RET_VAL"] == 0
    clock.advance(3 * HOUR_MS)
    cpu.scan()
    assert reads[-1] == {"RET_VAL": 0, "CQ": True, "CV": 23}
    cpu.stop()
    clock.advance(5 * HOUR_MS)  # STOP: not counted
    assert cpu.meters.hours(1, clock.now_ns()) == 23
    cpu.start("warm")
    clock.advance(HOUR_MS)
    cpu.scan()
    assert reads[-1]["CV"] == 23 and reads[-1]["CQ"] is False  # the program must restart it
    assert _call(cpu, "CTRL_RTM", NR=1, S=True)["RET_VAL"] == 0
    cpu.stop()
    cpu.start("hot")  # a hot restart resumes a started meter by itself
    clock.advance(2 * HOUR_MS)
    cpu.scan()
    assert reads[-1]["CV"] == 25 and reads[-1]["CQ"] is True
    cpu.stop()
    cpu.memory_reset()
    clock.advance(9 * HOUR_MS)
    assert cpu.meters.hours(1, clock.now_ns()) == 25


def test_sixteen_bit_meters_saturate_at_32767_hours_and_sfc101_counts_on(
    clock: VirtualClock,
) -> None:
    """READ_RTM (INT) saturates at 32767 h; SFC101 RTM (DINT) counts on; meter numbers beyond 0..7
    are W#16#8080 for SFC2-4."""
    reads: list[dict[str, object]] = []
    cpu = make_cpu(clock, reads)
    cpu.start()
    got = _call(cpu, "RTM", NR=1, MODE=5, PV=32766, CQ="M0.1", CV="MD4")
    assert got == {"RET_VAL": 0, "CQ": True, "CV": 32766}
    clock.advance(3 * HOUR_MS)
    cpu.scan()
    assert reads[-1]["CV"] == 32767
    assert _call(cpu, "RTM", NR=1, MODE=0, PV=0, CQ="M0.1", CV="MD4")["CV"] == 32769
    assert _call(cpu, "SET_RTM", NR=8, PV=0)["RET_VAL"] == as_int(0x8080)
    assert _call(cpu, "SET_RTM", NR=0, PV=-1)["RET_VAL"] == as_int(0x8081)
