"""SFB3 TP, SFB4 TON, SFB5 TOF against their timing diagrams (STEP7 comprehensive guide vol. 2, ch.
12).

Each table row is ``(t_ms, IN, expected Q, expected ET)``; the timer is called once per row
with ``now_ns = t_ms * 1e6``.
"""

from __future__ import annotations

import pytest

from s7graph.sfb.iec_timers import TIME_MAX_MS, TOF, TON, TP, TimerOut

MS = 1_000_000
Row = tuple[int, bool, bool, int]


def drive(timer: TP | TON | TOF, pt: int, rows: list[Row]) -> None:
    for t, in_, q, et in rows:
        assert timer(in_, pt, t * MS) == TimerOut(q, et), f"at t={t} ms IN={in_}"


def test_ton_sets_q_after_in_was_true_for_pt_and_in_false_resets_q_and_et() -> None:
    """TON, PT = T#100MS."""
    drive(
        TON(),
        100,
        [
            (0, False, False, 0),
            (10, True, False, 0),
            (60, True, False, 50),
            (109, True, False, 99),
            (110, True, True, 100),
            (500, True, True, 100),
            (501, False, False, 0),
            (510, True, False, 0),
            (550, False, False, 0),  # IN fell before PT: no Q
            (700, False, False, 0),
        ],
    )


def test_tp_gives_a_pulse_of_pt_that_is_not_retriggerable() -> None:
    """TP, PT = T#100MS; IN falling or rising during the pulse changes nothing."""
    drive(
        TP(),
        100,
        [
            (0, True, True, 0),
            (30, False, True, 30),
            (40, True, True, 40),  # rising edge during the pulse: no retrigger
            (99, True, True, 99),
            (100, True, False, 100),  # pulse over, ET holds PT while IN = 1
            (150, True, False, 100),
            (151, False, False, 0),  # IN = 0 after the pulse: ET = 0
            (200, True, True, 0),  # new rising edge: new pulse
            (250, False, True, 50),
            (300, False, False, 0),  # pulse ends with IN = 0: ET back to 0
        ],
    )


def test_tof_keeps_q_for_pt_after_in_falls_and_a_rising_in_resets_et() -> None:
    """TOF, PT = T#100MS."""
    drive(
        TOF(),
        100,
        [
            (0, False, False, 0),
            (10, True, True, 0),
            (50, False, True, 0),
            (100, False, True, 50),
            (120, True, True, 0),  # rising IN during the delay: ET = 0, Q stays 1
            (130, False, True, 0),
            (229, False, True, 99),
            (230, False, False, 100),
            (400, False, False, 100),
        ],
    )


def test_time_advances_only_when_the_instance_is_called() -> None:
    """ET/Q are computed at call time; skipping calls just jumps ET."""
    ton = TON()
    ton(True, 1000, 0)
    assert (ton.Q, ton.ET) == (False, 0)  # nothing changed between calls
    assert ton(True, 1000, 5000 * MS) == TimerOut(True, 1000)


def test_iec_timers_count_in_milliseconds_up_to_t_24d20h31m23s647ms() -> None:
    """1 ms resolution and the TIME maximum as PT."""
    assert TIME_MAX_MS == 24 * 86_400_000 + 20 * 3_600_000 + 31 * 60_000 + 23_000 + 647
    ton = TON()
    ton(True, TIME_MAX_MS, 0)
    assert ton(True, TIME_MAX_MS, (TIME_MAX_MS - 1) * MS) == TimerOut(False, TIME_MAX_MS - 1)
    assert ton(True, TIME_MAX_MS, TIME_MAX_MS * MS) == TimerOut(True, TIME_MAX_MS)
    ton2 = TON()
    ton2(True, 5, 0)
    assert ton2(True, 5, 4 * MS + 999_999).et == 4  # sub-ms time does not count


def test_tp_with_q_fed_back_to_in_toggles_every_pt() -> None:
    """Seed example (STEP7 comprehensive guide vol. 2, ch. 12): a TP whose Q is fed back (negated)
    to IN pulses."""
    tp = TP()
    seen = []
    q = False
    for t in range(0, 6):
        q = tp(not q, 1, t * MS).q
        seen.append(q)
    assert seen == [True, False, True, False, True, False]


@pytest.mark.parametrize("cls", [TP, TON, TOF])
def test_an_iec_timer_instance_round_trips_through_its_state(cls: type[TON]) -> None:
    timer = cls()
    timer(True, 100, 0)
    timer(False, 100, 20 * MS)
    copy = cls.from_state(timer.to_state())
    assert copy == timer
    if not timer.running:  # a running one resumes from its ET (the next test)
        assert copy(True, 100, 300 * MS) == timer(True, 100, 300 * MS)


@pytest.mark.parametrize("kind", [TON, TP, TOF])
def test_a_running_timer_restored_on_another_clock_resumes_its_elapsed_time(
    kind: type[TP] | type[TON] | type[TOF],
) -> None:
    """A hot restart in a new process: the saved start time is on the old process's clock
    (here 1000 s ahead of the new one); the time resumes from ET, as persisted."""
    timer = kind()
    if kind is TOF:
        drive(timer, 5000, [(1_000_000, True, True, 0), (1_000_000, False, True, 0)])
    else:
        drive(timer, 5000, [(1_000_000, True, kind is TP, 0)])
    timer(kind is not TOF, 5000, (1_000_000 + 2000) * MS)
    assert timer.ET == 2000
    again = kind.from_state(timer.to_state())
    assert "resume" not in timer.to_state()
    on = kind is not TOF
    assert again(on, 5000, 10 * MS).et == 2000  # not 0 (a clock behind), not PT (ahead)
    assert again(on, 5000, 1010 * MS).et == 3000
    assert again(on, 5000, 3010 * MS).et == 5000
