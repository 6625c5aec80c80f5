"""An export another tool edited reads back with the edit: s7graph's own data in a file —
the `.s7g` source in a PLCopen POU's ``addData``, the DB symbols of a SimaticML block's
``s7graph:`` comment — is used only while the file's own content is what s7graph exported
with it; else the file's own content holds, and the import says where it first differs
(I024; docs/import-export.md)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from s7graph.sequencer.exchange import export_chart, export_reported, import_chart
from s7graph.sequencer.text.format import format_expr
from s7graph.sequencer.text.parse import parse_chart
from s7graph.sequencer.text.walk import uncommented, unlocated
from s7graph.web.cli import main
from tests.sequencer.exchange.test_block_db_export import chart_of
from tests.sequencer.exchange.test_roundtrip import native_only

CHART = """FUNCTION_BLOCK "Fill"
VAR
  go : BOOL;
  full : BOOL;
  pump : BOOL;
END_VAR
SEQUENCE 1
  INITIAL_STEP S1 "Idle":
  END_STEP
  STEP S2 "Filling":
    N pump;
    INTERLOCK := NOT full;
  END_STEP
  TRANSITION T1 "Start" FROM S1 TO S2 := go;
  TRANSITION T2 FROM S2 TO S1 := full;
END_SEQUENCE
END_FUNCTION_BLOCK
"""


def exported() -> str:
    return export_chart(parse_chart(CHART, "fill.s7g"), "plcopen")


def sfc_edited(xml: str, old: str, new: str) -> str:
    """``xml`` with ``old`` replaced by ``new`` in its SFC part only (s7graph's data kept),
    as another IEC tool edits the chart it shows."""
    head, data = xml.split("<addData>", 1)
    assert old in head
    return head.replace(old, new) + "<addData>" + data


def line_of(xml: str, text: str) -> int:
    return xml[: xml.index(text)].count("\n") + 1


def test_an_unedited_plcopen_export_reads_back_from_s7graphs_data_exactly() -> None:
    chart = parse_chart(CHART, "fill.s7g")
    back = import_chart(exported().encode(), "fill.xml")
    assert back.problems == []
    assert uncommented(unlocated(back.chart)) == uncommented(unlocated(chart))


def test_a_plcopen_export_whose_boxes_were_only_moved_still_reads_from_s7graphs_data() -> None:
    """Layout (``position``, ``height``, ``width``) and a tool's own ``documentation``
    change nothing the chart says: the data holds, interlock and transition name too."""
    xml = sfc_edited(exported(), '<position x="40" y="180"/>', '<position x="77" y="190"/>')
    xml = sfc_edited(xml, 'height="30" width="80"', 'height="44" width="96"')
    xml = sfc_edited(xml, "<connectionPointOut/>", "<connectionPointOut/><documentation/>")
    back = import_chart(xml.encode(), "fill.xml")
    assert back.problems == []
    assert back.chart.all_steps()[1].interlock is not None
    assert back.chart.all_transitions()[0].name == "Start"


def test_a_step_renamed_in_the_sfc_is_imported_renamed_with_a_warning_at_the_step() -> None:
    xml = sfc_edited(exported(), 'name="Filling"', 'name="Topping_up"')
    back = import_chart(xml.encode(), "fill.xml")
    [warning] = [d for d in back.problems if d.code == "I024" and "SFC" in d.message]
    assert warning.loc.line == line_of(xml, 'name="Topping_up"')
    assert "step Topping_up (S2): name='Topping_up' where the export wrote 'Filling'" in (
        warning.message
    )
    steps = back.chart.all_steps()
    assert [(s.number, s.name) for s in steps] == [(1, "Idle"), (2, "Topping_up")]
    assert steps[1].interlock is None  # only s7graph's data held it: said in the warning
    assert "interlocks" in warning.message


def test_a_transition_condition_changed_in_the_sfc_is_imported_changed() -> None:
    xml = sfc_edited(exported(), "<![CDATA[go]]>", "<![CDATA[go AND NOT full]]>")
    back = import_chart(xml.encode(), "fill.xml")
    [warning] = [d for d in back.problems if d.code == "I024" and "SFC" in d.message]
    assert warning.loc.line == line_of(xml, "go AND NOT full")
    assert "transition T1: 'go AND NOT full' where the export wrote 'go'" in warning.message
    t1 = back.chart.all_transitions()[0]
    assert (t1.number, format_expr(t1.condition)) == (1, "go AND NOT full")  # type: ignore[arg-type]


def test_an_edited_plcopen_export_imports_with_exit_1_and_the_edit_on_the_command_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    source, out = tmp_path / "fill.xml", tmp_path / "back.s7g"
    source.write_text(sfc_edited(exported(), "<![CDATA[full]]>", "<![CDATA[NOT go]]>"))
    assert main(["import", str(source), "-o", str(out)]) == 1
    err = capsys.readouterr().err
    assert f"{source}:" in err and "warning[I024]: the SFC was edited" in err
    assert "TRANSITION T2 FROM S2 TO S1 := NOT go;" in out.read_text(encoding="utf-8")


def test_a_variable_changed_in_the_pou_interface_is_an_edit_too() -> None:
    xml = sfc_edited(exported(), '<variable name="full">', '<variable name="brim">')
    xml = sfc_edited(xml, "<![CDATA[full]]>", "<![CDATA[brim]]>")
    back = import_chart(xml.encode(), "fill.xml")
    assert any("variable brim" in d.message for d in back.problems if d.code == "I024")
    assert "brim" in [v.name for v in back.chart.vars]


def beside(xml: str, other: str) -> str:
    """``xml`` with the POU of ``other`` after its own: one file of two POUs."""
    found = re.search(r"<pou .*?</pou>", other, re.S)
    assert found is not None
    at = xml.index("</pou>") + len("</pou>")
    return xml[:at] + found[0] + xml[at:]


def test_only_the_pou_picked_is_checked_for_edits_against_s7graphs_export() -> None:
    """Whether s7graph's data still describes its POU takes an export of the chart it
    keeps: the import decides it for the chart ``--pou`` picks alone, so an edited POU
    beside it is neither exported nor reported."""
    fill = sfc_edited(exported(), 'name="Filling"', 'name="Topping_up"')
    drain = export_chart(parse_chart(CHART.replace('"Fill"', '"Drain"'), "d.s7g"), "plcopen")
    xml = beside(fill, native_only(drain).decode()).encode()
    back = import_chart(xml, "two.xml", pou="Drain")
    assert back.chart.name == "Drain"
    assert [d for d in back.problems if "edited" in d.message] == []
    picked = import_chart(xml, "two.xml", pou="Fill")
    assert [d.code for d in picked.problems if "the SFC was edited" in d.message] == ["I024"]
    assert [s.name for s in picked.chart.all_steps()] == ["Idle", "Topping_up"]


def test_a_db_renumbered_in_a_simaticml_block_holds_over_s7graphs_block_comment() -> None:
    """The ``s7graph:`` comment keeps ``"Recipe" : DB5`` (a DB symbol, which a GRAPH block
    has no field for); TIA, the DB renumbered, writes its informative address DB7: the
    block's own DB7 holds, reported at the access. Unedited, the comment's symbol holds."""
    xml, _ = export_reported(chart_of('src := "Recipe", x := 3'), "simaticml")
    same = import_chart(xml.encode(), "seq.xml")
    assert [d.code for d in same.problems] == ["I025"]  # the test chart's own stall
    edited = xml.replace('BlockNumber="5" Informative="true"', 'BlockNumber="7" Informative="true"')
    assert edited != xml
    back = import_chart(edited.encode(), "seq.xml")
    [warning] = [d for d in back.problems if d.code == "I024"]
    assert "\"Recipe\" is DB7 in the block's networks and DB5 in s7graph's block comment" in (
        warning.message
    )
    assert warning.loc.line == line_of(edited, 'BlockNumber="7"')
    assert [(s.name, s.address) for s in back.chart.symbols if s.name == "Recipe"] == [
        ("Recipe", "DB7")
    ]
