"""CASE values may be the names of integer constants of the block, alone, in lists and in
ranges; an unknown name or a constant that is no integer is E242 at the value, and so is a
value listed twice once the names are read (docs/scl.md, "Statements")."""

from __future__ import annotations

import pytest

from s7graph.steps.scl import check_scl, format_diagnostic
from tests.steps.scl.helpers import run

HEAD = """FUNCTION_BLOCK FB1
VAR s : INT; r : DINT; END_VAR
CONST Fill := 2; Drain := 5; Big := 9; Half := 0.5; END_CONST
LABEL L1; END_LABEL
"""


def src(body: str) -> str:
    return HEAD + body + "\nEND_FUNCTION_BLOCK\n"


def test_constant_names_select_arms_alone_in_lists_and_in_ranges() -> None:
    body = """FOR s := 0 TO 12 DO
  CASE s OF
    Fill: r := r + 1;
    3..Drain: r := r + 10;
    Big, 7: r := r + 100;
    10..11, 12: r := r + 1000;
  ELSE
    r := r + 10000;
  END_CASE;
END_FOR;"""
    program = src(body) + "ORGANIZATION_BLOCK OB1 FB1.DB1(); END_ORGANIZATION_BLOCK\n"
    # 0, 1, 6, 8 → ELSE; 2 → Fill; 3..5; 7 and 9; 10, 11, 12
    assert run(program).instance_db(1).values["r"] == 4 * 10000 + 1 + 3 * 10 + 2 * 100 + 3000


def test_a_declared_label_inside_an_arm_stays_a_label() -> None:
    body = "CASE s OF 0: GOTO L1; s := 7; L1: r := 1; Fill: r := 2; END_CASE;"
    program = src(body) + "ORGANIZATION_BLOCK OB1 FB1.DB1(); END_ORGANIZATION_BLOCK\n"
    values = run(program).instance_db(1).values
    assert (values["s"], values["r"]) == (0, 1)


@pytest.mark.parametrize(
    ("body", "col", "message"),
    [
        ("CASE s OF Fill: ; Nope: ; END_CASE;", 19, "CASE value Nope is not a constant"),
        ("CASE s OF Nope, 3: ; END_CASE;", 11, "CASE value Nope is not a constant"),
        ("CASE s OF 1..Half: ; END_CASE;", 14, "Half (the REAL constant 0.5) is not an integer"),
        ("CASE s OF 2: ; Fill: ; END_CASE;", 16, "CASE value Fill (= 2) is empty or listed twice"),
        ("CASE s OF 1: ; 3..Drain, 4: ; END_CASE;", 26, "CASE value 4 is empty or listed"),
        ("CASE s OF Drain..3: ; END_CASE;", 11, "CASE value 5..3 is empty or listed twice"),
        ("s, r: s := 1;", 1, "CASE values outside the arms of a CASE"),
    ],
)
def test_a_bad_case_value_names_the_value_and_its_line(body: str, col: int, message: str) -> None:
    found = [d for d in check_scl(src(body), "t.scl") if d.is_error]
    assert [(d.code, d.loc.line, d.loc.col) for d in found] == [("E242", 5, col)]
    assert message in format_diagnostic(found[0])
