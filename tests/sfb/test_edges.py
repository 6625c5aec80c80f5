"""FP / FN edge detection with an edge-memory bit (El-Shahat's S7-300/400 course, timers and
counters)."""

from __future__ import annotations

from s7graph.engine.address import parse_address
from s7graph.engine.memory import Memory
from s7graph.sfb.edges import F_TRIG, R_TRIG, Edge, fn, fn_at, fp, fp_at


def test_fp_and_fn_follow_the_edge_memory_algorithm() -> None:
    assert fp(True, False) == Edge(True, True)
    assert fp(True, True) == Edge(False, True)
    assert fp(False, True) == Edge(False, False)
    assert fn(False, True) == Edge(True, False)
    assert fn(False, False) == Edge(False, False)
    assert fn(True, False) == Edge(False, True)


def test_fp_on_a_stat_bit_gives_exactly_one_true_per_rising_edge_per_instance() -> None:
    """Two instances (mixing FB1 start counter) each see one pulse per edge."""
    a, b = R_TRIG(), R_TRIG()
    start = [False, True, True, True, False, True, True]
    pulses_a = [a(s) for s in start]
    pulses_b = [b(s) for s in start[2:]]  # b starts later: its first TRUE is an edge for b
    assert pulses_a == [False, True, False, False, False, True, False]
    assert pulses_b == [True, False, False, True, False]


def test_f_trig_fires_once_per_falling_edge() -> None:
    f = F_TRIG()
    assert [f(x) for x in [True, False, False, True, False]] == [False, True, False, False, True]


def test_fp_with_the_edge_memory_in_a_marker_bit() -> None:
    """``FP M10.0``: the previous RLO is stored in M10.0."""
    mem = Memory()
    m = parse_address("M10.0")
    assert [fp_at(mem, m, x) for x in [True, True, False, True]] == [True, False, False, True]
    assert mem.read(m) is True
    assert [fn_at(mem, m, x) for x in [False, False]] == [True, False]
