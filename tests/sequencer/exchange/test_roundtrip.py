"""For the charts under ``examples/``, import(export(chart)) gives back the same model, through
PLCopen TC6 XML and through TIA SimaticML (docs/import-export.md); the PLCopen export is an SFC
other IEC tools read, and SimaticML holds GRAPH natively."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from s7graph.engine.symbols import SymbolTable
from s7graph.sequencer.exchange import export_chart, export_reported, import_chart
from s7graph.sequencer.exchange.naming import transliterate
from s7graph.sequencer.exchange.shape import priority
from s7graph.sequencer.text.format import format_chart, format_expr, format_row
from s7graph.sequencer.text.model import Chart
from s7graph.sequencer.text.parse import parse_chart, parse_file
from s7graph.sequencer.text.walk import uncommented, unlocated
from s7graph.web.cli import main
from tests.paths import ROOT
from tests.sequencer.exchange.helpers import sim, synthetic

EXAMPLES = sorted(ROOT.glob("examples/*/*.s7g"))
SIX = synthetic("six_sequences.s7g")
DB_READS = synthetic("db_reads.s7g")  # instance DB variables read by name


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


@pytest.mark.parametrize(("to", "status"), [("plcopen", 1), ("simaticml", 0)])
def test_export_then_import_on_the_command_line_round_trips(
    to: str, status: int, tmp_path: Path
) -> None:
    """Mixing's interlocks and its V1/A1 rows are not in the SFC other IEC tools read: the
    PLCopen export says so (exit 1); SimaticML holds all of it (exit 0)."""
    path = next(p for p in EXAMPLES if p.stem == "mixing")
    symbols = path.with_name("symbols.txt")
    xml, back = tmp_path / "mixing.xml", tmp_path / "back.s7g"
    args = ["export", str(path), "--to", to, "-o", str(xml), "--symbols", str(symbols)]
    assert main(args) == status
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
    configuration's located globals. Step S5 ``Dwell`` is ``S5`` there: IEC compares names
    without case, and the variable ``dwell`` has that name."""
    path = next(p for p in EXAMPLES if p.stem == "drill")
    chart, table = example(path)
    back = import_chart(native_only(export_chart(chart, "plcopen", table)), "drill.xml").chart

    def shape(c: Chart) -> list[object]:
        return [
            [
                (s.number, s.name, s.initial, [format_row(r) for r in s.actions])
                for s in c.all_steps()
            ],
            [  # TC6 names no transition: the names are in s7graph's data only
                (t.number, t.sources, t.targets, unlocated(t.condition))
                for t in c.all_transitions()
            ],
        ]

    want = shape(chart)
    steps = want[0]
    assert isinstance(steps, list) and steps[4][:2] == (5, "Dwell")
    steps[4] = (5, "S5", *steps[4][2:])
    assert shape(back) == want
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
    text = synthetic("plcopen_export_timers.s7g").read_text(encoding="utf-8")
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


def test_permanent_calls_and_moves_travel_through_simaticml_as_lad_boxes() -> None:
    """A permanent CALL is a LAD call box fed by the power rail (block and instance DB by
    number, reported once as for CALL rows), an assignment of an operand or a constant a
    MOVE box: both read back as the same instructions."""
    chart = parse_chart(synthetic("permanent_boxes.s7g").read_text(encoding="utf-8"), "p.s7g")
    xml, problems = export_reported(chart, "simaticml")
    assert [(d.code, d.loc.line) for d in problems] == [("X012", 19)]
    assert '<CallInfo Name="SFB4" BlockType="SFB">' in xml and '<Part Name="Move"' in xml
    back = import_chart(xml.encode(), "p.xml")
    assert back.problems == []
    assert uncommented(unlocated(back.chart)) == uncommented(unlocated(chart))
    added = import_chart(xml.replace('Name="Move"', 'Name="Add"', 1).encode(), "p.xml")
    assert [(d.code, d.message) for d in added.problems] == [
        ("I022", "permanent operation not imported: part Add has no GRAPH permanent form")
    ]
    assert len(added.chart.before) == len(chart.before) - 1


def test_a_permanent_arithmetic_expression_is_one_clear_simaticml_export_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``n := n + 1`` among the permanent instructions has no LAD form this export writes:
    one located line, exit 2; PLCopen takes it (a stored action of the initial step)."""
    chart = tmp_path / "sum.s7g"
    chart.write_text(
        'FUNCTION_BLOCK "X"\nVAR a : BOOL; n : INT; END_VAR\nSEQUENCE 1\n'
        "INITIAL_STEP S1: END_STEP\nSTEP S2: END_STEP\n"
        "TRANSITION T1 FROM S1 TO S2 := a;\nTRANSITION T2 FROM S2 TO S1 := NOT a;\n"
        "END_SEQUENCE\nPERMANENT AFTER\n  n := n + 1;\n"
        "END_PERMANENT\nEND_FUNCTION_BLOCK\n"
    )
    assert main(["export", str(chart), "--to", "simaticml", "-o", str(tmp_path / "x.xml")]) == 2
    err = capsys.readouterr().err
    assert "sum.s7g:10:3: permanent instruction n := n + 1: an arithmetic expression" in err, err
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
    xml = export_chart(chart, "plcopen")
    drawn = re.findall(r'<transition localId="1000(\d\d)"[^>]*><position x="(\d+)"', xml)
    assert [int(n) for n, _ in sorted(drawn, key=lambda d: int(d[1]))] == [5, 3, 9]
    back = import_chart(native_only(xml), "alt.xml").chart
    names = {s.number: s.name for s in back.all_steps()}
    start = next(s.number for s in back.all_steps() if s.name == "Start")
    leaving = {t.number: t for t in back.all_transitions() if t.sources == (start,)}
    out = [names[leaving[n].targets[0]] for n in priority(list(leaving))]
    assert out == ["Fill", "Drain", "Heat"]  # read back, the same path wins


# ---------------------------------------------------------------- what other tools see

PERMANENT = synthetic("plcopen_export_permanent.s7g").read_text(encoding="utf-8")


def test_plcopen_export_gives_other_tools_the_permanent_instructions(tmp_path: Path) -> None:
    """PERMANENT AFTER goes to the SFC other IEC tools read as the body of an action stored
    (S) on the initial step and never reset — which runs every call, after the transitions,
    as PERMANENT AFTER does; a set coil is ``x := x OR c``, a reset coil ``x := x AND NOT c``,
    a timer the call of its instance. Read back as IEC, the chart runs the same."""
    chart = parse_chart(PERMANENT, "p.s7g")
    xml, problems = export_reported(chart, "plcopen")
    assert problems == []
    assert '<action localId="0" qualifier="S"><relPosition x="0" y="0"/><inline><ST>' in xml
    assert "latch := latch OR go;\nlatch := latch AND go;" in xml
    assert "TON_DB10(IN := Run.X, PT := T#50MS, Q => done, ET => waited);" in xml
    back = import_chart(native_only(xml), "p.xml")
    assert [d.code for d in back.problems] == ["I031", "I024"]  # TON_DB10 is SFB 4; the task
    assert format_chart(back.chart).split("PERMANENT AFTER")[1] == format_chart(chart).split(
        "PERMANENT AFTER"
    )[1].replace("S latch := go;", "latch := latch OR go;").replace(
        "R latch := NOT go;", "latch := latch AND go;"
    )
    texts = {}
    for name, c in (("original", chart), ("read back", back.chart)):
        path = tmp_path / f"{name}.s7g"
        path.write_text(format_chart(c))
        texts[name] = [
            (r["active"], r["values"])
            for r in sim(
                tmp_path,
                path,
                watch=["pulse", "latch", "n", "done"],
                cycles=20,
                stimulus=[
                    {"at_ms": 30, "set": {"go": True}},
                    {"at_ms": 120, "set": {"go": False}},
                ],
            )
        ]
    assert texts["read back"] == texts["original"]


def test_plcopen_export_reports_what_other_tools_do_not_see(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Interlocks, supervisions, rows without an IEC qualifier, TO STOP, block options and
    PERMANENT BEFORE's place: each a located warning (exit 1); all of it stays in s7graph's
    data, so s7graph reads the file back exactly."""
    text = (
        'FUNCTION_BLOCK "W"\n  ORDER := CODESYS;\nVAR a : BOOL; b : BOOL; END_VAR\n'
        "PERMANENT BEFORE\n  b := a;\nEND_PERMANENT\nSEQUENCE 1\n"
        "  INITIAL_STEP S1:\n    INTERLOCK := a;\n    NC b;\n  END_STEP\n"
        "  STEP S2:\n    SUPERVISION := S2.T > T#5S;\n  END_STEP\n"
        "  TRANSITION T1 FROM S1 TO S2 := a;\n  TRANSITION T2 FROM S2 TO STOP := NOT a;\n"
        "END_SEQUENCE\nEND_FUNCTION_BLOCK\n"
    )
    path = tmp_path / "w.s7g"
    path.write_text(text)
    _, problems = export_reported(parse_chart(text, str(path)), "plcopen")
    assert [(d.code, d.loc.line) for d in problems] == [
        ("X011", 5),
        ("X010", 1),
        ("X010", 9),
        ("X010", 13),
        ("X010", 16),
        ("X010", 10),
    ]
    assert main(["export", str(path), "--to", "plcopen", "-o", str(tmp_path / "w.xml")]) == 1
    err = capsys.readouterr().err
    assert f"{path}:10:5: warning[X010]: row 'NC b;' has no IEC form" in err
    assert err.splitlines()[-1].endswith("(PLCopen TC6 XML (SFC)), 6 warnings")
    back = import_chart((tmp_path / "w.xml").read_bytes(), "w.xml").chart
    assert uncommented(unlocated(back)) == uncommented(unlocated(parse_chart(text)))


def test_a_six_sequence_chart_keeps_sequences_and_numbers_read_by_another_tool() -> None:
    """Read as plain IEC, six sequences stay six, with the same step and transition
    numbers: a step only an upward link reaches hangs in its sequence's drawing (else it
    read as a chart of its own), and s7graph's export gives each step its number as its
    localId (a transition 100000 plus its number), which s7graph reads back."""
    chart = parse_file(SIX)
    back = import_chart(native_only(export_chart(chart, "plcopen")), "cell.xml").chart
    assert [[s.number for s in q.steps] for q in back.sequences] == [
        [s.number for s in q.steps] for q in chart.sequences
    ]
    assert [(t.number, t.sources, t.targets) for t in back.all_transitions()] == [
        (t.number, t.sources, t.targets) for t in chart.all_transitions()
    ]
    tia = import_chart(export_chart(chart, "simaticml").encode(), "cell.xml").chart
    assert [(t.number, t.sources, t.targets) for t in tia.all_transitions()] == [
        (t.number, t.sources, t.targets) for t in chart.all_transitions()
    ]


def test_simaticml_export_keeps_the_address_of_an_action_operand() -> None:
    """``N "Ram"`` with Ram at Q0.0: the action names the tag by an Access element with its
    address, as the networks do, so it reads back at Q0.0 (it came back as M100.0)."""
    text = synthetic("tia_export_addresses.s7g").read_text(encoding="utf-8")
    chart = parse_chart(text)
    back = import_chart(export_chart(chart, "simaticml").encode(), "a.xml")
    assert {s.name: s.address for s in back.chart.symbols} == {
        "Ram": "Q0.0",
        "Go": "I0.0",
        "Count": "MW20",
    }
    assert back.problems == []


def test_simaticml_export_writes_call_rows_and_reads_them_back() -> None:
    """An IEC chart with a timer has CALL rows: SimaticML takes them (in s7graph's spelling
    of the call, reported once: TIA names blocks by symbol) and reads them back."""
    text = synthetic("tia_export_call_rows.s7g").read_text(encoding="utf-8")
    chart = parse_chart(text, "t.s7g")
    xml, problems = export_reported(chart, "simaticml")
    assert [(d.code, d.loc.line) for d in problems] == [("X012", 10)]
    assert 'Qualifier="CALL"' in xml and "#done" in xml
    back = import_chart(xml.encode(), "t.xml").chart
    assert [format_row(r) for r in back.all_steps()[1].actions] == [
        'CALL SFB 4, DB 10 (IN := "Go", PT := T#2S, Q => done, ET => waited);'
    ]
    assert {s.name: s.address for s in back.symbols} == {"Go": "I0.0"}


def test_plcopen_export_writes_s7_literals_in_iec_form_and_reads_them_back() -> None:
    """``L#70000`` is ``DINT#70000`` and ``W#16#0F0F`` ``WORD#16#0F0F`` in the ST other tools
    read (they know no ``L#``); read back as plain IEC, the rows are the chart's."""
    text = """FUNCTION_BLOCK "T"
VAR big : DINT; w : WORD; END_VAR
SEQUENCE 1
INITIAL_STEP S1:
  N big := L#70000;
  N w := W#16#0F0F;
END_STEP
STEP S2: END_STEP
TRANSITION T1 FROM S1 TO S2 := big > L#5;
TRANSITION T2 FROM S2 TO S1 := TRUE;
END_SEQUENCE
END_FUNCTION_BLOCK
"""
    xml = export_chart(parse_chart(text, "t.s7g"), "plcopen")
    plain = native_only(xml).decode()
    assert "L#" not in plain and "DINT#70000" in plain and "WORD#16#0F0F" in plain
    back = import_chart(plain.encode(), "t.xml").chart
    rows = [format_row(r) for r in back.all_steps()[0].actions]
    assert rows == ["N big := 70000;", "N w := W#16#0F0F;"]
    t1 = back.all_transitions()[0].condition
    assert t1 is not None and format_expr(t1) in ("big > 5", "big > L#5")


def test_a_plcopen_export_with_a_symbol_table_reads_back_with_its_symbols() -> None:
    """The chart s7graph keeps in its own data carries the symbols it was exported with:
    read back, the drill passes ``check`` without the symbol file."""
    from s7graph.sequencer.checks.validate import validate

    path = next(p for p in EXAMPLES if p.stem == "drill")
    chart, table = example(path)
    back = import_chart(export_chart(chart, "plcopen", table).encode(), "drill.xml").chart
    assert [d for d in validate(back) if d.is_error] == []
    assert {s.name: s.address for s in back.symbols} == {s.name: str(s.address) for s in table}


def test_simaticml_counter_and_timer_rows_read_back() -> None:
    """TIA writes an S5 counter or timer as ``%C3`` / ``%T4`` in an action's text: the rows
    s7graph exports that way come back, not left out."""
    text = """FUNCTION_BLOCK "T"
SEQUENCE 1
INITIAL_STEP S1:
  S1 CS C3, C#5;
  S1 CU C3;
  S1 TL T4, S5T#2S;
END_STEP
STEP S2: END_STEP
TRANSITION T1 FROM S1 TO S2 := I0.0;
TRANSITION T2 FROM S2 TO S1 := I0.1;
END_SEQUENCE
END_FUNCTION_BLOCK
"""
    chart = parse_chart(text, "t.s7g")
    back = import_chart(export_chart(chart, "simaticml").encode(), "t.xml")
    assert [d.code for d in back.problems] == []
    rows = [format_row(r) for r in back.chart.all_steps()[0].actions]
    assert rows == [format_row(r) for r in chart.all_steps()[0].actions]


def test_simaticml_export_names_each_step_and_transition_once() -> None:
    """TIA takes a name once per block: two steps and a transition named ``Fill`` go out as
    ``Fill``, ``Fill_2`` and ``Fill_3``, each renamed one reported at its element."""
    text = """FUNCTION_BLOCK "T"
SEQUENCE 1
INITIAL_STEP S1 "Fill": END_STEP
STEP S2 "fill": END_STEP
TRANSITION T1 "Fill" FROM S1 TO S2 := I0.0;
TRANSITION T2 FROM S2 TO S1 := I0.1;
END_SEQUENCE
END_FUNCTION_BLOCK
"""
    xml, problems = export_reported(parse_chart(text, "t.s7g"), "simaticml")
    names = re.findall(r'<(?:Step|Transition) [^>]*?Name="([^"]+)"', xml)
    assert sorted(names, key=str.casefold) == ["Fill", "fill_2", "Fill_3", "Trans2"]
    assert [(d.code, d.loc.line) for d in problems] == [("X013", 4), ("X013", 5)]


def test_an_unnamed_transition_comes_back_unnamed_from_simaticml() -> None:
    """TIA names a transition nobody named ``Trans<n>``: the export writes that default for
    an unnamed transition, and the import reads it back as no name, so the chart comes
    back as written — ``T1`` unnamed, ``T2`` still ``Back``."""
    text = """FUNCTION_BLOCK "T"
SEQUENCE 1
INITIAL_STEP S1 "Idle": END_STEP
STEP S2 "Busy": END_STEP
TRANSITION T1 FROM S1 TO S2 := I0.0;
TRANSITION T2 "Back" FROM S2 TO S1 := I0.1;
END_SEQUENCE
END_FUNCTION_BLOCK
"""
    chart = parse_chart(text, "t.s7g")
    xml = export_chart(chart, "simaticml")
    assert re.findall(r'<Transition [^>]*?Name="([^"]+)"', xml) == ["Trans1", "Back"]
    back = import_chart(xml.encode(), "t.xml").chart
    assert [t.name for t in back.all_transitions()] == ["", "Back"]
    assert uncommented(unlocated(back)) == uncommented(unlocated(chart))


def test_plcopen_export_names_are_iec_identifiers() -> None:
    """IEC 61131-3 identifiers are ASCII letters, digits and single underscores, none at
    the end: ``Lamp (x)`` and ``Füll ä`` go out as ``Lamp_x`` and ``Full_a`` (a letter
    with a Latin base loses its marks)."""
    text = """FUNCTION_BLOCK "Hard_Ünïcode"
SYMBOLS
  "Lamp (x)" : Q0.0 : BOOL;
END_SYMBOLS
SEQUENCE 1
INITIAL_STEP S1 "Füll ä": N "Lamp (x)"; END_STEP
STEP S2: END_STEP
TRANSITION T1 FROM S1 TO S2 := I0.0;
TRANSITION T2 FROM S2 TO S1 := I0.1;
END_SEQUENCE
END_FUNCTION_BLOCK
"""
    plain = native_only(export_chart(parse_chart(text, "t.s7g"), "plcopen")).decode()
    names = re.findall(r'<(?:variable|step|pou) [^>]*?name="([^"]*)"', plain)
    assert names and all(re.fullmatch(r"[A-Za-z_](?:_?[A-Za-z0-9])*", n) for n in names), names
    assert "Lamp_x" in names and "Full_a" in names and "Hard_Unicode" in names


def test_plcopen_export_gives_each_step_and_global_an_iec_name_of_its_own() -> None:
    """Names that differ in GRAPH but give one IEC identifier (``Шаг`` and ``Shag``,
    ``Motor-1`` and ``Motor_1``, a step and a tag both ``Start``, a step ``Fill`` and the
    variable ``fill``: IEC compares without case) stay apart in the SFC other tools read:
    the steps as ``S<n>``, the globals with ``_2`` …, each reported (X013); read back as
    IEC, every row, jump and condition names what it named before."""
    text = """FUNCTION_BLOCK "Col" FB 4
VAR fill : BOOL; END_VAR
SYMBOLS
  "Motor-1" : Q0.0 : BOOL;
  "Motor_1" : Q0.1 : BOOL;
  "Start" : I0.0 : BOOL;
END_SYMBOLS
SEQUENCE 1
INITIAL_STEP S1 "Start": N "Motor-1"; END_STEP
STEP S2 "Fill": N "Motor_1"; END_STEP
STEP S3 "Шаг": END_STEP
STEP S4 "Shag": END_STEP
STEP S5 "S1": END_STEP
TRANSITION T1 FROM S1 TO S2 := "Start";
TRANSITION T2 FROM S2 TO S3 := NOT "Start";
TRANSITION T3 FROM S3 TO S4 := fill;
TRANSITION T4 FROM S4 TO S5 := S3.X;
TRANSITION T5 FROM S5 TO S1 := fill;
END_SEQUENCE
END_FUNCTION_BLOCK
"""
    xml, problems = export_reported(parse_chart(text, "t.s7g"), "plcopen")
    plain = native_only(xml).decode()
    steps = re.findall(r'<step [^>]*?name="([^"]*)"', plain)
    assert steps == ["Start", "S2", "S3", "S4", "S5"]
    assert re.findall(r'<jumpStep [^>]*?targetName="([^"]*)"', plain) == ["Start"]
    globals_ = re.findall(r'<variable name="([^"]*)" address', plain)
    assert globals_ == ["Motor_1", "Motor_1_2", "Start_2"]
    assert sorted((d.code, d.loc.line) for d in problems if d.code == "X013") == [
        ("X013", 5),
        ("X013", 6),
        ("X013", 10),
        ("X013", 11),
        ("X013", 12),
        ("X013", 13),
    ]
    back = import_chart(plain.encode(), "t.xml").chart
    rows = [[format_row(r) for r in s.actions] for s in back.all_steps()]
    assert rows[:2] == [['N "Motor_1";'], ['N "Motor_1_2";']]
    conds = [format_expr(t.condition) for t in back.all_transitions() if t.condition]
    assert conds == ['"Start_2"', 'NOT "Start_2"', "fill", "S3.X", "fill"]


@pytest.mark.parametrize(
    ("name", "latin"),
    [
        ("Подача", "Podacha"),
        ("Цех", "Cex"),  # ц: c before i, e, y, j
        ("Цапфа", "Czapfa"),  # else cz
        ("Щит", "Shhit"),
        ("ЖУК", "ZHUK"),  # a capital in capitals
        ("Объём", "Obyom"),  # ъ and ь are only marks: left out
        ("Выход", "Vyxod"),  # ы is y` without its mark
        ("Эхо", "Exo"),
        ("Їжак", "Yizhak"),  # Ukrainian
        ("Füll Straße", "Full Strasse"),  # another script's marks, and ß
        ("注水", "注水"),  # no Latin form: as it is
    ],
)
def test_transliteration_is_gost_7_79_system_b_without_its_marks(name: str, latin: str) -> None:
    assert transliterate(name) == latin


def test_cyrillic_names_go_to_plcopen_in_latin_letters_and_to_simaticml_as_they_are() -> None:
    """PLCopen takes IEC identifiers, ASCII only: Cyrillic names go out transliterated by
    GOST 7.79-2000 system B (``Подача`` → ``Podacha``, ``Цех`` → ``Cex``, ``ЖУК`` →
    ``ZHUK``, the POU ``Линия`` → ``Liniya``, the tag ``Насос`` → ``Nasos``), not as
    ``S<n>``; a name with no letter either can hold (``注水``) is ``S<n>``, reported.
    SimaticML names are not identifiers: they go out as they are, and both imports give
    back the names the chart had."""
    text = """FUNCTION_BLOCK "Линия"
SYMBOLS
  "Насос" : Q0.0 : BOOL;
END_SYMBOLS
SEQUENCE 1
INITIAL_STEP S1 "Подача": N "Насос"; END_STEP
STEP S2 "Цех": END_STEP
STEP S3 "ЖУК": END_STEP
STEP S4 "注水": END_STEP
TRANSITION T1 FROM S1 TO S2 := I0.0;
TRANSITION T2 FROM S2 TO S3 := I0.1;
TRANSITION T3 FROM S3 TO S4 := I0.2;
TRANSITION T4 FROM S4 TO S1 := I0.3;
END_SEQUENCE
END_FUNCTION_BLOCK
"""
    chart = parse_chart(text, "t.s7g")
    xml, problems = export_reported(chart, "plcopen")
    plain = native_only(xml).decode()
    assert re.findall(r'<step [^>]*?name="([^"]*)"', plain) == ["Podacha", "Cex", "ZHUK", "S4"]
    assert re.findall(r'<pou name="([^"]*)"', plain) == ["Liniya"]
    assert re.findall(r'<variable name="([^"]*)" address', plain) == ["Nasos"]
    assert [(d.code, d.loc.line) for d in problems if d.code == "X013"] == [("X013", 9)]
    assert "no letter or digit" in next(d.message for d in problems if d.code == "X013")
    kept = import_chart(xml.encode(), "t.xml").chart  # from s7graph's data in the file
    assert [s.name for s in kept.all_steps()] == ["Подача", "Цех", "ЖУК", "注水"]
    tia = export_chart(chart, "simaticml")
    assert re.findall(r'<Step [^>]*?Name="([^"]*)"', tia) == ["Подача", "Цех", "ЖУК", "注水"]
    back = import_chart(tia.encode(), "t.xml").chart
    assert [s.name for s in back.all_steps()] == ["Подача", "Цех", "ЖУК", "注水"]


@pytest.mark.parametrize("path", [*EXAMPLES, SIX, DB_READS], ids=lambda p: p.stem)
def test_plcopen_export_has_what_the_tc6_schema_requires(path: Path) -> None:
    """The TC6 v2.01 schema's rules other tools check a file against: a divergence,
    convergence and jump is placed (``position`` first), an action block's action too
    (``relPosition`` first), a step's and a divergence's outputs are named
    (``formalParameter``), and an SFC transition has no ``name``."""
    import xml.etree.ElementTree as ET

    table = path.with_name("symbols.txt")
    symbols = SymbolTable.from_file(table) if table.is_file() else None
    root = ET.fromstring(export_chart(parse_file(path), "plcopen", symbols))
    ns = "{http://www.plcopen.org/xml/tc6_0201}"
    sfc = root.find(f".//{ns}SFC")
    assert sfc is not None
    placed = ("selectionDivergence", "selectionConvergence", "simultaneousDivergence")
    placed += ("simultaneousConvergence", "jumpStep")
    for el in sfc:
        tag = el.tag.removeprefix(ns)
        if tag in placed:
            assert el[0].tag == f"{ns}position", tag
        if tag in ("step", "selectionDivergence", "simultaneousDivergence"):
            for point in el.iter(f"{ns}connectionPointOut"):
                assert point.get("formalParameter") is not None, tag
        if tag == "transition":
            assert el.get("name") is None
    for action in sfc.iter(f"{ns}action"):
        assert action[0].tag == f"{ns}relPosition"


def _call_chart(row: str, permanent: str = "") -> Chart:
    after = f"PERMANENT AFTER\n  {permanent}\nEND_PERMANENT\n" if permanent else ""
    return parse_chart(
        'FUNCTION_BLOCK "T"\nVAR\n  go : BOOL;\nEND_VAR\nSEQUENCE 1\nINITIAL_STEP S1:\n'
        f"  {row}\nEND_STEP\nSTEP S2: END_STEP\nTRANSITION T1 FROM S1 TO S2 := go;\n"
        f"TRANSITION T2 FROM S2 TO S1 := NOT go;\nEND_SEQUENCE\n{after}END_FUNCTION_BLOCK\n",
        "t.s7g",
    )


@pytest.mark.parametrize(
    ("row", "permanent", "words"),
    [
        ('CALL "TON", DB 10 (IN := go);', "", "the block by name, its instance DB by number"),
        ("CALL SFB 4, DB 10 (IN := go);", "", "the block and its instance DB by number"),
        ('CALL "TON", "T_S1" (IN := go);', "", "the block and its instance DB by name"),
        ("N go;", "CALL FC 2 (x := go);", "the block by number;"),
    ],
)
def test_simaticml_export_says_how_a_call_names_its_block_and_instance_db(
    row: str, permanent: str, words: str
) -> None:
    """X012 says what the call written names by number and what by name: ``CALL "TON", DB
    10`` names the block by name, so "block and instance DB by number" would be wrong."""
    _, problems = export_reported(_call_chart(row, permanent), "simaticml")
    x012 = [d.message for d in problems if d.code == "X012"]
    assert len(x012) == 1 and words in x012[0]
    assert ("rename them there" in x012[0]) == ("number" in words)
