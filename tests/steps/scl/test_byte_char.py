"""``BYTE#'a'`` and ``B#'a'``: a character's code as a BYTE constant, with the `$`-escapes
of strings; more or fewer than one character, or a code beyond 255, is E203 at the
literal (docs/scl.md, "Literals and constants")."""

from __future__ import annotations

import pytest

from s7graph.steps.scl import check_scl, format_diagnostic
from tests.steps.scl.helpers import run


def test_a_character_is_a_byte_in_expressions_initial_values_and_comparisons() -> None:
    src = """FUNCTION_BLOCK FB1
VAR b, c, d : BYTE; e : BYTE := BYTE#'$41'; END_VAR
b := BYTE#'a'; c := B#'$$'; d := b#'z';
IF b = BYTE#'a' THEN c := c OR B#16#80; END_IF;
END_FUNCTION_BLOCK
ORGANIZATION_BLOCK OB1 FB1.DB1(); END_ORGANIZATION_BLOCK
"""
    values = run(src).instance_db(1).values
    assert (values["b"], values["c"], values["d"], values["e"]) == (97, 0x24 | 0x80, 122, 65)


@pytest.mark.parametrize(
    ("literal", "message"),
    [
        ("BYTE#'ab'", "bad literal \"BYTE#'ab'\": it holds one character"),
        ("B#''", "bad literal \"B#''\": it holds one character"),
        ("BYTE#'€'", "BYTE#'€': a BYTE holds a character of code 0..255"),
    ],
)
def test_a_byte_literal_that_is_not_one_character_is_located(literal: str, message: str) -> None:
    src = f"FUNCTION_BLOCK FB1\nVAR b : BYTE; END_VAR\nb := {literal};\nEND_FUNCTION_BLOCK\n"
    (diag,) = check_scl(src, "t.scl")
    assert (diag.code, diag.loc.line, diag.loc.col) == ("E203", 3, 6)
    assert message in format_diagnostic(diag)
