"""S5 counters on C-area cells (El-Shahat's S7-300/400 course, timers and counters)."""

from __future__ import annotations

import pytest

from s7graph.engine.address import parse_address
from s7graph.engine.errors import ProgramError
from s7graph.engine.memory import Memory, S5Counter
from s7graph.sfb import s5_counters as c


def test_counters_count_rising_edges_and_saturate_at_0_and_999() -> None:
    """CU/CD count on the 0->1 transition; no wrap at 0 or 999."""
    cell = S5Counter()
    assert [c.count_up(cell, x) for x in [True, True, False, True]] == [True, True, True, True]
    assert cell.value == 2
    for _ in range(5):
        c.count_down(cell, True)
        c.count_down(cell, False)
    assert (cell.value, cell.q) == (0, False)
    cell.set_value(998)
    for _ in range(3):
        c.count_up(cell, False)
        c.count_up(cell, True)
    assert cell.value == 999


def test_s_loads_the_bcd_preset_on_a_rising_edge_and_q_is_value_above_zero() -> None:
    """``L C#26 / S C n`` loads 26; R clears; Q = value > 0."""
    mem = Memory(counters=8)
    cell = c.cell_of(mem.counters, 3)
    assert c.set_preset(cell, True, 0x0026) is True
    assert mem.read(parse_address("C3")) == 26
    assert cell.bcd() == 0x0026
    cell.set_value(5)
    c.set_preset(cell, True, 0x0026)  # held: no new load
    assert cell.value == 5
    assert c.reset(cell, True) is False
    assert cell.value == 0


def test_a_non_bcd_preset_is_a_programming_error() -> None:
    """El-Shahat's S7-300/400 course, timers and counters: loading a non-BCD preset can stop the
    PLC."""
    with pytest.raises(ProgramError, match="BCD"):
        c.set_preset(S5Counter(), True, 0x00A1)


def test_s_cud_simultaneous_edges_leave_the_value_and_r_dominates() -> None:
    cell = S5Counter()
    assert c.s_cud(cell, s=True, pv=0x0010) == c.CounterBox(True, 10, 0x0010)
    assert c.s_cud(cell, cu=True, cd=True).cv == 10
    assert c.s_cud(cell, cu=False, cd=False).cv == 10
    assert c.s_cud(cell, cu=True).cv == 11
    assert c.s_cud(cell, cu=False, cd=True, r=True) == c.CounterBox(False, 0, 0)


def test_fr_lets_a_held_condition_count_again() -> None:
    cell = S5Counter()
    c.count_up(cell, True)
    c.enable(cell, True)
    c.count_up(cell, True)
    assert cell.value == 2


def test_a_counter_number_beyond_the_area_is_a_programming_error() -> None:
    with pytest.raises(ProgramError, match="C8"):
        c.cell_of(Memory(counters=8).counters, 8)
