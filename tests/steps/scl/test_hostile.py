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


def test_a_flat_chain_of_a_hundred_contacts_is_not_nesting() -> None:
    """``a AND b AND c …`` is one level of operators, however long (an interlock of 100
    contacts compiles); only a chain beyond the tree's depth limit is E204."""
    bools = fb("b := " + " AND ".join(["b"] * 100) + ";").replace("INT;", "INT; b : BOOL;")
    assert codes(bools) == []
    assert codes(fb("i := " + " + ".join(["i"] * 100) + ";")) == []


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


@pytest.mark.parametrize("digits", ["١٢", "１２"])
def test_a_number_of_non_ascii_digits_is_a_syntax_error_where_it_stands(digits: str) -> None:
    """S7-SCL numbers have the digits 0-9 only: Arabic-Indic or full-width digits are not
    read as 12."""
    found = check_scl(fb(f"i := WORD_TO_INT(INT_TO_WORD({digits}));"), "d.scl")
    assert [(d.code, d.loc.line, d.loc.col) for d in found] == [("E201", 3, 30)]
    assert f"{digits[0]!r} is not a digit of S7-SCL" in found[0].message


def test_a_db_of_many_members_set_in_begin_gives_each_member_its_value() -> None:
    """Members are found by name through an index (a DB of N members set in BEGIN is not
    N×N comparisons)."""
    n = 3_000
    members = "".join(f"  v{k} : INT;\n" for k in range(n))
    sets = "".join(f"  V{k} := {k % 1000};\n" for k in range(n))
    src = f"DATA_BLOCK DB1\nSTRUCT\n{members}END_STRUCT\nBEGIN\n{sets}END_DATA_BLOCK\n"
    src += "ORGANIZATION_BLOCK OB1\nEND_ORGANIZATION_BLOCK\n"
    cpu = run(src)
    assert [cpu.mem.get(f"DB1.DBW{2 * k}") for k in (0, 1, 999, 1000, n - 1)] == [0, 1, 999, 0, 999]


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


ARMS = 3000
"""More arms than CPython compiles as one ``if``/``elif`` chain (about 2,900)."""


def test_an_elsif_chain_and_a_case_of_three_thousand_arms_choose_the_right_arm() -> None:
    """Each pass of the loop takes one arm or the ELSE: a chain cut into groups behind a
    flag still takes exactly one, also when the pass before took a later group's arm."""
    elsif = "".join(f"ELSIF k = {n} THEN r := {n};\n" for n in range(1, ARMS))
    arms = "".join(f"{n}: r := {n};\n" for n in range(1, ARMS))
    src = f"""
ORGANIZATION_BLOCK OB1
VAR_TEMP k, r, a, b : DINT; END_VAR
  FOR k := {ARMS - 5} TO {ARMS + 1} DO
    IF k = 0 THEN r := 0;
{elsif}    ELSE r := -1;
    END_IF;
    a := a + r;
    CASE k OF 0: r := 0;
{arms}    ELSE r := -1;
    END_CASE;
    b := b + r;
  END_FOR;
  k := 1;
  IF k = 0 THEN r := 0; {elsif} END_IF;
  MD0 := DINT_TO_DWORD(a);
  MD4 := DINT_TO_DWORD(b);
  MD8 := DINT_TO_DWORD(r);
END_ORGANIZATION_BLOCK
"""
    cpu = run(src)
    assert cpu.mode is CpuMode.RUN
    expected = sum(range(ARMS - 5, ARMS)) - 2
    assert (cpu.mem.get("MD0"), cpu.mem.get("MD4"), cpu.mem.get("MD8")) == (expected, expected, 1)


@pytest.mark.parametrize(
    ("values", "line"),
    [
        ("1..10: ; 20: ; 11..19: ; 15:", 2007),
        ("30..40: ; 25..30:", 2005),
        ("7: ; 1..6: ; 7..9:", 2006),
    ],
)
def test_a_case_value_listed_twice_is_found_among_two_thousand(values: str, line: int) -> None:
    """After 2,000 arms (lines 4–2003) the last value overlaps an earlier one."""
    body = "".join(f"{n}: ;\n" for n in range(1000, 3000)) + values.replace(" ;", " ;\n")
    assert codes(fb(f"CASE i OF\n{body} END_CASE;")) == [("E242", line, 2)]


@pytest.mark.parametrize(
    ("src", "said"),
    [
        ("FUNCTION FC99999999999999999999 : VOID\n;\nEND_FUNCTION\n", "FC number 99999999…"),
        ("DATA_BLOCK DB4000000000 STRUCT a : INT; END_STRUCT BEGIN END_DATA_BLOCK\n", "DB"),
        ("DATA_BLOCK DB0 STRUCT a : INT; END_STRUCT BEGIN END_DATA_BLOCK\n", "DB number 0"),
        ("ORGANIZATION_BLOCK OB99999\n;\nEND_ORGANIZATION_BLOCK\n", "OB number 99999"),
        ("FUNCTION_BLOCK FB65536\n;\nEND_FUNCTION_BLOCK\n", "FB number 65536 is outside"),
    ],
)
def test_a_block_number_outside_its_range_is_a_located_diagnostic(src: str, said: str) -> None:
    found = check_scl(src, "t.scl")
    assert [(d.code, d.loc.line) for d in found] == [("E214", 1)]
    assert said in found[0].message and len(format_diagnostic(found[0])) < 120


def test_an_fb_called_with_a_global_db_of_the_source_is_a_diagnostic_at_the_call() -> None:
    src = """DATA_BLOCK DB1 STRUCT a : INT; END_STRUCT BEGIN END_DATA_BLOCK
FUNCTION_BLOCK FB1
VAR a : INT; END_VAR
  a := a + 1;
END_FUNCTION_BLOCK
ORGANIZATION_BLOCK OB1
  FB1.DB1();
END_ORGANIZATION_BLOCK
"""
    found = check_scl(src, "t.scl")
    assert [(d.code, d.loc.line, d.loc.col) for d in found] == [("E233", 7, 3)]
    assert "DB1 is a global DB (t.scl:1:12), not an instance of FB1" in found[0].message


def test_a_block_error_and_a_loop_abort_name_their_place_once() -> None:
    src = """
ORGANIZATION_BLOCK OB1
VAR_TEMP a : ARRAY[1..3] OF INT; i : INT; END_VAR
  i := 7; a[i] := 1;
END_ORGANIZATION_BLOCK
"""
    entry = list(run(src).diagnostics)[-2]
    assert entry.message == "t.scl:4:13: array index 7 outside 1..3"
    looping = src.replace("i := 7; a[i] := 1;", "i := 7;\n  WHILE i > 0 DO END_WHILE;")
    entry = list(run(looping).diagnostics)[-2]
    assert entry.event_id == EventId.CYCLE_TIME_EXCEEDED and entry.block == "OB1"
    assert entry.message.startswith(
        "aborted: a loop still running at twice the maximum cycle time (300 ms), "
        "the loop at t.scl:5:"
    )


def test_a_source_over_a_million_characters_is_refused_before_it_is_parsed() -> None:
    found = check_scl(fb("i := 1;\n" * 130_000), "big.scl")
    assert [(d.code, d.loc.line, d.loc.col) for d in found] == [("E204", 1, 1)]
    assert "1,040,060 characters; at most 1,000,000" in found[0].message


@pytest.mark.parametrize("limit", [RecursionError, MemoryError])
def test_python_refusing_the_generated_code_is_a_diagnostic(
    monkeypatch: pytest.MonkeyPatch, limit: type[Exception]
) -> None:
    """CPython's compiler has limits of its own (nesting, memory): reaching one is E204 at
    the first block, never a crash."""
    from s7graph.steps.scl import compile as scl_compile

    def refuse(*_: object) -> None:
        raise limit

    monkeypatch.setattr(scl_compile, "_assemble", refuse)
    found = check_scl(fb("i := 1;"), "t.scl")
    assert [(d.code, d.loc.line) for d in found] == [("E204", 1)]
    assert "for Python to compile" in found[0].message


def test_where_a_scan_was_names_the_scl_source_never_the_generated_code() -> None:
    """The runner's monitor names where an aborted scan was (docs/runtime.md, "When a scan
    hangs or fails"): in an S7-SCL block, the place in its source."""
    import threading

    from s7graph.engine.blocks import fc
    from s7graph.engine.runner import _innermost

    seen: list[str] = []

    @fc(100, "PEEK")
    def peek(ctx: object, params: dict[str, object]) -> None:
        seen.append(_innermost(threading.get_ident()))

    src = """
ORGANIZATION_BLOCK OB1
VAR_TEMP i : INT; END_VAR
  i := 1;
    PEEK();
END_ORGANIZATION_BLOCK
"""
    cpu = run(src, blocks=[peek], before=lambda cpu: cpu.load(peek))
    assert cpu.mode is CpuMode.RUN, list(cpu.diagnostics)[-2:]
    assert seen == [" (t.scl:5:5)"]
