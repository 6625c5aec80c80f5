"""After a syntax error the parser reads on from the next ';' or keyword that closes or
goes on with a statement, and reports up to ten syntax errors, each with its place and
what was expected there (docs/scl.md, "Diagnostics")."""

from __future__ import annotations

import pytest

from s7graph.steps.scl import SclError, check_scl, format_diagnostic
from s7graph.steps.scl.recover import MAX_SYNTAX_ERRORS
from tests.steps.scl.helpers import build


def fb(body: str, decls: str = "n : INT; b : BOOL;") -> str:
    return f"FUNCTION_BLOCK FB1\nVAR {decls} END_VAR\n{body}\nEND_FUNCTION_BLOCK\n"


def found(src: str) -> list[str]:
    return [format_diagnostic(d) for d in check_scl(src, "t.scl")]


def test_each_broken_statement_is_one_error_with_what_was_expected() -> None:
    body = "n := 1 +;\nIF n > 1 b THEN\n  n := 2 3;\n  b := ;\nEND_IF;\nn := 4;"
    assert found(fb(body)) == [
        "t.scl:3:9: error[E201]: unexpected ';'; expected '(', '+', '-', a block like FB17 or"
        " DB10, a constant, a name or …",
        "t.scl:4:10: error[E201]: unexpected 'b'; expected '&', ')', '*', '**', '+', ',' or …",
        "t.scl:5:10: error[E201]: unexpected '3'; expected '&', ')', '*', '**', '+', ',' or …",
        "t.scl:6:8: error[E201]: unexpected ';'; expected '(', '+', '-', a block like FB17 or"
        " DB10, a constant, a name or …",
    ]


def test_errors_in_declarations_case_arms_and_later_blocks_are_all_reported() -> None:
    src = fb("CASE n OF 1: n := ; 2..: ; END_CASE;", "n : INT := ; b : BOOL;")
    src += "FUNCTION FC1 : INT\nFC1 := 1 1;\nEND_FUNCTION\n"
    assert [(c, line, col) for c, line, col in _places(src)] == [
        ("E201", 2, 16),
        ("E201", 3, 19),
        ("E201", 3, 24),
        ("E201", 6, 10),
    ]


def test_a_stray_character_is_one_error_and_reading_goes_on() -> None:
    assert _places(fb("n := @@@ 1;\nn := 2;\nb := ;")) == [("E201", 3, 6), ("E201", 5, 6)]


def test_a_missing_end_after_an_error_still_names_the_open_block() -> None:
    src = "FUNCTION_BLOCK FB1\nVAR n : INT; END_VAR\nn := 1 1;\nIF TRUE THEN\n"
    messages = found(src)
    assert len(messages) == 2
    assert messages[1].startswith("t.scl:4:13: error[E202]: missing END_IF for the IF at line 4")


def test_at_most_ten_syntax_errors_are_reported() -> None:
    body = "\n".join(f"n := {k} {k};" for k in range(25))
    with pytest.raises(SclError) as caught:
        build(fb(body))
    diags = caught.value.diagnostics
    assert len(diags) == MAX_SYNTAX_ERRORS == 10
    assert [d.loc.line for d in diags] == list(range(3, 13))
    assert str(caught.value).endswith("(and 9 more)")


def _places(src: str) -> list[tuple[str, int, int]]:
    return [(d.code, d.loc.line, d.loc.col) for d in check_scl(src, "t.scl")]


@pytest.mark.parametrize(
    ("body", "message"),
    [
        ("WHILE n < 3 DO n := n + 1 END_WHILE;", "t.scl:3:26: error[E201]: missing ';' after '1'"),
        ("IF b THEN n := 1 END_IF;", "t.scl:3:17: error[E201]: missing ';' after '1'"),
        ("IF b THEN n := 1 ELSE n := 2; END_IF;", "t.scl:3:17: error[E201]: missing ';' after '1'"),
        (
            "IF b THEN n := 1 ELSIF n = 2 THEN ; END_IF;",
            "t.scl:3:17: error[E201]: missing ';' after '1'",
        ),
        ("REPEAT n := 1 UNTIL b END_REPEAT;", "t.scl:3:14: error[E201]: missing ';' after '1'"),
        (
            "CASE n OF 1: b := TRUE ELSE n := 0; END_CASE;",
            "t.scl:3:23: error[E201]: missing ';' after 'TRUE'",
        ),
    ],
)
def test_a_statement_without_its_semicolon_before_a_closing_keyword_says_so(
    body: str, message: str
) -> None:
    assert found(fb(body)) == [message]


def test_elseif_is_named_with_the_keyword_s7_scl_writes() -> None:
    body = "IF n = 0 THEN b := TRUE; ELSEIF n = 1 THEN b := FALSE; END_IF;"
    assert found(fb(body)) == ["t.scl:3:26: error[E201]: ELSEIF is no keyword: S7-SCL writes ELSIF"]


@pytest.mark.parametrize(
    ("body", "message"),
    [
        (
            "#n := 1;",
            "t.scl:3:1: error[E201]: '#' before a local name is TIA Portal's: S7-SCL V5"
            " writes the name alone",
        ),
        (
            "FB2.DB2(x := 1, q => b);",
            "t.scl:3:19: error[E201]: '=>' in a call is TIA Portal's:"
            " S7-SCL V5 reads an FB's output after the call (inst.Q) and gives an FC's output"
            " with ':='",
        ),
        (
            "REGION fill\n  n := 1;\nEND_REGION\nb := TRUE;",
            "t.scl:3:1: error[E201]: REGION is"
            " TIA Portal's: S7-SCL V5 has no regions; leave the line out",
        ),
    ],
)
def test_tia_portal_notation_is_named_with_what_s7_scl_v5_writes(body: str, message: str) -> None:
    assert found(fb(body))[0] == message


def test_tia_portal_types_and_string_conversions_say_the_s7_scl_v5_ones() -> None:
    src = fb("s := INT_TO_STRING(n);\nn := STRING_TO_INT(s);", "n : INT; s : STRING; x : LREAL;")
    assert found(src) == [
        "t.scl:2:30: error[E212]: LREAL is a TIA Portal type of S7-1200/1500, not S7-SCL V5's:"
        " use REAL (FB1)",
        "t.scl:3:6: error[E211]: INT_TO_STRING is TIA Portal's; S7-SCL V5 writes I_STRNG (FB1)",
        "t.scl:4:6: error[E211]: STRING_TO_INT is TIA Portal's; S7-SCL V5 writes STRNG_I (FB1)",
    ]


def test_a_letter_no_name_may_hold_says_which_letters_names_have() -> None:
    assert found(fb("n := 1;", "n : INT; maß : INT;"))[0] == (
        "t.scl:2:16: error[E201]: 'ß' cannot be in a name: S7-SCL names have letters A-Z,"
        " digits and _"
    )


def test_an_iec_edge_fb_says_how_s7_scl_v5_computes_the_edge() -> None:
    assert found(fb("n := 1;", "n : INT; e : R_TRIG;")) == [
        "t.scl:2:18: error[E212]: R_TRIG is TIA Portal's: S7-300/400 has no such system block;"
        " keep the last input in a static BOOL (q := clk AND NOT last; last := clk;) (FB1)"
    ]
