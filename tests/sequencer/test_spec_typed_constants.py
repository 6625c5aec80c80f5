"""A constant may carry its type as S7-SCL writes it: ``INT#16#7FFF``, ``DINT#16#3FFF_FFFF``,
``BYTE#16#10``, ``WORD#8#177777``, ``DWORD#16#FFFF_FFFF``, ``REAL#1.5`` (in any case) —
the only way to write an INT or a DINT in hexadecimal, since a bare ``16#7F`` is a WORD
(IEC 61131-3, section 2.2.1: typed literals; docs/chart-format.md).
A value outside its type is an error at the constant."""

from __future__ import annotations

from pathlib import Path

import pytest

from s7graph.sequencer.text.parse import ChartSyntaxError, parse_chart
from tests.sequencer.helpers import seq, sim_trace, source

STEPS = seq("""
  INITIAL_STEP S1 "a": END_STEP
  STEP S2 "b": S1 N i := i - INT#16#10; S1 N r := r * REAL#2; END_STEP
  TRANSITION T1 FROM S1 TO S2 := i > int#16#7ff0 AND d = DINT#16#3FFF_FFFF;
""")
VARS = (
    "VAR i : INT := INT#16#7FFF; d : DINT := DINT#16#3FFF_FFFF; b : BYTE := BYTE#16#10;"
    " w : WORD := WORD#8#177777; dw : DWORD := dword#16#FFFF_FFFF; r : REAL := REAL#1.5;"
    " n : INT := INT#-32768; END_VAR"
)


def test_typed_constants_initialize_compare_and_compute_in_their_type(tmp_path: Path) -> None:
    rc, lines = sim_trace(
        tmp_path, source(STEPS, header=VARS), [], cycles=2, watch="i,d,b,w,dw,r,n"
    )
    assert rc == 0
    assert [line["active"] for line in lines] == [["S2"], ["S2"]]  # T1 held at once
    assert lines[1]["values"] == {
        "i": 0x7FFF - 0x10,
        "d": 0x3FFF_FFFF,
        "b": 0x10,
        "w": 0xFFFF,
        "dw": 0xFFFF_FFFF,
        "r": 3.0,
        "n": -32768,
    }


def test_a_typed_constant_outside_its_type_is_an_error_at_the_constant() -> None:
    text = source(STEPS, header=VARS.replace("INT#16#7FFF", "INT#16#8000"))
    with pytest.raises(ChartSyntaxError) as refused:
        parse_chart(text, "c.s7g")
    (error,) = refused.value.diagnostics
    assert error.code == "E003"
    assert "INT#16#8000" in error.message and "outside INT" in error.message
