"""System blocks called through the engine: SFB instances, STP, WAIT, clock, BLKMOV, alarms
(docs/runtime.md, "Programs of blocks in Python" and "The block runtime")."""

from __future__ import annotations

from datetime import datetime

from s7graph.engine.blocks import DB, ob
from s7graph.engine.clock import VirtualClock
from s7graph.engine.cpu import CallContext, Cpu
from s7graph.engine.modes import CpuMode
from s7graph.sfb import SYSTEM_BLOCKS, install, message_list
from s7graph.sfb.alarms import MessageEvent
from s7graph.sfb.catalogue import CATALOGUE, lookup
from s7graph.sfb.iec_timers import SFB4, TON
from s7graph.sfb.sfc_control import Waited


def make_cpu(clock: VirtualClock, body: object, *extra: object) -> Cpu:
    cpu = Cpu(clock)
    install(cpu)
    cpu.load(ob(1)(body), *extra)  # type: ignore[arg-type]
    return cpu


def test_ton_as_sfb4_with_an_instance_db_follows_the_scan_clock(clock: VirtualClock) -> None:
    """``CALL SFB4, DB10 (IN := I0.0, PT := T#50MS, Q => Q4.0)``."""

    def main(ctx: CallContext) -> None:
        ctx.call("SFB4", 10, IN="I0.0", PT=50, Q="Q4.0")

    cpu = make_cpu(clock, main)
    idb = cpu.create_instance_db(10, SFB4)
    cpu.start()
    cpu.mem.set("I0.0", True)
    cpu.mem.periph_in[0] = 1
    cpu.scan()
    clock.advance(49)
    cpu.scan()
    assert cpu.mem.get("Q4.0") is False and idb["ET"] == 49
    clock.advance(1)
    cpu.scan()
    assert cpu.mem.get("Q4.0") is True and idb["Q"] is True
    assert isinstance(idb["STATE"], TON)
    copy = cpu.create_instance_db(11, SFB4)
    copy.restore(idb.snapshot())
    assert copy["STATE"] == idb["STATE"]


def test_stp_in_ob1_puts_the_cpu_into_stop(clock: VirtualClock) -> None:
    """SFC46 STP moves the CPU to STOP."""

    def main(ctx: CallContext) -> None:
        if ctx.cycle >= 2:
            ctx.call("SFC46")

    cpu = make_cpu(clock, main)
    cpu.start()
    cpu.scan()
    assert cpu.mode is CpuMode.RUN
    for _ in range(3):
        clock.advance(10)
        cpu.scan()
    assert cpu.mode is CpuMode.STOP
    assert any("STP" in e.message for e in cpu.diagnostics)


def test_stp_in_ob100_stops_the_startup(clock: VirtualClock) -> None:
    """STP works from OB100 too."""

    def startup(ctx: CallContext) -> None:
        ctx.call("STP")

    cpu = make_cpu(clock, lambda ctx: None, ob(100)(startup))
    cpu.start()
    assert cpu.mode is CpuMode.STOP


def test_wait_is_recorded_without_advancing_time(clock: VirtualClock) -> None:
    def main(ctx: CallContext) -> None:
        ctx.call("WAIT", WT=20000)

    cpu = make_cpu(clock, main)
    cpu.start()
    record = cpu.scan()
    assert Waited(20000) in record.events
    assert clock.now_ns() == record.t_ns


def test_sfcs_return_ret_val_and_blkmov_rejects_a_bool_any_not_a_multiple_of_8(
    clock: VirtualClock,
) -> None:
    """RET_VAL >= 0 on success, < 0 (8x22) on error."""
    results: list[dict[str, object]] = []

    def main(ctx: CallContext) -> None:
        results.append(ctx.call("BLKMOV", SRCBLK="P#M0.0 BYTE 4", DSTBLK="P#M10.0 BYTE 4"))
        results.append(ctx.call("BLKMOV", SRCBLK="P#M0.0 BOOL 7", DSTBLK="P#M20.0 BYTE 1"))
        results.append(ctx.call("SFC21", BVAL="P#M0.0 BYTE 2", BLK="P#M30.0 BYTE 5"))
        results.append(ctx.call("BLKMOV", SRCBLK="nonsense", DSTBLK="P#M20.0 BYTE 1"))

    cpu = make_cpu(clock, main)
    cpu.mem.markers[0:4] = b"\x01\x02\x03\x04"
    cpu.start()
    cpu.scan()
    assert [r["RET_VAL"] for r in results] == [0, 0x8122 - 0x10000, 0, 0x8101 - 0x10000]
    assert bytes(cpu.mem.markers[10:14]) == b"\x01\x02\x03\x04"
    assert bytes(cpu.mem.markers[30:35]) == b"\x01\x02\x01\x02\x01"


def test_set_clk_and_read_clk_use_the_injected_clock(clock: VirtualClock) -> None:
    """docs/architecture.md, "The core is a function": the CPU clock is the injected clock plus an
    offset set by SET_CLK."""
    read: list[dict[str, object]] = []

    def main(ctx: CallContext) -> None:
        if not read:
            ctx.call("SET_CLK", PDT=datetime(2026, 11, 22, 12, 0))
        read.append(ctx.call("READ_CLK", CDT="DB1.DBB0"))
        read.append(ctx.call("TIME_TCK"))

    cpu = make_cpu(clock, main, DB(1, 8))  # zeroed: an FC OUT is never read in
    cpu.start()
    cpu.scan()
    clock.advance(125)  # below the 150 ms cycle-time limit
    cpu.scan()
    assert read[-2] == {"CDT": datetime(2026, 11, 22, 12, 0, 0, 125_000), "RET_VAL": 0}
    assert cpu.mem.get("DB1.DBB0") == 0x26  # DT is stored as BCD: year 26
    assert read[-1]["RET_VAL"] == 125


def test_alarm_sq_raises_on_sig_edges_into_the_cpus_message_list(clock: VirtualClock) -> None:
    rets: list[object] = []

    def main(ctx: CallContext) -> None:
        sig = ctx.mem.get("M0.0")
        out = ctx.call("ALARM_SQ", SIG=sig, ID=0xEEEE, EV_ID=7, SD="P#M2.0 WORD 1")
        rets.append(out["RET_VAL"])

    cpu = make_cpu(clock, main)
    cpu.start()
    cpu.mem.set("M0.0", True)
    cpu.mem.set("MW2", 0x1234)
    record = cpu.scan()
    cpu.scan()
    msg = message_list(cpu).get(7)
    assert msg is not None and msg.values == ("1234",) and msg.ack_required
    assert [type(a) for a in record.alarms] == [MessageEvent]
    assert rets == [0, 0x8084 - 0x10000]


def test_every_system_block_is_declared_from_its_catalogue_entry() -> None:
    assert len({b.label for b in SYSTEM_BLOCKS}) == len(SYSTEM_BLOCKS)
    for block in SYSTEM_BLOCKS:
        entry = lookup(block.label)
        assert entry.name == block.name
        declared = {v.name for v in block.interface} - (
            {"STATE"} if entry.needs_instance else set()
        )
        assert declared == {p.name for p in entry.pins} - {"RET_VAL"}
    assert {e.key for e in CATALOGUE} - {b.label for b in SYSTEM_BLOCKS} == set()
