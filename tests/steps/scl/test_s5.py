"""The S5 timer and counter functions of S7-SCL: S_PULSE, S_PEXT, S_ODT, S_ODTS,
S_OFFDT, S_CU, S_CD, S_CUD, run by the operating system's S5 cells (docs/scl.md,
"Functions"; STEP7 comprehensive guide vol. 2, ch. 13, timers and counters)."""

from __future__ import annotations

import pytest

from s7graph.engine import parse_address
from tests.steps.scl.helpers import errors, run

TIMERS = """
FUNCTION_BLOCK FB2
VAR
  CurrTime : S5TIME;
  BiVal : WORD;
  ActFlag : BOOL;
END_VAR
  CurrTime := S_ODT(T_NO := T10, S := I0.0, TV := T#1s, R := I0.1, BI := BiVal, Q := ActFlag);
  Q0.0 := ActFlag;
  MW2 := BiVal;
  CurrTime := S_ODTS(T_NO := T11, S := I0.0, TV := T#1s, R := I0.1, Q := Q0.1);
  CurrTime := S_OFFDT(T_NO := T12, S := I0.0, TV := T#1s, R := I0.1, Q := Q0.2);
  CurrTime := S_PEXT(T_NO := T13, S := I0.0, TV := T#1s, R := I0.1, Q := Q0.3);
  CurrTime := S_PULSE(T_NO := T14, S := I0.0, TV := T#1s, R := I0.1, Q := Q0.4);
END_FUNCTION_BLOCK
ORGANIZATION_BLOCK OB1
  FB2.DB2();
END_ORGANIZATION_BLOCK
"""


def q(cpu: object) -> list[bool]:
    return [cpu.mem.get(f"Q0.{k}") for k in range(5)]  # type: ignore[attr-defined]


def test_the_five_timers_from_scl() -> None:
    cpu = run(TIMERS, 1, ms=100)
    assert q(cpu) == [False, False, False, False, False]
    cpu.mem.periph_in[0] = 1  # S rises
    for _ in range(3):
        cpu.scan()
        cpu.clock.advance(100)  # type: ignore[attr-defined]
    # 300 ms in: on-delays wait, off-delay holds, both pulses run
    assert q(cpu) == [False, False, True, True, True]
    assert 0 < cpu.mem.get("MW2") <= 100  # BI: the time left in 10 ms units
    for _ in range(9):
        cpu.scan()
        cpu.clock.advance(100)  # type: ignore[attr-defined]
    # 1.2 s in: the on-delays are on, the pulses are over
    assert q(cpu) == [True, True, True, False, False]
    cpu.mem.periph_in[0] = 0  # S falls
    cpu.scan()
    assert q(cpu) == [False, True, True, False, False]  # S_ODTS keeps Q until R
    for _ in range(12):
        cpu.clock.advance(100)  # type: ignore[attr-defined]
        cpu.scan()
    assert q(cpu) == [False, True, False, False, False]  # the off-delay ran out
    cpu.mem.periph_in[0] = 2  # R
    cpu.scan()
    assert q(cpu) == [False, False, False, False, False]


def test_the_function_value_is_the_time_left_as_s5time() -> None:
    src = """
ORGANIZATION_BLOCK OB1
VAR_TEMP t : S5TIME; END_VAR
  t := S_PEXT(T_NO := T3, S := TRUE, TV := T#25S);
  DB1.S := t;
END_ORGANIZATION_BLOCK
DATA_BLOCK DB1 STRUCT S : S5TIME; END_STRUCT BEGIN END_DATA_BLOCK
"""
    cpu = run(src, 11, ms=100)
    assert cpu.mem.read_as(parse_address("DB1.DBW0"), "S5TIME") == 24000


def test_the_timer_resumes_with_the_time_left() -> None:
    """The guide's example: a pulse timer that, cut short, goes on with the time it had
    left when its switch closes again."""
    src = """
FUNCTION_BLOCK FB1
VAR
  currtime, t_remain : S5TIME;
  aa, bival : WORD;
END_VAR
  IF i0.0 = false THEN
    aa := bival;
    t_remain := currtime;
    IF bival <> 16#0 THEN
      m0.0 := 1;
    ELSE
      m0.0 := false;
    END_IF;
  END_IF;
  IF m0.0 = true THEN
    CurrTime := S_PULSE(T_NO := T14, S := i0.0, TV := T_remain, R := i0.1, BI := biVal, Q := q0.0);
  ELSE
    CurrTime := S_PULSE(T_NO := T14, S := i0.0, TV := T#20s, R := i0.1, BI := biVal, Q := q0.0);
  END_IF;
END_FUNCTION_BLOCK
ORGANIZATION_BLOCK OB1
  FB1.DB1();
END_ORGANIZATION_BLOCK
"""
    cpu = run(src, 1, ms=100)
    pi = cpu.mem.periph_in

    def seconds(n: float) -> None:
        for _ in range(round(n * 10)):
            cpu.scan()
            cpu.clock.advance(100)  # type: ignore[attr-defined]

    pi[0] = 1
    seconds(8)  # 8 s of the 20 s pulse
    assert cpu.mem.get("Q0.0") is True
    pi[0] = 0  # cut short: 12 s left
    seconds(5)
    assert cpu.mem.get("Q0.0") is False and cpu.instance_db(1)["t_remain"] == 12000
    pi[0] = 1
    seconds(11.5)
    assert cpu.mem.get("Q0.0") is True
    seconds(0.8)
    assert cpu.mem.get("Q0.0") is False  # the time left has run out


def test_the_three_counters() -> None:
    src = """
FUNCTION_BLOCK FB1
VAR
  CurrVal, binVal : WORD;
  actFlag : BOOL;
END_VAR
  CurrVal := S_CD(C_NO := C10, CD := M0.0, S := M0.1, PV := 16#100, R := FALSE,
                  CV := binVal, Q := actFlag);
  MW10 := binVal;
  MW12 := CurrVal;
  CurrVal := S_CU(C_NO := C11, CU := M0.0, S := M0.1, PV := 16#110, R := M0.2,
                  CV := binVal, Q := Q0.7);
  MW14 := binVal;
  CurrVal := S_CUD(C_NO := C12, CD := I0.0, CU := I0.1, S := I0.2 & I0.3, PV := C#120,
                   R := FALSE, CV := binVal);
  MW16 := binVal;
END_FUNCTION_BLOCK
ORGANIZATION_BLOCK OB1
  FB1.DB1();
END_ORGANIZATION_BLOCK
"""
    cpu = run(src, 1)
    mem = cpu.mem
    mem.set("M0.1", True)  # set both counters
    cpu.scan()
    mem.set("M0.1", False)
    for _ in range(3):  # three rising edges
        mem.set("M0.0", True)
        cpu.scan()
        mem.set("M0.0", False)
        cpu.scan()
    assert (mem.get("MW10"), mem.get("MW12"), mem.get("MW14")) == (97, 0x97, 113)
    assert mem.get("Q0.7") is True
    cpu.mem.periph_in[0] = 0x0C  # S of S_CUD
    cpu.scan()
    cpu.mem.periph_in[0] = 0x02  # CU
    cpu.scan()
    assert mem.get("MW16") == 121


def test_a_timer_number_from_a_variable_and_a_tv_word() -> None:
    src = """
FUNCTION_BLOCK FB3
VAR_INPUT
  MY_TIMER : ARRAY[1..4] OF STRUCT
    T_NO : INT;
    TV : WORD;
  END_STRUCT;
  mytime : TIMER;
END_VAR
VAR_TEMP I : INT; END_VAR
  FOR I := 1 TO 4 DO
    S_ODT(T_NO := MY_TIMER[I].T_NO, S := true, TV := MY_TIMER[I].TV);
  END_FOR;
  S_PEXT(T_NO := mytime, S := TRUE, TV := T#5S);
END_FUNCTION_BLOCK
ORGANIZATION_BLOCK OB1
  FB3.DB3(mytime := T20);
END_ORGANIZATION_BLOCK
"""

    def presets(cpu: object) -> None:
        db = cpu.instance_db(3)  # type: ignore[attr-defined]
        for k, row in enumerate(db["MY_TIMER"]):
            row["T_NO"] = 30 + k
            row["TV"] = 0x1000 | (k + 1) * 0x10  # 1 s, 2 s, 3 s, 4 s in 100 ms units

    cpu = run(src, 1, before=presets, ms=100)
    timers = cpu.mem.timers
    assert [timers[30 + k].preset_ms for k in range(4)] == [1000, 2000, 3000, 4000]
    assert timers[20].running


@pytest.mark.parametrize(
    ("call", "code"),
    [
        ("S_ODT(S := TRUE, TV := T#1S);", "E231"),
        ("S_ODT(T_NO := T1, X := TRUE);", "E230"),
        ("S_ODT(T_NO := 1.5, S := TRUE);", "E220"),
        ("b := S_ODT(T_NO := T1, S := TRUE, Q := b) = S5T#0MS;", "E232"),
    ],
)
def test_s5_function_diagnostics(call: str, code: str) -> None:
    src = f"FUNCTION_BLOCK FB1\nVAR b : BOOL; END_VAR\n  {call}\nEND_FUNCTION_BLOCK\n"
    assert errors(src) == [code]


WORD_TV = """
DATA_BLOCK DB1 STRUCT tv : S5TIME; left : S5TIME; END_STRUCT BEGIN END_DATA_BLOCK
FUNCTION_BLOCK FB1
VAR tv : WORD := W#16#2005; bi : WORD; END_VAR
  S_ODT(T_NO := T1, S := I0.0, TV := tv, BI := bi, Q := Q0.0);
  MW2 := bi;
  DB1.left := S_ODT(T_NO := T2, S := I0.0, TV := MW10, Q := Q0.1);
  S_PEXT(T_NO := T3, S := I0.0, TV := DB1.tv, BI := MW4, Q := Q0.2);
END_FUNCTION_BLOCK
ORGANIZATION_BLOCK OB1
  FB1.DB2();
END_ORGANIZATION_BLOCK
"""


def test_a_tv_word_counts_in_its_own_time_base_and_bi_counts_in_it() -> None:
    """``W#16#2005`` is 5 x 1 s, ``W#16#1050`` 50 x 100 ms, as STL's ``L`` then ``SD``
    start them: BI counts seconds (not 500 x 10 ms), Q comes after the whole 5 s; an S5TIME
    in a global DB's bytes is read as its word too (``W#16#2003``: 3 x 1 s)."""

    def presets(cpu: object) -> None:
        mem = cpu.mem  # type: ignore[attr-defined]
        mem.set("MW10", 0x1050)
        mem.set("DB1.DBW0", 0x2003)
        mem.periph_in[0] = 1  # S

    cpu = run(WORD_TV, 1, before=presets, ms=100)
    timers = cpu.mem.timers
    bases = [(timers[k].time_base_ms, timers[k].binary()) for k in (1, 2, 3)]
    assert bases == [(1000, 5), (100, 50), (1000, 3)]
    assert (cpu.mem.get("MW2"), cpu.mem.get("MW4")) == (5, 3)
    for _ in range(44):  # 4.5 s in
        cpu.scan()
        cpu.clock.advance(100)  # type: ignore[attr-defined]
    assert cpu.mem.get("Q0.0") is False and cpu.mem.get("MW2") == 1  # one second unit left
    assert cpu.mem.get("Q0.2") is False  # the 3 s pulse is over
    for _ in range(6):
        cpu.scan()
        cpu.clock.advance(100)  # type: ignore[attr-defined]
    assert cpu.mem.get("Q0.0") is True and cpu.mem.get("MW2") == 0


def test_the_time_left_written_to_memory_keeps_the_timers_time_base() -> None:
    """The function value into an S5TIME in a global DB is the timer's word, as ``LC T``
    reads it: 30 x 100 ms left (``W#16#1030``), not the same 3 s in the finest base."""
    cpu = run(WORD_TV, 21, before=lambda cpu: cpu.mem.set("MW10", 0x1050), ms=100)
    cpu.mem.periph_in[0] = 1
    cpu.scan()
    for _ in range(20):  # 2 s in
        cpu.clock.advance(100)  # type: ignore[attr-defined]
        cpu.scan()
    assert cpu.mem.get("DB1.DBW2") == 0x1030
    assert cpu.mem.read_as(parse_address("DB1.DBW2"), "S5TIME") == 3000


def test_a_tv_word_that_is_not_bcd_is_a_located_block_error() -> None:
    src = """
ORGANIZATION_BLOCK OB1
  S_ODT(T_NO := T1, S := TRUE, TV := MW0);
END_ORGANIZATION_BLOCK
"""
    cpu = run(src, before=lambda cpu: cpu.mem.set("MW0", 0x00FA))
    assert str(cpu.mode) == "STOP"
    assert any(
        "t.scl:3:3: TV: W#16#00FA is not valid BCD" in str(e) for e in cpu.diagnostics.since(0)
    )


def test_a_tv_word_not_bcd_is_quoted_as_given_with_its_time_base() -> None:
    """``TV := W#16#20A5``: the count A5 is no BCD; the error quotes the word given, time
    base bits and all, not the count alone (``W#16#00A5``)."""
    src = """
ORGANIZATION_BLOCK OB1
  S_ODT(T_NO := T1, S := TRUE, TV := W#16#20A5);
END_ORGANIZATION_BLOCK
"""
    cpu = run(src)
    assert str(cpu.mode) == "STOP"
    found = [str(e) for e in cpu.diagnostics.since(0) if "BCD" in str(e)]
    assert found and "t.scl:3:3: TV: W#16#20A5 is not valid BCD" in found[0]
    assert not any("W#16#00A5" in e for e in found)


INDEXED_TV = """
DATA_BLOCK DB1
STRUCT i : INT; tv : ARRAY[1..3] OF S5TIME; left : ARRAY[1..3] OF S5TIME; END_STRUCT
BEGIN
END_DATA_BLOCK
FUNCTION_BLOCK FB1
  DB1.left[DB1.i] := S_ODT(T_NO := T1, S := I0.0, TV := DB1.tv[DB1.i], Q := Q0.0);
END_FUNCTION_BLOCK
ORGANIZATION_BLOCK OB1
  FB1.DB2();
END_ORGANIZATION_BLOCK
"""


def test_an_s5time_at_an_index_read_from_memory_is_passed_and_written_as_its_word() -> None:
    """``DB1.tv[DB1.i]``, its address computed from a value in memory, is an S5TIME in a
    global DB's bytes like ``DB1.tv``: TV is its word (``W#16#2003``: 3 x 1 s, not 300 x
    10 ms), and the time left goes into ``DB1.left[DB1.i]`` as the timer's word."""

    def presets(cpu: object) -> None:
        mem = cpu.mem  # type: ignore[attr-defined]
        mem.set("DB1.DBW0", 2)  # i
        mem.set("DB1.DBW4", 0x2003)  # tv[2]
        mem.periph_in[0] = 1  # S

    cpu = run(INDEXED_TV, 1, before=presets, ms=100)
    timer = cpu.mem.timers[1]
    assert (timer.time_base_ms, timer.binary()) == (1000, 3)
    for _ in range(10):  # 1 s in
        cpu.scan()
        cpu.clock.advance(100)  # type: ignore[attr-defined]
    assert cpu.mem.get("DB1.DBW10") == 0x2002  # left[2]: 2 x 1 s, the timer's word
