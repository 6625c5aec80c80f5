"""SFB0 CTU, SFB1 CTD, SFB2 CTUD (STEP7 comprehensive guide vol. 2, ch. 12)."""

from __future__ import annotations

from s7graph.sfb.iec_counters import CTD, CTU, CTUD, INT_MAX, INT_MIN, CounterOut, UpDownOut


def test_ctu_counts_rising_edges_and_q_is_cv_at_least_pv() -> None:
    """Q = (CV >= PV); a held CU counts once."""
    ctu = CTU()
    rows = [  # (CU, R, Q, CV) with PV = 2
        (False, False, False, 0),
        (True, False, False, 1),
        (True, False, False, 1),
        (False, False, False, 1),
        (True, False, True, 2),
        (False, False, True, 2),
        (True, False, True, 3),
        (True, True, False, 0),  # R resets
        (False, False, False, 0),
        (True, True, False, 0),  # R blocks counting
    ]
    for cu, r, q, cv in rows:
        assert ctu(cu, r, 2) == CounterOut(q, cv)


def test_ctu_stops_at_32767() -> None:
    """CTU counts to 32767 and no further."""
    ctu = CTU(CV=INT_MAX - 1)
    ctu(False, False, 0)
    assert ctu(True, False, 0).cv == INT_MAX
    ctu(False, False, 0)
    assert ctu(True, False, 0).cv == INT_MAX


def test_ctd_loads_pv_counts_down_to_minus_32768_and_q_is_cv_at_most_0() -> None:
    ctd = CTD()
    assert ctd(False, True, 2) == CounterOut(False, 2)
    assert ctd(True, False, 2) == CounterOut(False, 1)
    ctd(False, False, 2)
    assert ctd(True, False, 2) == CounterOut(True, 0)
    ctd.CV = INT_MIN
    ctd(False, False, 2)
    assert ctd(True, False, 2).cv == INT_MIN


def test_ctud_r_wins_over_load_and_simultaneous_edges_cancel() -> None:
    ctud = CTUD()
    assert ctud(False, False, False, True, 5) == UpDownOut(True, False, 5)
    assert ctud(False, False, True, True, 5) == UpDownOut(False, True, 0)  # R over LOAD
    assert ctud(True, False, False, False, 5) == UpDownOut(False, False, 1)
    assert ctud(False, True, False, False, 5) == UpDownOut(False, True, 0)  # CD edge
    assert ctud(True, False, False, False, 5).cv == 1  # CU rose again
    assert ctud(False, False, False, False, 5).cv == 1
    assert ctud(True, True, False, False, 5).cv == 1  # both edges at once: unchanged


def test_an_iec_counter_round_trips_through_its_state() -> None:
    ctu = CTU()
    ctu(True, False, 3)
    assert CTU.from_state(ctu.to_state()) == ctu
