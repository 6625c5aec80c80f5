"""For the charts under ``examples/``, import(export(chart)) gives back the same model, through
PLCopen TC6 XML and through TIA SimaticML (docs/import-export.md); the PLCopen export is an SFC
other IEC tools read, and SimaticML holds GRAPH natively."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from s7graph.engine.symbols import SymbolTable
from s7graph.sequencer.exchange import export_chart, import_chart
from s7graph.sequencer.text.format import format_row
from s7graph.sequencer.text.model import Chart
from s7graph.sequencer.text.parse import parse_chart, parse_file
from s7graph.sequencer.text.walk import uncommented, unlocated
from s7graph.web.cli import main
from tests.paths import ROOT

EXAMPLES = sorted(ROOT.glob("examples/*/*.s7g"))


def example(path: Path) -> tuple[Chart, SymbolTable]:
    return parse_file(path), SymbolTable.from_file(path.with_name("symbols.txt"))


@pytest.mark.parametrize("to", ["plcopen", "simaticml"])
@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.stem)
def test_example_comes_back_the_same_through_the_format(path: Path, to: str) -> None:
    chart, table = example(path)
    xml = export_chart(chart, to, table)
    back = import_chart(xml.encode(), f"{path.stem}.xml", symbols=table)
    assert back.format == to
    assert back.problems == []
    assert uncommented(unlocated(back.chart)) == uncommented(unlocated(chart))  # XML: no comments


@pytest.mark.parametrize("to", ["plcopen", "simaticml"])
def test_export_then_import_on_the_command_line_round_trips(to: str, tmp_path: Path) -> None:
    path = next(p for p in EXAMPLES if p.stem == "mixing")
    symbols = path.with_name("symbols.txt")
    xml, back = tmp_path / "mixing.xml", tmp_path / "back.s7g"
    assert main(["export", str(path), "--to", to, "-o", str(xml), "--symbols", str(symbols)]) == 0
    assert main(["import", str(xml), "-o", str(back), "--symbols", str(symbols)]) == 0
    assert main(["check", str(back), "--symbols", str(symbols)]) == 0
    original = parse_file(path)
    assert uncommented(unlocated(parse_chart(back.read_text()))) == uncommented(unlocated(original))


def native_only(xml: str) -> bytes:
    """The export without s7graph's own data: what another IEC tool sees."""
    return re.sub(r"<addData>.*?</addData>", "", xml, flags=re.S).encode()


def test_plcopen_export_is_an_iec_sfc_with_the_same_steps_conditions_and_rows() -> None:
    """Read as plain IEC (s7graph's data removed), the drill's export has the same steps,
    transitions, conditions and action rows: ``S1 S x`` went out as a P action
    ``x := TRUE``, ``N x`` as a Boolean action, ``S1 N n := n + 1`` as a P action — only the
    supervisions (GRAPH's) have no IEC form, and the symbols come back from the
    configuration's located globals."""
    path = next(p for p in EXAMPLES if p.stem == "drill")
    chart, table = example(path)
    back = import_chart(native_only(export_chart(chart, "plcopen", table)), "drill.xml").chart

    def shape(c: Chart) -> list[object]:
        return [
            [
                (s.number, s.name, s.initial, [format_row(r) for r in s.actions])
                for s in c.all_steps()
            ],
            [
                (t.number, t.name, t.sources, t.targets, unlocated(t.condition))
                for t in c.all_transitions()
            ],
        ]

    assert shape(back) == shape(chart)
    assert {s.name: s.address for s in back.symbols} == {s.name: str(s.address) for s in table}


def test_plcopen_export_of_rows_without_iec_form_is_reported_when_read_as_iec() -> None:
    """Mixing's interlocked rows (N C, D C) and its V1/A1 rows have no IEC qualifier: the
    export writes them as comments an IEC tool ignores, and reading it as plain IEC says
    so, row by row."""
    path = next(p for p in EXAMPLES if p.stem == "mixing")
    chart, table = example(path)
    back = import_chart(native_only(export_chart(chart, "plcopen", table)), "mixing.xml")
    empty = [d for d in back.problems if "empty body" in d.message]
    # Feed_A and Feed_B: NC, DC, DC, V1 S, A1 R; Mix: NC, V1 S, A1 R; Drain: NC
    assert len(empty) == 5 + 5 + 3 + 1


def test_an_iec_timer_call_goes_to_plcopen_as_an_fb_instance_and_comes_back() -> None:
    """``CALL SFB 4, DB 10 (…)`` is the call of the POU's instance ``TON_DB10`` in the SFC
    other IEC tools read (``Q => done`` included), and reads back as the same row; a call
    with no IEC form stays a comment."""
    text = (
        'FUNCTION_BLOCK "T"\nVAR done : BOOL; waited : TIME; END_VAR\nSEQUENCE 1\n'
        "INITIAL_STEP S1:\n  CALL SFB 4, DB 10 (IN := I0.0, PT := T#2S, Q => done, ET => waited);"
        "\n  CALL SFB 1, DB 11 (CD := I0.1, LOAD := I0.2, PV := 3);"
        "\n  CALL SFC 46;\nEND_STEP\nSTEP S2: END_STEP\n"
        "TRANSITION T1 FROM S1 TO S2 := done;\nTRANSITION T2 FROM S2 TO S1 := NOT I0.0;\n"
        "END_SEQUENCE\nEND_FUNCTION_BLOCK\n"
    )
    chart = parse_chart(text, "t.s7g")
    xml = export_chart(chart, "plcopen")
    assert '<variable name="TON_DB10"><type><derived name="TON"/></type></variable>' in xml
    assert "TON_DB10(IN := %IX0.0, PT := T#2S, Q => done, ET => waited);" in xml
    assert "CTD_DB11(CD := %IX0.1, LD := %IX0.2, PV := 3);" in xml  # IEC's LD is S7's LOAD
    assert "(* s7graph: CALL SFC 46; *)" in xml
    back = import_chart(native_only(xml), "t.xml").chart
    assert [format_row(r) for r in back.all_steps()[0].actions] == [
        "CALL SFB 4, DB 10 (IN := I0.0, PT := T#2S, Q => done, ET => waited);",
        "CALL SFB 1, DB 11 (CD := I0.1, LOAD := I0.2, PV := 3, Q => CTD_DB11_Q, "
        "CV => CTD_DB11_CV);",
    ]


def test_a_row_simaticml_cannot_hold_is_one_clear_export_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A CALL row has no SimaticML form here: one located line, exit 2; PLCopen takes it."""
    chart = tmp_path / "call.s7g"
    chart.write_text(
        'FUNCTION_BLOCK "X"\nVAR a : BOOL; END_VAR\nSEQUENCE 1\n'
        "INITIAL_STEP S1: END_STEP\nSTEP S2: CALL FC 9; END_STEP\n"
        "TRANSITION T1 FROM S1 TO S2 := a;\nTRANSITION T2 FROM S2 TO S1 := NOT a;\n"
        "END_SEQUENCE\nEND_FUNCTION_BLOCK\n"
    )
    assert main(["export", str(chart), "--to", "simaticml", "-o", str(tmp_path / "x.xml")]) == 2
    err = capsys.readouterr().err
    assert "call.s7g:5:10: S2 row" in err and "CALL FC 9" in err, err
    assert main(["export", str(chart), "--to", "plcopen", "-o", str(tmp_path / "x.xml")]) == 0


def test_a_jump_into_another_chart_keeps_both_charts_when_read_as_iec() -> None:
    """PLCopen has no jump between charts of a POU but a jump step naming the other
    chart's step: read back, the two charts stay two sequences and the jump leads across."""
    text = (
        'FUNCTION_BLOCK "J"\nVAR a : BOOL; END_VAR\n'
        'SEQUENCE 1\nINITIAL_STEP S1 "Idle": END_STEP\nSTEP S2 "Run": END_STEP\n'
        "TRANSITION T1 FROM S1 TO S2 := a;\nTRANSITION T2 FROM S2 TO S4 := NOT a;\n"
        'END_SEQUENCE\nSEQUENCE 2\nINITIAL_STEP S3 "Wait": END_STEP\n'
        'STEP S4 "Other": END_STEP\nTRANSITION T3 FROM S3 TO S4 := a;\n'
        "TRANSITION T4 FROM S4 TO S3 := NOT a;\nEND_SEQUENCE\nEND_FUNCTION_BLOCK\n"
    )
    chart = parse_chart(text)
    back = import_chart(native_only(export_chart(chart, "plcopen")), "j.xml").chart
    assert [[s.name for s in q.steps] for q in back.sequences] == [
        ["Idle", "Run"],
        ["Wait", "Other"],
    ]
    assert [(t.sources, t.targets) for t in back.all_transitions()] == [
        ((1,), (2,)),
        ((2,), (4,)),
        ((3,), (4,)),
        ((4,), (3,)),
    ]


def test_plcopen_export_draws_an_alternative_branch_left_to_right_in_graph_priority() -> None:
    """GRAPH's priority (the first written, then the lowest number) goes out as IEC's left to
    right, so an IEC tool reading the export takes the same path: written T5, T9, T3 is
    drawn T5, T3, T9, and reads back in that order."""
    chart = parse_chart(
        """FUNCTION_BLOCK "Alt"
SEQUENCE 1 "Alt"
  INITIAL_STEP S1 "Start": END_STEP
  STEP S2 "Fill": END_STEP
  STEP S3 "Heat": END_STEP
  STEP S4 "Drain": END_STEP
  TRANSITION T5 FROM S1 TO S2 := I0.0;
  TRANSITION T9 FROM S1 TO S3 := I0.1;
  TRANSITION T3 FROM S1 TO S4 := I0.2;
END_SEQUENCE
END_FUNCTION_BLOCK
""",
        "alt.s7g",
    )
    back = import_chart(native_only(export_chart(chart, "plcopen")), "alt.xml").chart
    names = {s.number: s.name for s in back.all_steps()}
    start = next(s.number for s in back.all_steps() if s.name == "Start")
    out = [names[t.targets[0]] for t in back.all_transitions() if t.sources == (start,)]
    assert out == ["Fill", "Drain", "Heat"]
