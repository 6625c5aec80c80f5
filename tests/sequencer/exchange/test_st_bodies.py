"""ST bodies with statements (docs/import-export.md): CODESYS's ``END_IF`` without ``;`` reads;
bodies of assignments and calls become rows and permanent instructions as before; a body
with statements a GRAPH row cannot hold (IF, CASE, FOR …) is kept whole for the SCL block —
an SCL FC the chart calls (a ``PENDING SCL`` comment when the SCL compiler refuses it) —
and a transition body assigning its own name is its condition."""

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


def test_a_codesys_project_with_statement_bodies_imports_running_every_body() -> None:
    """Count (assignments) gives rows; Fill (an IF, ending ``END_IF`` without ``;``) and the
    transition Done (a CASE) become SCL FCs the chart calls, each reported where its first
    statement a row cannot hold is; Start (``Start := …;``) is its condition. Done is
    computed by its FC, so the chart can leave Filling: no stall is reported."""
    result = import_file(synthetic("codesys_statements.xml"))
    chart = result.chart
    assert codes(result.problems) == [("I033", 35), ("I033", 64)]
    fill, done = result.problems
    assert "action Fill: an IF statement, which a GRAPH row cannot hold" in fill.message
    assert "the body is SCL FC 2 (the chart's SCL source), called from S2" in fill.message
    assert "transition Done: a CASE statement" in done.message
    filling = chart.all_steps()[1]
    assert [format_row(r) for r in filling.actions] == [
        "CALL FC 2 (busy_IN := busy, level := level, valve_IN := valve, full_IN := full, "
        "busy => busy, valve => valve, full => full);",
        "S1 N n := n + 1;",
        "S1 R busy;",
    ]
    assert "TRANSITION T1 FROM S1 TO S2 := start AND NOT busy;" in format_chart(chart)
    assert "TRANSITION T2 FROM S2 TO S1 := Done;" in format_chart(chart)
    assert not result.pending
    assert [(f.item.kind, f.item.name, f.item.placement, f.number) for f in result.functions] == [
        ("transition", "Done", "before", 1),
        ("action", "Fill", "step", 2),
    ]
    done_fc, fill_fc = result.functions
    assert fill_fc.item.writes == ("busy", "valve", "full")
    assert done_fc.item.result == "Done"
    assert fill_fc.item.text.startswith("busy := TRUE;\nIF level < 10 THEN")


def test_the_pending_bodies_travel_in_the_chart_text() -> None:
    """The ``.s7g`` file keeps each body the SCL compiler refuses as a comment — on the
    step that would call it — and reads back to the same chart."""
    chart = import_file(synthetic("codesys_scl_bodies.xml")).chart
    text = format_chart(chart)
    assert (
        "  (* PENDING SCL: action Log (codesys_scl_bodies.xml:49), called from a row of S2:\n"
        "IF phase > 0 THEN\n"
    ) in text
    assert text.index("PENDING SCL: action Log") < text.index('STEP S2 "Heating"')
    assert unlocated(parse_chart(text)).all_steps()[1].comment == chart.all_steps()[1].comment


def test_a_body_of_assignments_ending_end_if_is_no_longer_dropped_whole() -> None:
    """Before, one ``END_IF`` without ``;`` made the whole body unreadable; now only a body
    that holds a statement a row cannot hold is set aside — its assignments with it, since
    its SCL FC runs them in their order."""
    text = (
        b"FUNCTION_BLOCK F\nVAR_INPUT go : BOOL; END_VAR\nVAR n : INT; done : BOOL; END_VAR\n"
        b"INITIAL_STEP A: END_STEP\nSTEP B: WORK(N); END_STEP\n"
        b"ACTION WORK:\n n := n + 1;\n IF n > 3 THEN done := TRUE; END_IF\nEND_ACTION\n"
        b"TRANSITION FROM A TO B := go; END_TRANSITION\n"
        b"TRANSITION FROM B TO A := done; END_TRANSITION\nEND_FUNCTION_BLOCK\n"
    )
    result = import_chart(text, "f.st")
    assert codes(result.problems) == [("I033", 8)]
    assert [format_row(r) for r in result.chart.all_steps()[1].actions] == [
        "CALL FC 1 (n_IN := n, done_IN := done, n => n, done => done);"
    ]
    [fc] = result.functions
    assert fc.item.text == "\n n := n + 1;\n IF n > 3 THEN done := TRUE; END_IF\n"


def test_a_pou_body_with_statements_is_called_from_permanent_before() -> None:
    text = (
        b"PROGRAM P\nVAR go : BOOL; n : INT; END_VAR\n"
        b"IF go THEN n := n + 1; END_IF;\n"
        b"INITIAL_STEP A: END_STEP\nSTEP B: END_STEP\n"
        b"TRANSITION FROM A TO B := go; END_TRANSITION\n"
        b"TRANSITION FROM B TO A := n > 3; END_TRANSITION\nEND_PROGRAM\n"
    )
    result = import_chart(text, "p.st")
    [fc] = result.functions
    assert (fc.item.kind, fc.item.placement, fc.item.writes) == ("body", "before", ("n",))
    assert fc.item.text.strip() == "IF go THEN n := n + 1; END_IF;"
    assert "PERMANENT BEFORE\n  CALL FC 1 (go := go, n_IN := n, n => n);" in format_chart(
        result.chart
    )


def test_a_transition_body_assigning_its_name_is_its_condition() -> None:
    chart = import_file(synthetic("codesys_statements.xml")).chart
    t1 = chart.all_transitions()[0]
    assert t1.condition is not None and t1.name == ""
    assert "start AND NOT busy" in format_chart(chart)
