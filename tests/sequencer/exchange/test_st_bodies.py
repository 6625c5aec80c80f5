"""ST bodies with statements (docs/import-export.md): CODESYS's ``END_IF`` without ``;`` reads;
bodies of assignments and calls become rows and permanent instructions as before; a body
with statements a GRAPH row cannot hold (IF, CASE, FOR …) is kept whole for the SCL block —
a ``PendingScl`` record, a ``PENDING SCL`` comment in the chart, a located warning — and a
transition body assigning its own name is its condition."""

from __future__ import annotations

from s7graph.sequencer.exchange import import_chart, import_file
from s7graph.sequencer.exchange.st import SAssign, SOther, parse_statements
from s7graph.sequencer.text.format import format_chart, format_row
from s7graph.sequencer.text.parse import parse_chart
from s7graph.sequencer.text.walk import unlocated
from tests.sequencer.exchange.helpers import codes, synthetic


def test_end_if_without_a_semicolon_reads_as_codesys_reads_it() -> None:
    """``END_IF`` (and END_CASE, END_FOR, END_WHILE, END_REPEAT) may end without ``;``;
    written, the ``;`` is an empty statement."""
    bare = parse_statements("IF a THEN x := 1; END_IF\ny := 2;")
    semi = parse_statements("IF a THEN x := 1; END_IF;\ny := 2;")
    assert [type(s) for s in bare] == [type(s) for s in semi] == [SOther, SAssign]
    loops = parse_statements(
        "FOR i := 1 TO 3 DO n := n + i; END_FOR\nWHILE a DO a := FALSE; END_WHILE\n"
        "REPEAT n := n - 1; UNTIL n < 0 END_REPEAT\nCASE n OF 1: x := 1; END_CASE"
    )
    assert [s.keyword for s in loops if isinstance(s, SOther)] == ["FOR", "WHILE", "REPEAT", "CASE"]
    assert loops[0].writes == ("i", "n")  # type: ignore[union-attr]


def test_a_codesys_project_with_statement_bodies_imports_keeping_every_body() -> None:
    """Count (assignments) gives rows; Fill (an IF, ending ``END_IF`` without ``;``) and the
    transition Done (a CASE) are kept for the SCL block, each with a located warning; Start
    (``Start := …;``) is its condition. Done stays FALSE until the SCL block computes it, so
    the import also says the chart cannot leave Filling, and why."""
    result = import_file(synthetic("codesys_statements.xml"))
    chart = result.chart
    assert codes(result.problems) == [("I021", 35), ("I021", 64), ("I025", 82)]
    fill, done, stall = result.problems
    assert "action Fill: an IF statement, which a GRAPH row cannot hold" in fill.message
    assert "called from S2" in fill.message and "none of it runs until then" in fill.message
    assert "transition Done: a CASE statement" in done.message
    assert "Done is written only by transition Done, kept for the SCL block" in stall.message
    filling = chart.all_steps()[1]
    assert [format_row(r) for r in filling.actions] == ["S1 N n := n + 1;", "S1 R busy;"]
    assert "TRANSITION T1 FROM S1 TO S2 := start AND NOT busy;" in format_chart(chart)
    assert "TRANSITION T2 FROM S2 TO S1 := Done;" in format_chart(chart)
    assert [(p.kind, p.name, p.placement, p.step, p.event) for p in result.pending] == [
        ("transition", "Done", "before", None, ""),
        ("action", "Fill", "step", 2, ""),
    ]
    done_body, fill_body = result.pending
    assert fill_body.writes == ("busy", "valve", "full")
    assert done_body.result == "Done"
    assert fill_body.text.startswith("busy := TRUE;\nIF level < 10 THEN")


def test_the_pending_bodies_travel_in_the_chart_text() -> None:
    """The ``.s7g`` file keeps each pending body as a comment — on the step that will call
    it, at the end for PERMANENT ones — and reads back to the same chart."""
    chart = import_file(synthetic("codesys_statements.xml")).chart
    text = format_chart(chart)
    assert (
        "  (* PENDING SCL: action Fill (codesys_statements.xml:31), called from a row of S2:\n"
        "busy := TRUE;\nIF level < 10 THEN\n"
    ) in text
    assert text.index("PENDING SCL: action Fill") < text.index('STEP S2 "Filling"')
    assert text.rstrip().endswith("END_CASE\n*)")
    assert unlocated(parse_chart(text)).all_steps()[1].comment == chart.all_steps()[1].comment


def test_a_body_of_assignments_ending_end_if_is_no_longer_dropped_whole() -> None:
    """Before, one ``END_IF`` without ``;`` made the whole body unreadable; now only a body
    that holds a statement a row cannot hold is kept aside — its assignments with it, since
    the SCL block will run them in their order."""
    text = (
        b"FUNCTION_BLOCK F\nVAR_INPUT go : BOOL; END_VAR\nVAR n : INT; done : BOOL; END_VAR\n"
        b"INITIAL_STEP A: END_STEP\nSTEP B: WORK(N); END_STEP\n"
        b"ACTION WORK:\n n := n + 1;\n IF n > 3 THEN done := TRUE; END_IF\nEND_ACTION\n"
        b"TRANSITION FROM A TO B := go; END_TRANSITION\n"
        b"TRANSITION FROM B TO A := done; END_TRANSITION\nEND_FUNCTION_BLOCK\n"
    )
    result = import_chart(text, "f.st")
    assert codes(result.problems) == [("I025", 5), ("I021", 8)]
    assert result.chart.all_steps()[1].actions == ()
    assert "done is written only by action WORK, kept for the SCL block" in (
        result.problems[0].message
    )
    [pending] = result.pending
    assert pending.text == "\n n := n + 1;\n IF n > 3 THEN done := TRUE; END_IF\n"


def test_a_pou_body_with_statements_is_kept_for_permanent_before() -> None:
    text = (
        b"PROGRAM P\nVAR go : BOOL; n : INT; END_VAR\n"
        b"IF go THEN n := n + 1; END_IF;\n"
        b"INITIAL_STEP A: END_STEP\nSTEP B: END_STEP\n"
        b"TRANSITION FROM A TO B := go; END_TRANSITION\n"
        b"TRANSITION FROM B TO A := n > 3; END_TRANSITION\nEND_PROGRAM\n"
    )
    result = import_chart(text, "p.st")
    [pending] = result.pending
    assert (pending.kind, pending.placement, pending.writes) == ("body", "before", ("n",))
    assert pending.text.strip() == "IF go THEN n := n + 1; END_IF;"
    assert "called from PERMANENT BEFORE" in format_chart(result.chart)


def test_a_transition_body_assigning_its_name_is_its_condition() -> None:
    chart = import_file(synthetic("codesys_statements.xml")).chart
    t1 = chart.all_transitions()[0]
    assert t1.condition is not None and t1.name == ""
    assert "start AND NOT busy" in format_chart(chart)
