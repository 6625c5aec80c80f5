"""Every statement: IF, CASE, FOR, WHILE, REPEAT, EXIT, CONTINUE, RETURN, GOTO, and their
diagnostics (docs/scl.md, "Statements")."""

from __future__ import annotations

import pytest

from tests.steps.scl.helpers import codes, errors, run


def fb(body: str, decls: str = "", labels: str = "") -> dict[str, object]:
    """Run ``body`` once in FB1 (VAR ``i j n s : INT``, ``b : BOOL``, ``log : STRING``);
    the instance's values after it."""
    src = f"""
FUNCTION_BLOCK FB1
VAR i, j, n, s : INT; b : BOOL; log : STRING[80]; {decls} END_VAR
{f"LABEL {labels}; END_LABEL" if labels else ""}
{body}
END_FUNCTION_BLOCK
ORGANIZATION_BLOCK OB1
  FB1.DB1();
END_ORGANIZATION_BLOCK
"""
    return dict(run(src).instance_db(1).values)


@pytest.mark.parametrize(("n", "expected"), [(1, "one"), (2, "two"), (5, "other"), (-3, "neg")])
def test_if_elsif_else(n: int, expected: str) -> None:
    got = fb(f"""
  n := {n};
  IF n = 1 THEN log := 'one';
  ELSIF n = 2 THEN log := 'two';
  ELSIF n < 0 THEN log := 'neg';
  ELSE log := 'other';
  END_IF;""")
    assert got["log"] == expected


@pytest.mark.parametrize(
    ("n", "expected"), [(1, "a"), (3, "b"), (7, "b"), (9, "b"), (4, "c"), (10, "else"), (-5, "m")]
)
def test_case_with_lists_ranges_and_else(n: int, expected: str) -> None:
    got = fb(f"""
  n := {n};
  CASE n OF
    1: log := 'a';
    3, 5..9: log := 'b';
    4: log := 'c';
    -10..-1: log := 'm';
  ELSE
    log := 'else';
  END_CASE;""")
    assert got["log"] == expected


def test_case_without_else_does_nothing_for_other_values() -> None:
    assert fb("n := 3; log := 'x'; CASE n OF 1: log := 'a'; END_CASE;")["log"] == "x"


def test_for_counts_with_by_up_and_down_and_leaves_the_first_value_beyond() -> None:
    got = fb("""
  s := 0;
  FOR i := 1 TO 10 BY 3 DO s := s * 100 + i; log := CONCAT(log, I_STRNG(i)); END_FOR;
  FOR j := 10 TO 1 BY -4 DO log := CONCAT(log, I_STRNG(j)); END_FOR;""")
    assert got["log"] == "+1+4+7+10+10+6+2"
    assert got["i"] == 13 and got["j"] == -2


def test_for_evaluates_its_end_and_step_once() -> None:
    got = fb("n := 3; s := 0; FOR i := 1 TO n DO n := 10; s := s + 1; END_FOR;")
    assert got["s"] == 3


def test_for_with_a_step_in_a_variable_counts_down_when_it_is_negative() -> None:
    got = fb("n := -2; s := 0; FOR i := 10 TO 1 BY n DO s := s + 1; n := 5; END_FOR;")
    assert (got["s"], got["i"]) == (5, 0)  # the step read once: 10 8 6 4 2
    got = fb("n := 2; s := 0; FOR i := 10 TO 1 BY -n DO s := s + 1; END_FOR;")
    assert (got["s"], got["i"]) == (5, 0)


def test_for_that_never_starts_leaves_only_the_start_value() -> None:
    got = fb("s := 0; FOR i := 5 TO 1 DO s := s + 1; END_FOR;")
    assert (got["s"], got["i"]) == (0, 5)


def test_for_steps_to_the_end_of_the_range_without_overflow() -> None:
    got = fb("FOR i := 32000 TO 32766 DO s := i; END_FOR; b := OK;")
    assert (got["i"], got["s"], got["b"]) == (32767, 32766, True)


def test_for_whose_body_sets_its_variable_wraps_at_the_end_of_the_range() -> None:
    """The step after ``i := 32767`` leaves the INT: it wraps to -32768 with OK FALSE, and
    the loop goes on from there up to its end (the step is checked whenever the loop
    stores into its variable, constant end and step or not)."""
    got = fb(
        "b := TRUE; FOR i := 1 TO 10 DO c := c + 1; IF b THEN i := 32767; b := FALSE; "
        "END_IF; END_FOR; okay := OK;",
        "c : DINT; okay : BOOL;",
    )
    assert (got["c"], got["i"], got["okay"]) == (1 + 32779, 11, False)


def test_while_and_repeat() -> None:
    got = fb("""
  i := 1;
  WHILE i <= 50 DO i := i + 2; END_WHILE;
  j := 1;
  REPEAT j := j + 2; UNTIL j > 50 AND NOT b END_REPEAT;
  n := 0;
  REPEAT n := n + 1; UNTIL TRUE END_REPEAT;""")
    assert (got["i"], got["j"], got["n"]) == (51, 51, 1)


def test_exit_and_continue_in_every_loop() -> None:
    got = fb("""
  FOR i := 1 TO 10 DO
    IF i MOD 2 = 0 THEN CONTINUE; END_IF;
    IF i > 7 THEN EXIT; END_IF;
    log := CONCAT(log, I_STRNG(i));
  END_FOR;
  j := 0;
  WHILE TRUE DO
    j := j + 1;
    IF j < 3 THEN CONTINUE; END_IF;
    EXIT;
  END_WHILE;
  n := 0; s := 0;
  REPEAT
    n := n + 1;
    IF n < 4 THEN CONTINUE; END_IF;
    s := s + 1;
  UNTIL n >= 6 END_REPEAT;""")
    assert got["log"] == "+1+3+5+7"
    assert (got["i"], got["j"], got["n"], got["s"]) == (9, 3, 6, 3)


def test_exit_leaves_only_the_innermost_loop() -> None:
    got = fb("""
  s := 0;
  FOR i := 1 TO 3 DO
    FOR j := 1 TO 3 DO
      IF j = 2 THEN EXIT; END_IF;
      s := s + 1;
    END_FOR;
  END_FOR;""")
    assert got["s"] == 3


def test_return_leaves_the_block() -> None:
    got = fb("i := 1; IF i = 1 THEN RETURN; END_IF; i := 2;")
    assert got["i"] == 1
    got = fb("FOR i := 1 TO 10 DO IF i = 4 THEN RETURN; END_IF; END_FOR;")
    assert got["i"] == 4


def test_goto_forward_and_backward() -> None:
    got = fb(
        """
  i := 0;
  GOTO skip;
  log := 'never';
skip: i := i + 1;
back: log := CONCAT(log, 'x');
  IF LEN(log) < 3 THEN GOTO back; END_IF;""",
        labels="skip, back",
    )
    assert (got["i"], got["log"]) == (1, "xxx")


def test_goto_out_of_nested_loops_to_an_enclosing_list() -> None:
    got = fb(
        """
  s := 0;
  FOR i := 1 TO 5 DO
    WHILE TRUE DO
      s := s + 1;
      IF s = 3 THEN GOTO out; END_IF;
    END_WHILE;
  END_FOR;
  log := 'not here';
out: log := CONCAT(log, 'out');""",
        labels="out",
    )
    assert (got["s"], got["i"], got["log"]) == (3, 1, "out")


def test_labels_inside_a_loop_body_and_exit_continue_through_them() -> None:
    got = fb(
        """
  s := 0;
  FOR i := 1 TO 4 DO
    j := 0;
again: j := j + 1;
    IF j < i THEN GOTO again; END_IF;
    IF i = 2 THEN CONTINUE; END_IF;
    s := s + j;
    IF i = 3 THEN EXIT; END_IF;
  END_FOR;""",
        labels="again",
    )
    assert (got["s"], got["i"]) == (4, 3)


def test_the_label_empty_statement_and_a_label_on_a_loop() -> None:
    got = fb(
        """
  i := 0;
top: FOR j := 1 TO 2 DO i := i + 1; END_FOR;
  IF i < 4 THEN GOTO top; END_IF;
done: ;""",
        labels="top, done",
    )
    assert got["i"] == 4


@pytest.mark.parametrize(
    ("body", "labels", "code"),
    [
        ("GOTO nowhere;", "a", "E218"),
        ("GOTO a;", "a", "E218"),  # declared, never placed
        ("a: i := 1; a: i := 2;", "a", "E219"),
        ("IF b THEN a: i := 1; END_IF; GOTO a;", "a", "E219"),  # into a branch
        ("FOR i := 1 TO 2 DO a: ; END_FOR; GOTO a;", "a", "E219"),  # into a loop
        ("x: i := 1;", "a", "E218"),  # placed, not declared
        ("EXIT;", "", "E240"),
        ("IF b THEN CONTINUE; END_IF;", "", "E240"),
        ("FOR r := 1 TO 2 DO END_FOR;", "", "E241"),
        ("FOR i := 1 TO 2 BY 0 DO END_FOR;", "", "E241"),
        ("CASE r OF 1: ; END_CASE;", "", "E242"),
        ("CASE i OF 1: ; 0..2: ; END_CASE;", "", "E242"),
        ("CASE i OF 40000: ; END_CASE;", "", "E242"),
        ("WHILE i DO END_WHILE;", "", "E222"),
    ],
)
def test_statement_diagnostics(body: str, labels: str, code: str) -> None:
    src = f"""FUNCTION_BLOCK FB1
VAR i : INT; r : REAL; b : BOOL; END_VAR
{f"LABEL {labels}; END_LABEL" if labels else ""}
{body}
END_FUNCTION_BLOCK
"""
    assert code in errors(src)


def test_duplicate_label_declaration_and_unused_labels() -> None:
    src = """FUNCTION FC1 : VOID
LABEL a, b, a; END_LABEL
a: ;
END_FUNCTION
"""
    assert codes(src) == [("E210", 2, 13), ("W301", 2, 10), ("W301", 2, 13)]


def test_goto_diagnostic_is_located_at_the_goto() -> None:
    src = """FUNCTION FC1 : VOID
LABEL a; END_LABEL
a: ;
  GOTO b;
END_FUNCTION
"""
    assert codes(src)[0] == ("E218", 4, 3)
