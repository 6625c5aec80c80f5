"""Diagnostic buffer read (SFC51 RDSYSST, SZL 0x00A0) and SFC52 WR_USMSG (STEP7 comprehensive guide
vol. 2, ch. 12; Siemens' Program Design for S7-300/400, ch. 10)."""

from __future__ import annotations

from datetime import datetime

from s7graph.engine.blocks import DB, ob
from s7graph.engine.clock import VirtualClock
from s7graph.engine.cpu import CallContext, Cpu
from s7graph.engine.datatypes import decode
from s7graph.engine.diagnostics import DiagnosticBuffer
from s7graph.sfb import install
from s7graph.sfb.catalogue import as_int
from s7graph.sfb.diag_read import (
    RET_DR_PARTIAL,
    RET_DR_TOO_SHORT,
    RET_EVENTN_ILLEGAL,
    RET_NO_REQUEST,
    RET_NOT_SENT,
    RET_SZL_ID_UNKNOWN,
    SzlHeader,
    rdsysst,
    wr_usmsg,
)


def buffer_with(n: int) -> DiagnosticBuffer:
    buf = DiagnosticBuffer(capacity=5)
    for i in range(n):
        buf.record(i, 0x4300 + i, message=f"entry {i}")
    return buf


def test_szl_00a0_lists_the_diagnostic_buffer_newest_first() -> None:
    result = rdsysst(buffer_with(3), 0x00A0)
    assert result.ret_val == 0 and result.busy is False
    assert result.header == SzlHeader(20, 3)
    assert [e.t_ns for e in result.records] == [2, 1, 0]


def test_szl_01a0_lists_the_newest_index_entries_of_the_ring() -> None:
    result = rdsysst(buffer_with(8), 0x01A0, index=2)
    assert [e.t_ns for e in result.records] == [7, 6]


def test_a_short_destination_gets_what_fits_and_an_unknown_szl_id_fails() -> None:
    short = rdsysst(buffer_with(4), 0x00A0, capacity=2)
    assert short.ret_val == RET_DR_PARTIAL > 0 and short.header.n_dr == 2
    none_fit = rdsysst(buffer_with(4), 0x00A0, capacity=0)
    assert none_fit.ret_val == RET_DR_TOO_SHORT < 0 and none_fit.records == ()
    assert rdsysst(buffer_with(1), 0x0424).ret_val == RET_SZL_ID_UNKNOWN < 0


def test_wr_usmsg_adds_a_user_entry_with_the_clock_time_even_without_a_display() -> None:
    """WR_USMSG(SEND := FALSE, EVENTN := W#16#A101) adds a time-stamped entry."""
    buf = DiagnosticBuffer()
    assert wr_usmsg(buf, 0xA101, 123_000_000) == 0
    (entry,) = buf.latest()
    assert (entry.t_ns, entry.event_id) == (123_000_000, 0xA101)
    assert "incoming" in entry.message
    assert wr_usmsg(buf, 0x4302, 0) == RET_EVENTN_ILLEGAL


def test_wr_usmsg_with_send_writes_the_entry_and_warns_that_no_display_is_registered() -> None:
    buf = DiagnosticBuffer()
    assert wr_usmsg(buf, 0xA002, 5, send=True) == RET_NOT_SENT > 0
    assert [e.event_id for e in buf.latest()] == [0xA002]


# --- End to end through a Cpu -----------------------------------------------------------------

HEADER = "P#DB1.DBX0.0 BYTE 4"


def cpu_with(clock: VirtualClock, main: object, db_bytes: int = 64) -> Cpu:
    cpu = Cpu(clock)
    install(cpu)
    cpu.load(ob(1)(main), DB(1, size=db_bytes))  # type: ignore[arg-type]
    return cpu


def record(cpu: Cpu, n: int) -> bytes:
    """The ``n``-th 20-byte record (0-based) delivered to DB1 after the 4-byte header."""
    start = 4 + 20 * n
    return bytes(cpu.mem.dbs[1].data[start : start + 20])


def test_a_program_writes_a_user_message_and_reads_it_back_newest_first(
    clock: VirtualClock,
) -> None:
    """End to end: WR_USMSG(SEND := FALSE, EVENTN := W#16#A101) then RDSYSST
    W#16#01A0 INDEX 2 gives the user entry as record 1 with the clock's time stamp."""
    outs: list[dict[str, object]] = []

    def main(ctx: CallContext) -> None:
        if ctx.cycle == 1:
            ctx.call("SET_CLK", PDT=datetime(2026, 3, 14, 15, 9, 26))
            outs.append(ctx.call("SFC52", SEND=False, EVENTN=0xA101, INFO1="", INFO2=""))
            outs.append(
                ctx.call(
                    "SFC51",
                    REQ=True,
                    SZL_ID=0x01A0,
                    INDEX=2,
                    BUSY="M0.0",
                    SZL_HEADER=HEADER,
                    DR="P#DB1.DBX4.0 BYTE 40",
                )
            )

    cpu = cpu_with(clock, main)
    cpu.start()
    clock.advance(250)
    cpu.scan()
    assert outs[0] == {"RET_VAL": 0}
    assert outs[1] == {"RET_VAL": 0, "BUSY": False}
    user = cpu.diagnostics.latest()[0]
    assert (user.event_id, user.block) == (0xA101, "SFC52") and "incoming" in user.message
    db = cpu.mem.dbs[1].data
    assert bytes(db[0:4]) == bytes([0, 20, 0, 2])  # LENGTHDR = 20, N_DR = 2
    newest = record(cpu, 0)
    assert newest[0:2] == bytes([0xA1, 0x01])
    assert decode("DATE_AND_TIME", newest[12:20]) == datetime(2026, 3, 14, 15, 9, 26)
    assert record(cpu, 1)[0:2] == bytes([0x43, 0x02])  # STARTUP -> RUN before it


def test_rdsysst_in_a_program_follows_the_ret_val_conventions(clock: VirtualClock) -> None:
    """REQ = FALSE: W#16#7000; a DR for fewer records: warning W#16#0081 with what fits;
    no room for one record: W#16#8081; unknown SZL_ID: W#16#8082; bad ANY: 8x01."""
    rets: list[object] = []

    def main(ctx: CallContext) -> None:
        def read(req: bool, szl_id: int, dr: str) -> None:
            out = ctx.call(
                "RDSYSST", REQ=req, SZL_ID=szl_id, INDEX=0, BUSY="M0.0", SZL_HEADER=HEADER, DR=dr
            )
            rets.append(out["RET_VAL"])

        if ctx.cycle == 1:
            ctx.call("WR_USMSG", SEND=False, EVENTN=0xA001, INFO1="", INFO2="")
            read(False, 0x00A0, "P#DB1.DBX4.0 BYTE 20")
            read(True, 0x00A0, "P#DB1.DBX4.0 BYTE 20")
            read(True, 0x00A0, "P#DB1.DBX4.0 BYTE 19")
            read(True, 0x0424, "P#DB1.DBX4.0 BYTE 20")
            read(True, 0x00A0, "DB1.DBX4.0")

    cpu = cpu_with(clock, main)
    cpu.start()
    cpu.scan()
    assert rets == [
        RET_NO_REQUEST,
        RET_DR_PARTIAL,
        RET_DR_TOO_SHORT,
        RET_SZL_ID_UNKNOWN,
        as_int(0x8701),  # DR is parameter 7
    ]
    assert bytes(cpu.mem.dbs[1].data[0:6]) == bytes([0, 20, 0, 1, 0xA0, 0x01])


def test_wr_usmsg_in_a_program_keeps_info_and_rejects_a_system_event_id(
    clock: VirtualClock,
) -> None:
    rets: list[object] = []

    def main(ctx: CallContext) -> None:
        if ctx.cycle == 1:
            ctx.mem.set("MW10", 0x1234)
            for eventn, send in ((0xA102, True), (0x4302, False)):
                out = ctx.call(
                    "WR_USMSG", SEND=send, EVENTN=eventn, INFO1="P#M10.0 WORD 1", INFO2=""
                )
                rets.append(out["RET_VAL"])

    cpu = cpu_with(clock, main)
    cpu.start()
    clock.advance(40)
    cpu.scan()
    assert rets == [RET_NOT_SENT, RET_EVENTN_ILLEGAL]
    user = cpu.diagnostics.latest()[0]
    assert user.event_id == 0xA102 and "INFO1=16#1234" in user.message
    assert user.t_ns == clock.now_ns()
