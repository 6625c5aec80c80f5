"""Diagnostic buffer read (SFC51 RDSYSST, SZL 0x00A0) and SFC52 WR_USMSG (seeds §6.6, §7.2)."""

from __future__ import annotations

from engine.diagnostics import DiagnosticBuffer
from sfb.diag_read import (
    RET_DR_TOO_SHORT,
    RET_EVENTN_ILLEGAL,
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
    assert short.ret_val == RET_DR_TOO_SHORT and short.header.n_dr == 2
    assert rdsysst(buffer_with(1), 0x0424).ret_val == RET_SZL_ID_UNKNOWN < 0


def test_wr_usmsg_adds_a_user_entry_with_the_clock_time_even_without_a_display() -> None:
    """Behaviour 53: WR_USMSG(SEND := FALSE, EVENTN := W#16#A101) adds a time-stamped entry."""
    buf = DiagnosticBuffer()
    assert wr_usmsg(buf, 0xA101, 123_000_000, send=True) == 0
    (entry,) = buf.latest()
    assert (entry.t_ns, entry.event_id) == (123_000_000, 0xA101)
    assert "incoming" in entry.message
    assert wr_usmsg(buf, 0x4302, 0) == RET_EVENTN_ILLEGAL
