"""S5 timers SP SE SD SS SF on T-area cells (El-Shahat's S7-300/400 course, timers and counters).

Rows are ``(t_ms, S, R, expected Q)``; every row is one timer instruction at ``t_ms``.
"""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from s7graph.engine.address import parse_address
from s7graph.engine.errors import ProgramError
from s7graph.engine.memory import Memory, S5Timer
from s7graph.sfb import s5_timers as s5
from s7graph.sfb.s5_timers import TimerFunction

MS = 1_000_000
Row = tuple[int, bool, bool, bool]


def drive(fn: str, tv_ms: int, rows: list[Row], cell: S5Timer | None = None) -> S5Timer:
    cell = cell if cell is not None else S5Timer()
    for t, s, r, q in rows:
        assert s5.run(cell, fn, s, tv_ms, t * MS, r=r) is q, f"{fn} at t={t} ms S={s} R={r}"
    return cell


def test_on_delay_sets_q_7_s_after_the_rising_edge_and_s_false_resets_it() -> None:
    """SD (German SE, S_ODT) with S5T#7S, the mixing FB1 feedback supervision."""
    drive(
        "SD",
        7000,
        [
            (0, True, False, False),
            (6990, True, False, False),
            (7000, True, False, True),
            (9000, True, False, True),
            (9001, False, False, False),  # S -> 0: Q = 0
            (10000, True, False, False),
            (15000, False, False, False),  # S fell before 7 s: never set
            (30000, False, False, False),
        ],
    )


def test_extended_pulse_is_retriggered_by_a_new_rising_edge() -> None:
    """SE (German SV, S_PEXT) keeps Q for TV even when S falls; retriggers."""
    drive(
        "S_PEXT",
        100,
        [
            (0, True, False, True),
            (20, False, False, True),  # S fell: pulse continues
            (60, True, False, True),  # new edge: restart with TV from 60
            (150, False, False, True),  # the first pulse would have ended at 100
            (159, False, False, True),
            (160, False, False, False),
            (300, False, False, False),
        ],
    )


def test_pulse_ends_early_when_s_goes_false() -> None:
    """SP (German SI, S_PULSE) — Q only while S = 1 and the time runs."""
    cell = drive(
        "SP",
        100,
        [
            (0, True, False, True),
            (50, True, False, True),
            (60, False, False, False),  # ends early
            (70, True, False, True),  # new pulse
            (170, True, False, False),  # expired although S = 1
            (200, True, False, False),
        ],
    )
    assert cell.binary() == 0


def test_retentive_on_delay_stays_set_until_r() -> None:
    """SS (S_ODTS) runs on after S falls; Q = 1 after TV until R."""
    drive(
        "SS",
        100,
        [
            (0, True, False, False),
            (10, False, False, False),  # keeps running
            (100, False, False, True),
            (500, False, False, True),
            (510, True, False, True),  # an edge after expiry changes nothing
            (520, False, True, False),  # R
            (530, False, False, False),
            (540, True, False, False),  # start again
            (580, False, False, False),
            (590, True, False, False),  # rising while running: restart at 590
            (689, True, False, False),
            (690, True, False, True),
        ],
    )


def test_off_delay_starts_on_the_falling_edge() -> None:
    """SF (German SA, S_OFFDT): Q = 1 with S, drops TV after S falls."""
    drive(
        "SF",
        100,
        [
            (0, False, False, False),
            (10, True, False, True),
            (500, True, False, True),  # held: no timing while S = 1
            (510, False, False, True),  # falling edge starts
            (560, True, False, True),  # S rises while running: timer stops, Q stays 1
            (570, False, False, True),  # falls again: restart from 570
            (669, False, False, True),
            (670, False, False, False),
        ],
    )


@pytest.mark.parametrize("fn", list(TimerFunction))
def test_r_clears_value_and_q_for_every_function(fn: TimerFunction) -> None:
    """El-Shahat's S7-300/400 course, timers and counters: R = 1 sets the time value to 0 and Q to 0
    for all five functions."""
    cell = S5Timer()
    s5.run(cell, fn, True, 1000, 0)
    s5.run(cell, fn, fn is not TimerFunction.SF, 1000, 10 * MS)
    assert s5.run(cell, fn, False, 1000, 20 * MS, r=True) is False
    assert cell.binary() == 0


def test_l_t_reads_the_count_binary_and_lc_t_reads_bcd_with_time_base() -> None:
    """S5T#1M20S = W#16#1800 (800 x 100 ms); L T strips the base."""
    cell = S5Timer()
    s5.run(cell, "SE", True, 80_000, 0)
    assert cell.bcd() == 0x1800
    assert cell.binary() == 800
    s5.tick(cell, 12_345 * MS)
    assert cell.binary() == 800 - 123
    assert cell.bcd() == 0x1677
    assert cell.value_ms == 67_700


def test_s5_timers_tick_at_their_time_base_so_accuracy_is_minus_one_base() -> None:
    """Started mid-base, an S5T#1S timer (100 x 10 ms) expires after 990..1000 ms."""
    cell = S5Timer()
    s5.run(cell, "SD", True, 1000, 7 * MS)  # 7 ms into the first 10 ms base
    s5.tick(cell, 996 * MS)
    assert not cell.q
    s5.tick(cell, 1000 * MS)  # 993 ms after the start: the 100th boundary passed
    assert cell.q
    big = S5Timer()
    s5.run(big, "SD", True, 20_000, 0)  # S5T#20S = 200 x 100 ms
    s5.tick(big, 150 * MS)
    assert big.binary() == 199  # value moves in whole time-base steps


def test_timers_are_frozen_in_hold_by_shifting_their_start() -> None:
    """Timer update stops during HOLD while the clock runs."""
    mem = Memory(timers=4)
    cell = s5.cell_of(mem.timers, 2)
    s5.run(cell, "SD", True, 100, 0)
    s5.tick_all(mem.timers, 50 * MS)
    s5.shift(mem.timers, 1000 * MS)  # 1 s in HOLD
    s5.tick_all(mem.timers, 1050 * MS)
    assert not cell.q and cell.binary() == 5
    s5.tick_all(mem.timers, 1100 * MS)
    assert cell.q
    assert mem.read(parse_address("T2")) == 0  # L T2 after expiry


def test_a_timer_number_beyond_the_area_is_a_programming_error() -> None:
    with pytest.raises(ProgramError, match="T9"):
        s5.cell_of(Memory(timers=4).timers, 9)


def test_the_s5time_literals_of_the_seeds_encode_with_the_smallest_base() -> None:
    """El-Shahat's S7-300/400 course, timers and counters: S5T#2S = 16#0200, S5T#1M20S = 16#1800,
    S5T#2M = 16#2120, max 16#3999."""
    assert s5.s5time_encode(2000) == 0x0200
    assert s5.s5time_encode(80_000) == 0x1800
    assert s5.s5time_encode(120_000) == 0x2120
    assert s5.s5time_encode(9_990_000) == 0x3999
    assert s5.s5time_split(0xC200) == (200, 10)  # bits 14-15 ignored


@given(st.integers(0, 3), st.integers(0, 999))
def test_s5time_decode_then_encode_gives_the_finest_equivalent_word(base: int, count: int) -> None:
    """Round trip: decode(encode(decode(w))) == decode(w); encode picks the finest base."""
    word = (base << 12) | s5.to_bcd(count)
    ms = s5.s5time_decode(word)
    again = s5.s5time_encode(ms)
    assert s5.s5time_decode(again) == ms
    assert (again >> 12) <= base


def test_sd_timer_started_once_expires_after_the_right_number_of_scans_without_more_calls() -> None:
    """The OS ticks the T area once per scan on the process time.

    An SD timer with S5T#50MS started in the first scan (no instruction after that) sets Q
    in the scan at 50 ms; HOLD freezes it, STARTUP does not."""
    from s7graph.engine.blocks import ob
    from s7graph.engine.clock import VirtualClock
    from s7graph.engine.cpu import CallContext, Cpu

    clock = VirtualClock()
    started: list[int] = []

    @ob(1)
    def main(ctx: CallContext) -> None:
        if not started:
            s5.run(ctx.mem.timers[3], "SD", True, 50, ctx.now_ns)
            started.append(ctx.cycle)

    cpu = Cpu(clock)  # no sfb.install: importing sfb registers the tick
    cpu.load(main)
    cpu.start()
    cell = cpu.mem.timers[3]
    cpu.scan()
    q_at: list[int] = []
    for scan in range(1, 8):
        clock.advance(10)
        if scan == 2:
            cpu.hold()
            clock.advance(1000)  # frozen: HOLD time does not count
            cpu.resume()
        cpu.scan()
        if cell.q:
            q_at.append(scan)
    assert started == [1]
    assert q_at[0] == 5 and cell.value_ms == 0 and not cell.running


def test_a_running_timer_restored_on_another_clock_keeps_its_time_left() -> None:
    """The hot memory image of a new process: T3 had 7 s left of 10 s on the old clock;
    it has 7 s left on the new one, whatever the two clocks' origins."""
    old = Memory()
    cell = old.timers[3]
    s5.run(cell, "SE", True, 10_000, 10**15)
    s5.tick(cell, 10**15 + 3000 * MS)
    assert cell.value_ms == 7000
    new = Memory()
    new.restore_hot(old.hot_snapshot())
    s5.tick(new.timers[3], 5 * MS)
    assert new.timers[3].value_ms == 7000 and new.timers[3].running
    s5.tick(new.timers[3], 7005 * MS)
    assert new.timers[3].value_ms == 0 and not new.timers[3].running


def test_a_timer_number_outside_the_cells_is_a_programming_error_saying_which_way() -> None:
    timers = [S5Timer() for _ in range(4)]
    with pytest.raises(ProgramError, match=r"T4: timer number too high \(the CPU has 4\)"):
        s5.cell_of(timers, 4)
    with pytest.raises(ProgramError, match=r"T-1: timer number negative"):
        s5.cell_of(timers, -1)


def test_a_pulse_stopped_by_s_falling_keeps_its_time_left() -> None:
    """STEP 7 Statement List manual, SP: "the time is stopped" when the RLO falls before it
    elapsed — Q = 0, and ``L T n`` reads the time left until R or a new start."""
    cell = drive("SP", 1000, [(0, True, False, True), (300, False, False, False)])
    assert not cell.running and cell.binary() == 70
    s5.tick(cell, 900 * MS)
    assert cell.binary() == 70


def test_an_on_delay_stopped_by_s_falling_keeps_its_time_left_and_q_0() -> None:
    """STEP 7 Statement List manual, SD: the time is stopped (not reset) when the RLO falls
    before it elapsed; only R clears the value."""
    cell = drive("SD", 1000, [(0, True, False, False), (400, False, False, False)])
    assert not cell.running and cell.binary() == 60
    s5.tick(cell, 2000 * MS)
    assert not cell.q and cell.binary() == 60
    assert s5.run(cell, "SD", False, 1000, 2010 * MS, r=True) is False
    assert cell.binary() == 0


def test_a_reset_timer_whose_s_stays_1_starts_again_only_on_a_new_rising_edge() -> None:
    """R acts as a level and dominates; the start needs a rising edge of S, so a timer reset
    while S holds 1 stays reset until S falls and rises again."""
    drive(
        "SD",
        100,
        [
            (0, True, False, False),
            (50, True, True, False),  # reset while running
            (60, True, False, False),  # S held: no edge, no start
            (500, True, False, False),
            (510, False, False, False),
            (520, True, False, False),  # a new edge starts it
            (619, True, False, False),
            (620, True, False, True),
        ],
    )


def test_a_rising_fr_restarts_a_timer_whose_s_is_held() -> None:
    """FR (enable): a rising edge of its RLO while S = 1 starts the timer again without an
    edge at S (STEP 7 Statement List manual, FR)."""
    cell = S5Timer()
    s5.run(cell, "SE", True, 100, 0)
    assert s5.run(cell, "SE", True, 100, 100 * MS) is False  # elapsed, S still 1
    assert s5.run(cell, "SE", True, 100, 150 * MS, fr=True) is True  # FR rises: restart
    assert cell.binary() == 10
    assert s5.run(cell, "SE", True, 100, 160 * MS, fr=True) is True  # FR held: no new start
    assert s5.run(cell, "SE", True, 100, 250 * MS, fr=True) is False


def test_a_preset_between_two_counts_of_its_time_base_is_cut_to_the_lower_count() -> None:
    """S5T#12S15MS needs the 100 ms base (1201 units of 10 ms do not fit in three digits):
    120 × 100 ms, the 15 ms dropped; the timer then counts and reads in units of 100 ms."""
    assert s5.s5time_encode(12_015) == 0x1120
    cell = S5Timer()
    s5.run(cell, "SE", True, 12_015, 0)
    assert (cell.preset_ms, cell.time_base_ms, cell.binary()) == (12_000, 100, 120)


def test_a_timer_started_with_an_s5time_word_counts_in_the_words_time_base() -> None:
    """``L W#16#1001`` then a start: 1 × 100 ms, not 10 × 10 ms — the word's time base is
    the timer's (its accuracy and the unit of ``L T n``)."""
    cell = S5Timer()
    assert s5.start(cell, "SE", 0x1001, 0) is True
    assert (cell.preset_ms, cell.time_base_ms, cell.binary()) == (100, 100, 1)
    s5.tick(cell, 99 * MS)
    assert cell.q
    s5.tick(cell, 100 * MS)
    assert not cell.q


def test_an_off_delay_started_for_the_next_update_holds_q_and_counts_from_that_update() -> None:
    """The TF row's off delay: Q = 1 at once, the time counted from the next OS update."""
    cell = S5Timer()
    s5.start_off_delay_at_next_update(cell, 0x0010, 5 * MS)  # 10 × 10 ms
    assert cell.q and cell.binary() == 10
    s5.tick(cell, 30 * MS)  # the next scan: the delay starts here
    assert cell.q and cell.binary() == 10
    s5.tick(cell, 129 * MS)
    assert cell.q
    s5.tick(cell, 130 * MS)
    assert not cell.q and cell.binary() == 0


def test_an_off_delay_of_zero_time_started_for_the_next_update_drops_q_there() -> None:
    cell = S5Timer()
    s5.start_off_delay_at_next_update(cell, 0x0000, 5 * MS)
    assert cell.q
    s5.tick(cell, 10 * MS)
    assert not cell.q and not cell.running
