"""Hostile sources end in located diagnostics or a watchdog STOP, never an internal error
(docs/scl.md, "Diagnostics" and "Run time")."""

from __future__ import annotations

import pytest

from s7graph.engine import CpuMode, EventId
from s7graph.steps.scl import check_scl, format_diagnostic
from tests.steps.scl.helpers import codes, run

N = 10_000


def fb(body: str) -> str:
    return f"FUNCTION_BLOCK FB1\nVAR i : INT; END_VAR\n{body}\nEND_FUNCTION_BLOCK\n"


@pytest.mark.parametrize(
    "body",
    [
        "IF TRUE THEN\n" * N + "i := 1;\n" + "END_IF;\n" * N,
        "WHILE FALSE DO\n" * N + "END_WHILE;\n" * N,
        "i := " + "+".join(["i"] * N) + ";",
        "i := " + "-" * N + "1;",
        "i := " + "ABS(" * N + "1" + ")" * N + ";",
        "i := " + "NOT " * N + "i;",
    ],
    ids=["if", "while", "chain", "minus", "calls", "not"],
)
def test_nesting_ten_thousand_deep_is_a_located_diagnostic(body: str) -> None:
    found = codes(fb(body))
    assert [c for c, _, _ in found] == ["E204"]
    assert found[0][1] >= 3
    if body.startswith("i := "):
        assert found[0][1:] == (3, 6)  # where the expression starts


def test_nested_structures_ten_thousand_deep_are_a_diagnostic() -> None:
    decl = "s : " + "STRUCT a : " * N + "INT;" + " END_STRUCT;" * N
    src = f"FUNCTION_BLOCK FB1\nVAR {decl} END_VAR\nEND_FUNCTION_BLOCK\n"
    assert [c for c, _, _ in codes(src)] == ["E204"]


def test_ten_thousand_parentheses_are_only_parentheses() -> None:
    assert codes(fb("i := " + "(" * N + "1" + ")" * N + ";")) == []


def test_a_hundred_thousand_digit_literal_is_a_located_diagnostic() -> None:
    found = check_scl(fb("i := " + "7" * 100_000 + ";"), "big.scl")
    assert [(d.code, d.loc.line, d.loc.col) for d in found] == [("E203", 3, 6)]
    assert "100000 digits" in format_diagnostic(found[0])
    assert len(format_diagnostic(found[0])) < 200


def test_a_huge_radix_literal_and_a_huge_typed_literal_are_diagnostics() -> None:
    assert [c for c, _, _ in codes(fb("i := 16#" + "F" * 50_000 + ";"))] == ["E203"]
    assert [c for c, _, _ in codes(fb("i := INT#" + "9" * 5_000 + ";"))] == ["E203"]


def test_a_long_string_literal_is_a_diagnostic() -> None:
    assert [c for c, _, _ in codes(fb("i := LEN('" + "x" * 300 + "');"))] == ["E203"]


ENDLESS = {
    "while": "WHILE TRUE DO END_WHILE;",
    "repeat": "REPEAT i := i + 1; UNTIL FALSE END_REPEAT;",
    "for": "FOR i := 0 TO 32767 DO END_FOR;",  # the INT wraps: the loop never ends
    "goto": "back: i := i + 1; GOTO back;",
}


@pytest.mark.parametrize("body", ENDLESS.values(), ids=ENDLESS.keys())
def test_an_endless_loop_stops_the_cpu_by_cycle_monitoring(body: str) -> None:
    src = f"""
ORGANIZATION_BLOCK OB1
VAR_TEMP i : INT; END_VAR
LABEL back; END_LABEL
  MW0 := INT_TO_WORD(WORD_TO_INT(MW0) + 1);
  IF WORD_TO_INT(MW0) > 2 THEN
    {body}
  END_IF;
END_ORGANIZATION_BLOCK
"""
    cpu = run(src, 3)
    assert cpu.mode is CpuMode.STOP
    assert cpu.mem.get("MW0") == 3
    events = [(e.event_id, e.block) for e in list(cpu.diagnostics)][-2:]
    assert events == [(EventId.CYCLE_TIME_EXCEEDED, "OB1"), (EventId.STOP_CYCLE_TIME, "OB1")]
    assert "twice the maximum cycle time (300 ms)" in list(cpu.diagnostics)[-2].message


def test_the_loop_budget_follows_the_maximum_cycle_time_and_a_long_loop_runs() -> None:
    """30,000 passes (the guide's FOR loop example) fit a 150 ms cycle; with a 10 ms
    maximum they do not."""
    src = """
ORGANIZATION_BLOCK OB1
VAR_TEMP chk, i : INT; END_VAR
  FOR i := 1 TO 30000 DO chk := chk + 1; END_FOR;
  MW0 := INT_TO_WORD(chk);
END_ORGANIZATION_BLOCK
"""
    cpu = run(src, 2)
    assert cpu.mode is CpuMode.RUN and cpu.mem.get("MW0") == 30000
    cpu = run(src, 1, cpu_options={"max_cycle_ms": 10})
    assert cpu.mode is CpuMode.STOP


def test_an_endless_loop_in_a_called_fb_names_the_fb() -> None:
    src = """
FUNCTION_BLOCK FB3
  WHILE TRUE DO END_WHILE;
END_FUNCTION_BLOCK
ORGANIZATION_BLOCK OB1
  FB3.DB3();
END_ORGANIZATION_BLOCK
"""
    cpu = run(src)
    assert cpu.mode is CpuMode.STOP
    assert list(cpu.diagnostics)[-1].block == "FB3"


def test_endless_recursion_of_fcs_is_a_stack_overflow_stop() -> None:
    src = """
FUNCTION FC1 : VOID
  FC1();
END_FUNCTION
ORGANIZATION_BLOCK OB1
  FC1();
END_ORGANIZATION_BLOCK
"""
    cpu = run(src)
    assert cpu.mode is CpuMode.STOP
    assert list(cpu.diagnostics)[-1].event_id == EventId.STACK_OVERFLOW


@pytest.mark.parametrize(
    "decl",
    [
        "a : ARRAY[1..65536] OF STRUCT b : ARRAY[1..65536] OF INT; END_STRUCT;",
        "a : ARRAY[-32768..32767, -32768..32767] OF BOOL;",
        "a : ARRAY[1..30000] OF DINT;",
        "s : STRUCT "
        + " ".join(f"f{k} : ARRAY[1..1000] OF REAL;" for k in range(20))
        + " END_STRUCT;",
    ],
)
def test_a_variable_larger_than_a_db_is_a_diagnostic(decl: str) -> None:
    src = f"FUNCTION_BLOCK FB1\nVAR {decl} END_VAR\nEND_FUNCTION_BLOCK\n"
    assert [c for c, _, _ in codes(src)] == ["E217"]
