"""Cross-references of a chart (``sequencer/xref.py``): every operand of the conditions,
interlocks, supervisions, action rows and permanent instructions with the element it stands
in, its access and its place; a symbol and its address are one operand, whether written by
the symbol or the address; an FB variable is not a symbol of the same name; the chart's
unused symbols are listed (a use in an S7-SCL block beside the chart counts); one table of
accesses by qualifier."""

from __future__ import annotations

from s7graph.engine.symbols import SymbolTable
from s7graph.sequencer.text.elements import DeclRef, RowRef, StepRef, TransitionRef
from s7graph.sequencer.text.parse import parse_chart
from s7graph.sequencer.xref import ACCESS, cross_references
from s7graph.steps.qualifiers import QUALIFIERS
from s7graph.steps.scl.parse import parse_source
from tests.paths import ROOT

CHART = """FUNCTION_BLOCK "Seq_x" FB 1 DB 1
VAR count : INT := 0; Lamp : BOOL; END_VAR
SYMBOLS
  "Start" : I0.0 : BOOL;
  "Lamp" : Q1.0 : BOOL;
  "Spare" : M9.0 : BOOL;
END_SYMBOLS
PERMANENT BEFORE
  M0.1 := "Start" AND NOT I0.1;
  S M0.2 := S2.X;
END_PERMANENT
SEQUENCE 1 "Main"
  INITIAL_STEP S1 "Idle":
    S0 R M0.2;
  END_STEP
  STEP S2 "Run":
    INTERLOCK := I0.1;
    SUPERVISION := S2.U > T#5S;
    N "Lamp";
    S1 N count := count + Lamp;
    D Q1.1, T#2S;
    CALL "TON", DB 10 (IN := M0.1, PT := T#1S, Q => M0.3);
    S1 ON S3;
    S1 CU C 4;
  END_STEP
  STEP S3 "End":
  END_STEP
  TRANSITION T1 "Go" FROM S1 TO S2 := I0.0 AND T2.TT;
  TRANSITION T2 FROM S2 TO S3 := count > 2;
  TRANSITION T3 FROM S3 TO S1 := TRUE;
END_SEQUENCE
END_FUNCTION_BLOCK
"""


def _uses(table: SymbolTable | None = None) -> dict[str, list[tuple[str, str, int]]]:
    refs = cross_references(parse_chart(CHART, "x.s7g"), table)
    return {
        operand: [(u.element, u.access, u.loc.line) for u in uses]
        for operand, uses in refs.operands().items()
    }


def test_every_use_names_its_element_access_and_line() -> None:
    uses = _uses()
    assert uses['"Start" (I0.0)'] == [
        ("permanent before 1", "read", 9),
        ('T1 "Go"', "read", 28),  # written as I0.0: the same operand
    ]
    assert uses["M0.2"] == [
        ("permanent before 2", "set", 10),
        ('S1 "Idle" row 1 (S0 R)', "reset", 14),
    ]
    assert uses["I0.1"] == [("permanent before 1", "read", 9), ('S2 "Run" interlock', "read", 17)]
    assert uses["S2.U"] == [('S2 "Run" supervision', "read", 18)]
    assert uses["S2.X"] == [("permanent before 2", "read", 10)]
    assert uses["T2.TT"] == [('T1 "Go"', "read", 28)]
    assert uses['"Lamp" (Q1.0)'] == [('S2 "Run" row 1 (N)', "write", 19)]
    assert uses["count"] == [
        ('S2 "Run" row 2 (S1 N)', "write", 20),
        ('S2 "Run" row 2 (S1 N)', "read", 20),
        ("T2", "read", 29),
    ]
    assert uses["Lamp"] == [('S2 "Run" row 2 (S1 N)', "read", 20)]  # the variable, unquoted
    assert uses["Q1.1"] == [('S2 "Run" row 3 (D)', "write", 21)]
    row = 'S2 "Run" row 4 (CALL)'
    assert uses['"TON"'] == [(row, "call", 22)]
    assert uses["DB 10"] == [(row, "instance", 22)]
    assert (row, "read", 22) in uses["M0.1"] and uses["M0.3"] == [(row, "write", 22)]
    assert uses["S3"] == [('S2 "Run" row 5 (S1 ON)', "activate", 23)]
    assert uses["C4"] == [('S2 "Run" row 6 (S1 CU)', "counter", 24)]


def test_each_use_names_the_element_the_editor_selects() -> None:
    refs = cross_references(parse_chart(CHART, "x.s7g"))
    assert {u.element: u.ref for u in refs.of("I0.1")} == {
        "permanent before 1": DeclRef("permanent", "before"),
        'S2 "Run" interlock': StepRef(2, "interlock"),
    }
    assert [u.ref for u in refs.of("S2.U")] == [StepRef(2, "supervision")]
    assert [u.ref for u in refs.of("Q1.1")] == [RowRef(2, 2)]
    assert [u.ref for u in refs.of("T2.TT")] == [TransitionRef(1)]


def test_a_symbol_tables_symbol_and_its_address_are_one_operand() -> None:
    table = SymbolTable.from_text('"Guard" ; I0.1 ; BOOL\n')
    uses = _uses(table)
    assert "I0.1" not in uses
    assert [e for e, _, _ in uses['"Guard" (I0.1)']] == ["permanent before 1", 'S2 "Run" interlock']


def test_the_unused_symbols_of_the_chart_are_listed_and_an_operand_found_by_any_name() -> None:
    refs = cross_references(parse_chart(CHART, "x.s7g"))
    assert refs.unused == ("Spare",)
    assert [u.element for u in refs.of("start")] == ["permanent before 1", 'T1 "Go"']
    assert refs.of("I0.0") == refs.of('"Start"') and refs.of("nothing") == []


def test_each_qualifier_has_one_access_and_the_docs_table_is_the_codes() -> None:
    assert set(ACCESS) == set(QUALIFIERS)
    text = (ROOT / "docs" / "cli.md").read_text(encoding="utf-8")
    table = text.split("| access | qualifiers |", 1)[1].split("\n\n", 1)[0]
    documented = {
        q.strip(" `"): row.split("|")[1].strip()
        for row in table.splitlines()[2:]
        for q in row.split("|")[2].split(",")
    }
    assert documented == ACCESS


def test_a_symbol_used_only_in_a_block_beside_the_chart_is_not_unused() -> None:
    block = parse_source(
        'FUNCTION FC 3 : VOID\nBEGIN\n  "Spare" := %M9.1 OR I0.0;\nEND_FUNCTION\n', "b.scl"
    )
    refs = cross_references(parse_chart(CHART, "x.s7g"), blocks=[block])
    assert refs.unused == ()
    assert [(u.element, u.access, u.place) for u in refs.of("M9.0")] == [
        ("FC 3", "write", "b.scl:3:3")
    ]
    assert [u.element for u in refs.of('"Start"')][-1] == "FC 3"  # its address written
    assert [u.ref for u in refs.of("M9.1")] == [None]  # nothing the chart's editor selects


def test_a_db_a_call_passes_is_a_use_of_that_db_however_it_is_named() -> None:
    chart = """FUNCTION_BLOCK "Seq" FB 1 DB 1
SYMBOLS "Recipe" : DB5 : DB5; END_SYMBOLS
PERMANENT BEFORE
  CALL FC 5 (src := DB5, x := MW2);
  CALL FC 5 (src := "Recipe", x := MW2);
  CALL FB 7, DB 6 (src := "Other");
  CALL FC 5 (src := db7, x := MW2);
END_PERMANENT
SEQUENCE 1 "S"
  INITIAL_STEP S1 "wait": END_STEP
END_SEQUENCE
END_FUNCTION_BLOCK
"""
    table = SymbolTable.from_text('"Other" ; DB 6 ; DB 6\n')
    refs = cross_references(parse_chart(chart, "x.s7g"), table)
    uses = {k: [(u.element, u.access, u.place) for u in v] for k, v in refs.operands().items()}
    assert uses['"Recipe" (DB5)'] == [
        ("permanent before 1", "argument", "x.s7g:4:21"),
        ("permanent before 2", "argument", "x.s7g:5:21"),
    ]
    assert uses['"Other" (DB6)'] == [  # a DB of the symbol table: passed, and an instance
        ("permanent before 3", "instance", "x.s7g:6:3"),
        ("permanent before 3", "argument", "x.s7g:6:27"),
    ]
    assert uses["DB 7"] == [("permanent before 4", "argument", "x.s7g:7:21")]
    assert refs.unused == () and "MW2" in uses
    assert refs.of("DB7") == refs.of("db 7") and len(refs.of("DB6")) == 2
