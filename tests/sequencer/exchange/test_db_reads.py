"""An instance DB's variables read by name (``"T_S2".Q``, ``DB10.Q``) in the exports: in
SimaticML a global access to a DB member, the DB by its name, as TIA writes one; in
PLCopen IEC 61131-3's access to an FB instance's output (``TON_DB10.Q``). Each reads back
to the chart; a DB symbol no read goes through is no PLCopen type."""

from __future__ import annotations

import re
from dataclasses import replace

import pytest

from s7graph.engine.symbols import SymbolTable
from s7graph.sequencer.checks.validate import validate
from s7graph.sequencer.exchange import export_reported, import_chart
from s7graph.sequencer.text.format import format_expr, format_row
from s7graph.sequencer.text.model import Chart
from s7graph.sequencer.text.parse import parse_chart, parse_file
from s7graph.sequencer.text.walk import uncommented, unlocated
from tests.sequencer.exchange.helpers import synthetic
from tests.sequencer.exchange.test_roundtrip import native_only

PRESS = synthetic("db_reads.s7g")


def chart_of(condition: str, symbols: str = "", first_row: str = "") -> Chart:
    return parse_chart(
        f"""FUNCTION_BLOCK "M" FB 1 DB 1
{f"SYMBOLS {symbols} END_SYMBOLS" if symbols else ""}
SEQUENCE 1
  INITIAL_STEP S1 "Idle": {first_row} END_STEP
  STEP S2 "Dwell": CALL "TON", DB 10 (IN := S2.X, PT := T#2S); END_STEP
  TRANSITION T1 FROM S1 TO S2 := I0.0;
  TRANSITION T2 FROM S2 TO S1 := {condition};
END_SEQUENCE
END_FUNCTION_BLOCK
""",
        "m.s7g",
    )


def same(a: Chart, b: Chart) -> bool:
    return uncommented(unlocated(a)) == uncommented(unlocated(b))


def test_simaticml_writes_a_read_as_tia_writes_a_db_member_and_reads_it_back() -> None:
    chart = parse_file(PRESS)
    xml, problems = export_reported(chart, "simaticml")
    member = (
        r'<Access Scope="GlobalVariable" UId="\d+"><Symbol><Component Name="T_S2" />'
        r'<Component Name="(Q|ET)" /></Symbol></Access>'
    )
    # the transition, the interlock, the supervision, the row and the permanent Move box
    assert sorted(set(re.findall(member, xml))) == ["ET", "Q"]
    assert len(re.findall(member, xml)) == 6
    assert 's7graph: DB 1; "T_S2" : DB10 : SFB4; "Spare" : DB11 : SFB4' in xml
    assert [d.code for d in problems] == ["X012"]  # the CALL row's spelling only
    back = import_chart(xml.encode(), "press.xml")
    assert back.problems == []
    assert same(back.chart, chart)


def test_simaticml_writes_a_read_by_db_number_by_the_dbs_symbol_reported() -> None:
    chart = chart_of("DB10.Q", '"T_S2" : DB10 : SFB4;')
    xml, problems = export_reported(chart, "simaticml")
    assert [(d.code, d.loc.line, d.loc.col) for d in problems if d.code == "X013"] == [
        ("X013", 7, 34)
    ]
    assert 'DB10.Q is written "T_S2".Q' in problems[-1].message
    back = import_chart(xml.encode(), "m.xml").chart
    t2 = back.all_transitions()[1].condition
    assert t2 is not None and format_expr(t2) == '"T_S2".Q'


def test_simaticml_refuses_a_read_of_a_db_no_symbol_names_saying_to_name_it() -> None:
    with pytest.raises(ValueError) as caught:
        export_reported(chart_of("DB10.Q AND I0.1"), "simaticml")
    assert str(caught.value) == (
        "m.s7g:7:34: DB10.Q: TIA reads a DB's variables by the DB's name, and DB 10 has "
        'none: name it in the chart\'s SYMBOLS ("Timer_10" : DB10 : SFB4;) or in the '
        "symbol table"
    )


def test_a_db_symbol_of_the_symbol_table_travels_through_simaticml() -> None:
    """Imported with the table, the chart is the one exported; without it, the DB symbol
    kept in the block comment is declared in the chart's SYMBOLS."""
    table = SymbolTable()
    table.add("T_S2", "DB 10")
    chart = chart_of('"T_S2".Q')
    xml, _ = export_reported(chart, "simaticml", table)
    assert same(import_chart(xml.encode(), "m.xml", symbols=table).chart, chart)
    alone = import_chart(xml.encode(), "m.xml").chart
    assert [(s.name, s.address, s.type) for s in alone.symbols] == [("T_S2", "DB10", "SFB4")]
    assert [d for d in validate(alone) if d.is_error] == []


@pytest.mark.parametrize("to", ["plcopen", "simaticml"])
def test_symbols_the_table_given_holds_in_another_case_stay_in_the_table(to: str) -> None:
    """The symbol table holds a name once regardless of case, as STEP 7's symbol editor
    does: a DB symbol or tag the export carried that the table given to the import holds
    as ``"t_s2"`` or ``"LAMP"`` (the same DB, the same address) stays in the table."""
    table = SymbolTable()
    table.add("t_s2", "DB 10")
    table.add("LAMP", "Q0.0")
    chart = chart_of('"T_S2".Q', '"T_S2" : DB10 : SFB4; "Lamp" : Q0.0 : BOOL;', 'N "Lamp";')
    xml, _ = export_reported(chart, to)
    back = import_chart(xml.encode(), "m.xml", symbols=table).chart
    assert back.symbols == ()
    assert same(back, replace(chart, symbols=()))
    assert [d for d in validate(back, table) if d.is_error] == []


def test_a_tia_file_reading_a_db_member_reads_the_instance_db_the_table_names() -> None:
    """A file TIA wrote has no s7graph comment: ``"T_S2".Q`` is the instance DB's variable
    when the symbol table given names DB ``"T_S2"``, else a tag, as before."""
    table = SymbolTable()
    table.add("T_S2", "DB 10")
    xml, _ = export_reported(chart_of('"T_S2".Q', '"T_S2" : DB10 : SFB4;'), "simaticml")
    tia = re.sub(r"<Text>s7graph:[^<]*</Text>", "<Text />", xml)
    read = import_chart(tia.encode(), "m.xml", symbols=table).chart
    t2 = read.all_transitions()[1].condition
    assert t2 is not None and format_expr(t2) == '"T_S2".Q' and read.symbols == ()
    tag = import_chart(tia.encode(), "m.xml").chart.all_transitions()[1].condition
    assert tag is not None and format_expr(tag) == '"T_S2.Q"'


def test_a_read_of_a_user_fbs_instance_db_comes_back_for_check_with_its_blocks() -> None:
    """The import has no program blocks to check ``"Motor_DB".Running`` against: it keeps
    the read (``check --blocks`` checks it)."""
    chart = chart_of('"Motor_DB".Running', '"Motor_DB" : DB12 : FB17;', "CALL FB 17, DB 12;")
    xml, _ = export_reported(chart, "simaticml")
    back = import_chart(xml.encode(), "m.xml")
    assert same(back.chart, chart)
    assert [d.code for d in validate(back.chart) if d.is_error] == ["E048"]  # no --blocks


def test_plcopen_reads_an_iec_timers_variable_through_the_instance_its_call_uses() -> None:
    chart = parse_file(PRESS)
    xml, problems = export_reported(chart, "plcopen")
    plain = native_only(xml).decode()
    assert "TON_DB10.Q AND TON_DB10.ET >= T#2S" in plain
    assert "waited := TON_DB10.ET;" in plain and "last := TON_DB10.ET;" in plain
    assert '<variable name="TON_DB10"><type><derived name="TON"/></type>' in plain
    assert "TON_DB10(IN := Dwell.X, PT := T#2S);" in plain  # CALL "TON": the instance's call
    assert "SFB4" not in plain and "T_S2" not in plain
    spare = [d for d in problems if "Spare" in d.message]
    assert [(d.code, d.loc.line) for d in spare] == [("X010", 5)]
    assert "no read goes through it" in spare[0].message
    assert same(import_chart(xml.encode(), "press.xml").chart, chart)  # s7graph's data


def test_plcopen_read_by_another_tool_comes_back_as_the_calls_outputs() -> None:
    """An IEC tool's file (no s7graph data) reads ``TON_DB10.Q`` as the FB variable the
    call's ``Q =>`` writes, as for any IEC timer."""
    xml, _ = export_reported(parse_file(PRESS), "plcopen")
    back = import_chart(native_only(xml), "press.xml").chart
    t2 = back.all_transitions()[1].condition
    assert t2 is not None and format_expr(t2) == "TON_DB10_Q AND TON_DB10_ET >= T#2S"
    assert format_row(back.all_steps()[1].actions[0]) == (
        "CALL SFB 4, DB 10 (IN := S2.X, PT := T#2S, Q => TON_DB10_Q, ET => TON_DB10_ET);"
    )


def test_plcopen_reads_a_user_fbs_variable_from_a_global_instance_of_its_type() -> None:
    table = SymbolTable()
    table.add("Motor_DB", "DB 12")
    chart = chart_of('"Motor_DB".Running', first_row="CALL FB 17, DB 12;")
    xml, problems = export_reported(chart, "plcopen", table)
    plain = native_only(xml).decode()
    assert "Motor_DB.Running" in plain
    declared = '<variable name="Motor_DB"><type><derived name="FB17"/></type></variable>'
    assert plain.count(declared) == 2  # external in the POU, global in the configuration
    read = [d for d in problems if "Motor_DB" in d.message]
    assert [(d.code, d.loc.line) for d in read] == [("X010", 7)]
    assert "which nothing calls" in read[0].message
    kept = import_chart(xml.encode(), "m.xml").chart
    assert [(s.name, s.address, s.type) for s in kept.symbols] == [("Motor_DB", "DB12", "FB17")]
    assert same(import_chart(xml.encode(), "m.xml", symbols=table).chart, chart)


@pytest.mark.parametrize("to", ["plcopen", "simaticml"])
@pytest.mark.parametrize(
    ("read", "why"),
    [
        ("DB11.Q", "DB11.Q: DB11 is no instance DB of this chart's calls"),
        ('"Nope".Q', '"Nope".Q: no DB symbol "Nope"'),
    ],
)
def test_an_export_of_a_read_the_chart_cannot_make_names_its_place(
    to: str, read: str, why: str
) -> None:
    with pytest.raises(ValueError, match=re.escape(f"m.s7g:7:34: {why} (s7graph check says")):
        export_reported(chart_of(read, '"T_S2" : DB11 : SFB4;'), to)


@pytest.mark.parametrize("to", ["plcopen", "simaticml"])
def test_an_export_reads_an_operand_symbol_of_the_chart_as_no_db_as_check_does(to: str) -> None:
    """The chart's own ``"Lamp" : Q0.0`` hides a DB symbol ``"Lamp"`` of the symbol table
    given, for the export as for ``check`` (E048): the read names no DB."""
    table = SymbolTable()
    table.add("Lamp", "DB 10")
    chart = chart_of('"Lamp".Q', '"Lamp" : Q0.0 : BOOL;')
    assert [d.code for d in validate(chart, table) if d.is_error] == ["E048"]
    want = 'm.s7g:7:34: "Lamp".Q: no DB symbol "Lamp" (s7graph check says'
    with pytest.raises(ValueError, match=re.escape(want)):
        export_reported(chart, to, table)


def test_a_row_the_import_leaves_out_leaves_the_calls_whose_dbs_the_chart_reads() -> None:
    """A row the validator refuses is left out (I021); the conditions are then checked with
    the chart's calls still there, so ``"T_S2".Q`` still names an instance DB."""
    xml, _ = export_reported(parse_file(PRESS), "simaticml")
    bad = xml.replace('<Token Text="#waited := " />', '<Token Text="#nosuch := " />', 1)
    back = import_chart(bad.encode(), "press.xml")
    assert [(d.code, "nosuch" in d.message) for d in back.problems] == [("I021", True)]
    assert [format_row(r) for r in back.chart.all_steps()[1].actions] == [
        'CALL "TON", DB 10 (IN := S2.X, PT := T#2S);'
    ]
    t2 = back.chart.all_transitions()[1].condition
    assert t2 is not None and format_expr(t2) == '"T_S2".Q AND "T_S2".ET >= T#2S'
