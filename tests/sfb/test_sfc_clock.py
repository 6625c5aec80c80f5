"""SFC0 SET_CLK, SFC1 READ_CLK, SFC64 TIME_TCK on the injected clock (docs/architecture.md, "The
core is a function", STEP7 comprehensive guide vol. 2, ch. 12)."""

from __future__ import annotations

from datetime import datetime

from s7graph.sfb.sfc_clock import (
    RET_DT_RANGE,
    RealTimeClock,
    read_clk,
    set_clk,
    tick_diff,
    time_tck,
)

MS = 1_000_000


def test_read_clk_is_the_epoch_plus_injected_time_until_set_clk_moves_it() -> None:
    rtc = RealTimeClock()
    assert read_clk(rtc, 1500 * MS) == (0, datetime(1990, 1, 1, 0, 0, 1, 500_000))
    assert set_clk(rtc, datetime(2026, 11, 22, 8, 30), 2000 * MS) == 0
    assert rtc.read(2000 * MS) == datetime(2026, 11, 22, 8, 30)
    assert rtc.read(62_000 * MS + 999_999) == datetime(2026, 11, 22, 8, 31)  # ms resolution


def test_set_clk_outside_dt_range_is_refused_with_a_negative_ret_val() -> None:
    """RET_VAL < 0 on error; the clock is unchanged."""
    rtc = RealTimeClock()
    assert set_clk(rtc, datetime(2090, 1, 1), 0) == RET_DT_RANGE < 0
    assert rtc.read(0) == datetime(1990, 1, 1)


def test_the_rtc_round_trips_through_its_snapshot() -> None:
    rtc = RealTimeClock()
    set_clk(rtc, datetime(2026, 1, 2, 3, 4, 5), 7 * MS)
    copy = RealTimeClock()
    copy.restore(rtc.snapshot())
    assert copy.read(99 * MS) == rtc.read(99 * MS)


def test_time_tck_counts_ms_and_wraps_to_zero_after_2_pow_31_minus_1() -> None:
    assert time_tck(1234 * MS + 999_999) == 1234
    assert time_tck((2**31 - 1) * MS) == 2**31 - 1
    assert time_tck(2**31 * MS) == 0
    assert tick_diff(5, 2**31 - 10) == 15  # the book's overflow compensation
