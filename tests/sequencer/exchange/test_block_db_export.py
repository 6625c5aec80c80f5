"""A DB a chart's CALL passes to an S7-SCL block's BLOCK_DB input (``src := DB5``, ``src :=
"Recipe"``) in the exports: to SimaticML as TIA writes a DB as a whole — an ``Address`` of
area DB, type Block_DB, the DB's number and no bit offset, under the DB's symbol when it has
one (TIA Portal Openness system manual, "Major changes", the ``Address`` node of
``SW.PlcBlocks.Access.xsd``) — and back; to PLCopen, which has no BLOCK_DB, as the ST comment
any call of a user block is, the DB named in its report. An export error names the chart's
place (docs/import-export.md)."""

from __future__ import annotations

from dataclasses import replace

import pytest

from s7graph.sequencer.checks.validate import validate
from s7graph.sequencer.exchange import export_reported, import_chart
from s7graph.sequencer.text.model import Chart, SymbolDecl
from s7graph.sequencer.text.parse import parse_chart
from s7graph.sequencer.text.walk import uncommented, unlocated
from tests.sequencer.test_block_db_arguments import chart_text, interfaces, table

WHOLE_DB5 = '<Address Area="DB" Type="Block_DB" BlockNumber="5"'


def chart_of(args: str, *, in_step: bool = False) -> Chart:
    """The chart calling FC 5 with ``args``, without its unused bit symbol (SimaticML
    carries the tags a block uses, as TIA's block export does)."""
    chart = parse_chart(chart_text(args, in_step=in_step), "seq.s7g")
    return replace(chart, symbols=tuple(s for s in chart.symbols if s.name != "Lamp"))


def same(a: Chart, b: Chart) -> bool:
    return uncommented(unlocated(a)) == uncommented(unlocated(b))


@pytest.mark.parametrize("db", ["DB5", '"Recipe"'])
@pytest.mark.parametrize("in_step", [False, True], ids=["permanent", "row"])
def test_a_db_passed_to_a_block_db_input_goes_to_simaticml_as_a_whole_db_and_comes_back(
    db: str, in_step: bool
) -> None:
    chart = chart_of(f"src := {db}, x := 3", in_step=in_step)
    xml, problems = export_reported(chart, "simaticml")
    assert [d.code for d in problems] == ["X012"]  # blocks by number, as for every call
    if db == "DB5":
        assert f'<Access Scope="GlobalVariable" UId="{21 if in_step else 23}">{WHOLE_DB5} />' in xml
    else:
        assert f'<Component Name="Recipe" />{WHOLE_DB5} Informative="true" />' in xml
    if not in_step:  # the LAD call box's parameter: what the S7-SCL block declares
        assert '<Parameter Name="src" Section="Input" Type="Block_DB" />' in xml
    back = import_chart(xml.encode(), "seq.xml")
    assert [d.code for d in back.problems] == ["I025"]  # T2 := FALSE: the test chart's stall
    assert same(back.chart, chart)
    found = validate(back.chart, table(), blocks=interfaces())  # s7graph check --blocks
    assert [d.message for d in found if d.is_error] == []


@pytest.mark.parametrize("to", ["simaticml", "plcopen"])
def test_a_db_symbol_of_the_symbol_table_a_call_passes_goes_with_the_export(to: str) -> None:
    """``src := "Other"`` names a DB of ``--symbols``: the export carries the symbol (in
    the block comment, in s7graph's data), so the chart reads back without the table; with
    it, the symbol stays in the table."""
    chart = chart_of('src := "Other", x := 3')
    xml, _ = export_reported(chart, to, table())
    alone = import_chart(xml.encode(), "seq.xml").chart
    other = SymbolDecl("Other", "DB6", "DB6")
    assert unlocated(alone.symbols[-1]) == unlocated(other)
    assert same(import_chart(xml.encode(), "seq.xml", symbols=table()).chart, chart)


def test_a_whole_db_tia_wrote_without_s7graphs_comment_is_declared_from_its_address() -> None:
    """A file TIA wrote has no ``s7graph:`` comment: the DB symbol's informative address
    says it is DB 5, so the import declares ``"Recipe" : DB5 : DB5`` and no tag; an
    ``Address`` alone is ``DB5``."""
    xml, _ = export_reported(chart_of('src := "Recipe", x := 3'), "simaticml")
    tia = xml.replace('; "Recipe" : DB5 : DB5', "")
    assert '"Recipe" : DB5' not in tia
    back = import_chart(tia.encode(), "tia.xml").chart
    assert [(s.name, s.address, s.type) for s in back.symbols] == [("Recipe", "DB5", "DB5")]
    bare = tia.replace('<Symbol><Component Name="Recipe" />', "").replace(
        ' Informative="true" /></Symbol>', " />"
    )
    back = import_chart(bare.encode(), "tia.xml").chart
    assert same(back, replace(chart_of("src := DB5, x := 3"), symbols=()))


def test_plcopen_writes_a_call_passing_a_db_as_an_st_comment_that_names_the_db() -> None:
    """IEC 61131-3 has no BLOCK_DB, nor a DB as a value: the call, like any call of a user
    block, is an ST comment in its S7 spelling, its report says why of the DB, and the
    chart reads back from s7graph's data."""
    chart = parse_chart(chart_text("src := DB5, x := 3", in_step=True), "seq.s7g")
    xml, problems = export_reported(chart, "plcopen")
    assert "(* s7graph: CALL FC 5 (src := DB5, x := 3); *)" in xml
    rows = [d.message for d in problems if d.loc.line == 12]
    assert rows == [
        "row 'CALL FC 5 (src := DB5, x := 3);' has no IEC form (IEC 61131-3 has no BLOCK_DB "
        "to pass DB 5 to): an ST comment in the SFC other tools read, kept in s7graph's data"
    ]
    (symbol,) = [d.message for d in problems if d.loc.line == 4]
    assert "a call passes it to a BLOCK_DB input, which IEC 61131-3 has not" in symbol
    assert same(import_chart(xml.encode(), "seq.xml").chart, chart)


@pytest.mark.parametrize(
    ("condition", "where", "why"),
    [
        ("nope", "6:32", "bad address 'nope': not an S7 address: TIA needs a tag"),
        ("a AND DB5", "6:38", "bad address 'DB5': not an S7 address: TIA needs a tag"),
        ("n + 1 > 2", "6:32", "n + 1: an operand LAD draws is a tag, a variable or a constant"),
        ("a OR n + 1", "6:37", "+ has no LAD form: a SimaticML network cannot hold it"),
    ],
)
def test_a_simaticml_export_error_names_the_place_in_the_chart(
    condition: str, where: str, why: str
) -> None:
    """A chart exported unchecked (``s7graph export`` checks it first) that SimaticML cannot
    hold: one error naming the place, not a bare message."""
    chart = parse_chart(
        'FUNCTION_BLOCK "X"\nVAR a : BOOL; n : INT; END_VAR\nSEQUENCE 1\n'
        "INITIAL_STEP S1: END_STEP\nSTEP S2: END_STEP\n"
        f"TRANSITION T1 FROM S1 TO S2 := {condition};\nTRANSITION T2 FROM S2 TO S1 := NOT a;\n"
        "END_SEQUENCE\nEND_FUNCTION_BLOCK\n",
        "t.s7g",
    )
    with pytest.raises(ValueError) as refused:
        export_reported(chart, "simaticml")
    assert str(refused.value).startswith(f"t.s7g:{where}: {why}"), refused.value
