"""Comments: block comments nest, line comments inside them stay comment, and a comment
never closed names the line where it opened (docs/scl.md, "Blocks and declarations")."""

from __future__ import annotations

import pytest

from s7graph.steps.scl import SclError, format_diagnostic
from tests.steps.scl.helpers import build, codes, run

FB = """FUNCTION_BLOCK FB1
VAR n : INT; END_VAR
{body}
END_FUNCTION_BLOCK
DATA_BLOCK DB1 FB1 BEGIN END_DATA_BLOCK
ORGANIZATION_BLOCK OB1 BEGIN FB1.DB1(); END_ORGANIZATION_BLOCK
"""


def n_after(body: str) -> object:
    return run(FB.format(body=body)).instance_db(1).values["n"]


def test_a_nested_block_comment_ends_at_its_own_closing() -> None:
    assert n_after("(* outer (* inner *) n := 5; still comment *)\nn := n + 1;") == 1


def test_comments_nest_several_levels_deep_over_lines() -> None:
    body = "(* a (* b (* c\n*) n := 7; *)\nn := 9; *) n := n + 2;"
    assert n_after(body) == 2


def test_a_line_comment_inside_a_block_comment_stays_comment() -> None:
    assert n_after("(* // n := 5; *) n := 3;\n(* x\n// y\n*) n := n + 1;\n") == 4


def test_a_block_opener_in_a_line_comment_or_string_opens_nothing() -> None:
    src = FB.format(body="// (* not opened\nn := 4;")
    assert run(src).instance_db(1).values["n"] == 4
    strings = FB.replace("n : INT;", "n : INT; s : STRING[8];").format(body="s := '(*x';")
    assert run(strings).instance_db(1).values["s"] == "(*x"


def test_places_after_a_comment_stay_where_they_are() -> None:
    body = "(* one\n (* two *)\n*) n := 1.5;"
    assert [(c, line, col) for c, line, col in codes(FB.format(body=body))] == [("E220", 5, 4)]


@pytest.mark.parametrize(
    ("body", "line", "col"),
    [("n := 1;\n(* open\n (* inner *)\n n := 2;", 4, 1), ("(* (* twice *)", 3, 1)],
)
def test_an_unclosed_comment_names_the_line_where_it_opened(body: str, line: int, col: int) -> None:
    with pytest.raises(SclError) as caught:
        build(FB.format(body=body))
    (diag,) = caught.value.diagnostics
    assert (diag.code, diag.loc.line, diag.loc.col) == ("E202", line, col)
    assert f"comment opened at line {line} is never closed" in format_diagnostic(diag)
