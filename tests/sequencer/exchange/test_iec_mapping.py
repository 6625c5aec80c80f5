"""IEC qualifiers and constructs map to GRAPH where an exact equivalent exists and are otherwise
reported at their place (``exchange.mapping``, the table of docs/import-export.md)."""

from __future__ import annotations

from pathlib import Path

import pytest

from s7graph.sequencer.exchange import import_chart
from s7graph.sequencer.exchange.mapping import CONSTRUCTS, QUALIFIERS, markdown_tables
from s7graph.sequencer.text.format import format_chart, format_row
from s7graph.sequencer.text.model import Chart
from tests.paths import DOCS
from tests.sequencer.exchange.helpers import codes, sim

DOC = DOCS / "import-export.md"


def program(body: str, decls: str = "x : BOOL; y : BOOL; n : INT;") -> bytes:
    return (
        f"PROGRAM P\nVAR {decls} END_VAR\nINITIAL_STEP A:\nEND_STEP\n{body}\n"
        "TRANSITION FROM A TO B := x; END_TRANSITION\n"
        "TRANSITION FROM B TO A := NOT x; END_TRANSITION\nEND_PROGRAM\n"
    ).encode()


def rows_of(chart: Chart, step: str) -> list[str]:
    s = next(s for s in chart.all_steps() if s.name == step)
    return [format_row(r) for r in s.actions]


@pytest.mark.parametrize(
    ("association", "row"),
    [
        ("y(N)", "N y;"),
        ("y(S)", "S y;"),
        ("y(R)", "R y;"),
        ("y(P)", "S1 N y;"),
        ("y(P1)", "S1 N y;"),
        ("y(D, T#2s)", "D y, T#2s;"),
        ("y(L, T#500ms)", "L y, T#500ms;"),
    ],
)
def test_boolean_action_variable_maps_to_its_graph_row(association: str, row: str) -> None:
    result = import_chart(program(f"STEP B: {association}; END_STEP"), "p.st")
    assert rows_of(result.chart, "B") == [row]
    assert result.problems == []


@pytest.mark.parametrize("qualifier", ["P0", "SD, T#1s", "DS, T#1s", "SL, T#1s"])
def test_qualifier_without_equivalent_on_a_variable_is_reported_at_its_line(qualifier: str) -> None:
    result = import_chart(program(f"STEP B:\n y({qualifier});\nEND_STEP"), "p.st")
    assert rows_of(result.chart, "B") == []
    assert codes(result.problems) == [("I020", 6)]


def test_st_body_statements_become_rows_or_gated_permanent_coils() -> None:
    body = (
        "STEP B: ACT(N); END_STEP\nACTION ACT:\n y := TRUE;\n n := n + 1;\n"
        " x := y AND NOT x;\nEND_ACTION"
    )
    result = import_chart(program(body), "p.st")
    assert rows_of(result.chart, "B") == ["S y;", "N n := n + 1;"]
    assert "x := S2.X AND y AND NOT x OR NOT S2.X AND x;" in format_chart(result.chart)
    assert [d.code for d in result.problems] == ["I031"]  # rows and coils: order may differ


def test_a_pulse_body_assigning_a_bit_is_gated_by_a_one_call_pulse(tmp_path: Path) -> None:
    """``P`` runs a body once, in the call its step becomes active: ``S1 N B_P1`` is that
    call's pulse, and PERMANENT AFTER assigns the bit only then."""
    body = "STEP B: ACT(P); END_STEP\nACTION ACT:\n y := NOT y;\nEND_ACTION"
    result = import_chart(program(body), "p.st")
    assert rows_of(result.chart, "B") == ["S1 N B_P1;"]
    chart = tmp_path / "p.s7g"
    chart.write_text(format_chart(result.chart))
    records = sim(
        tmp_path, chart, watch=["y"], cycles=6, stimulus=[{"at_ms": 10, "set": {"x": True}}]
    )
    assert [r["values"]["y"] for r in records] == [False, True, True, True, True, True]


def test_a_call_of_a_block_the_import_does_not_map_is_reported_where_it_is() -> None:
    body = "STEP B: ACT(N); END_STEP\nACTION ACT:\n y := x;\n E1(CLK := x);\nEND_ACTION"
    result = import_chart(program(body, "x : BOOL; y : BOOL; E1 : LOGGER;"), "p.st")
    assert [(d.code, d.loc.line, d.loc.col) for d in result.problems] == [
        ("I023", 2, 25),
        ("I021", 8, 2),
    ]
    assert "call of E1 : LOGGER not imported" in result.problems[1].message


def test_an_iec_timer_called_in_an_action_is_a_call_of_its_system_block(tmp_path: Path) -> None:
    """``T1(IN := x, PT := T#50ms)`` in an N action is ``CALL SFB 4, DB 100`` with its
    outputs in FB variables, so ``T1.Q`` in a transition switches when the time is up;
    a counter called in the POU body is a permanent call, with a DB of its own."""
    text = (
        "PROGRAM P\nVAR x : BOOL; T1 : TON; C1 : CTU; END_VAR\n"
        "C1(CU := x, PV := 3);\n"
        "INITIAL_STEP A:\nEND_STEP\nSTEP B: WAIT(N); END_STEP\nSTEP C:\nEND_STEP\n"
        "ACTION WAIT:\n T1(IN := TRUE, PT := T#50ms);\nEND_ACTION\n"
        "TRANSITION FROM A TO B := x; END_TRANSITION\n"
        "TRANSITION FROM B TO C := T1.Q; END_TRANSITION\n"
        "TRANSITION FROM C TO A := NOT x; END_TRANSITION\nEND_PROGRAM\n"
    )
    result = import_chart(text.encode(), "p.st")
    assert rows_of(result.chart, "B") == [
        "CALL SFB 4, DB 100 (IN := TRUE, PT := T#50ms, Q => T1_Q, ET => T1_ET);"
    ]
    written = format_chart(result.chart)
    assert "CALL SFB 0, DB 101 (CU := x, PV := 3, Q => C1_Q, CV => C1_CV);" in written
    assert [d.code for d in result.problems] == ["I031", "I031"]  # called as SFB n, DB m
    # the action's call has no final execution in GRAPH; the body's needs none
    assert ["once more" in d.message for d in result.problems] == [True, False]
    chart = tmp_path / "p.s7g"
    chart.write_text(written)
    records = sim(
        tmp_path, chart, watch=["C1_CV"], cycles=12, stimulus=[{"at_ms": 10, "set": {"x": True}}]
    )
    active = [r["active"] for r in records]
    assert active[1] == ["S2"] and active[6] == ["S2"] and active[7] == ["S3"]
    assert records[-1]["values"]["C1_CV"] == 1


def test_priority_orders_the_paths_of_an_alternative() -> None:
    text = (
        b"PROGRAM P\nVAR x : BOOL; END_VAR\nINITIAL_STEP A: END_STEP\nSTEP B: END_STEP\n"
        b"STEP C: END_STEP\nTRANSITION (PRIORITY := 2) FROM A TO B := x; END_TRANSITION\n"
        b"TRANSITION (PRIORITY := 1) FROM A TO C := x; END_TRANSITION\nEND_PROGRAM\n"
    )
    chart = import_chart(text, "p.st").chart
    assert [t.targets for t in chart.all_transitions()] == [(3,), (2,)]


def test_located_variables_are_symbols_unless_s7_would_change_them() -> None:
    text = (
        b"PROGRAM P\nVAR\n a AT %IX0.1 : BOOL;\n q AT %QX0.2 : BOOL := TRUE;\n"
        b" w AT %MW4 : INT;\n i AT %IX1.0 : BOOL;\nEND_VAR\nINITIAL_STEP A: END_STEP\n"
        b"STEP B: i(S); END_STEP\nTRANSITION FROM A TO B := a AND q AND w > 0; "
        b"END_TRANSITION\nEND_PROGRAM\n"
    )
    result = import_chart(text, "p.st")
    assert [(s.name, s.address, s.type) for s in result.chart.symbols] == [
        ("a", "I0.1", "BOOL"),
        ("w", "MW4", "INT"),
    ]
    assert [v.name for v in result.chart.vars] == ["q", "i"]
    assert codes(result.problems) == [("I023", 4), ("I023", 6)]


def test_names_graph_reserves_are_renamed_and_reported() -> None:
    text = (
        b"PROGRAM P\nVAR STOP : BOOL; S_NO : INT; END_VAR\nINITIAL_STEP A: END_STEP\n"
        b"STEP B: END_STEP\nTRANSITION FROM A TO B := STOP AND S_NO > 1; END_TRANSITION\n"
        b"END_PROGRAM\n"
    )
    result = import_chart(text, "p.st")
    assert [v.name for v in result.chart.vars] == ["STOP_", "S_NO_"]
    assert "STOP_ AND S_NO_ > 1" in format_chart(result.chart)
    assert [d.code for d in result.problems] == ["I030", "I030"]


CODESYS = b"""<?xml version="1.0" encoding="utf-8"?>
<project xmlns="http://www.plcopen.org/xml/tc6_0200">
  <fileHeader companyName="CODESYS Development GmbH" productName="CODESYS" productVersion="3.5"
              creationDateTime="2024-01-01T00:00:00"/>
  <contentHeader name="demo"><coordinateInfo><fbd><scaling x="1" y="1"/></fbd>
    <ld><scaling x="1" y="1"/></ld><sfc><scaling x="1" y="1"/></sfc></coordinateInfo>
  </contentHeader>
  <types><dataTypes/><pous>
    <pou name="Seq" pouType="program">
      <interface><localVars>
        <variable name="go"><type><BOOL/></type></variable>
        <variable name="n"><type><INT/></type></variable>
        <variable name="lamp"><type><BOOL/></type></variable>
      </localVars></interface>
      <actions>
        <action name="Enter"><body><ST>
          <xhtml:p xmlns:xhtml="http://www.w3.org/1999/xhtml">n := n + 1;</xhtml:p>
        </ST></body></action>
        <action name="Busy"><body><ST>lamp := TRUE;</ST></body></action>
        <action name="Leave"><body><ST>lamp := FALSE;</ST></body></action>
      </actions>
      <body><SFC>
        <step localId="0" initialStep="true" name="Init">
          <connectionPointOut formalParameter="sfc"/>
        </step>
        <inVariable localId="1"><expression>go</expression></inVariable>
        <transition localId="2">
          <connectionPointIn><connection refLocalId="0" formalParameter="sfc"/></connectionPointIn>
          <condition><connectionPointIn><connection refLocalId="1"/></connectionPointIn></condition>
        </transition>
        <step localId="3" name="Work">
          <connectionPointIn><connection refLocalId="2"/></connectionPointIn>
          <addData><data name="http://www.3s-software.com/plcopenxml/sfc/element"
                         handleUnknown="implementation">
            <attributes>
              <attribute guid="a6b08bd8-b696-47e3-9cbf-7408b61c9ff8">Enter</attribute>
              <attribute guid="700a583f-b4d4-43e4-8c14-629c7cd3bec8">Busy</attribute>
              <attribute guid="a2621e18-7de3-4ea6-ae6d-89e9e0b7befd">Leave</attribute>
            </attributes></data></addData>
        </step>
        <inVariable localId="4"><expression>NOT go</expression></inVariable>
        <transition localId="5">
          <connectionPointIn><connection refLocalId="3"/></connectionPointIn>
          <condition><connectionPointIn><connection refLocalId="4"/></connectionPointIn></condition>
        </transition>
        <jumpStep localId="6" targetName="Init">
          <connectionPointIn><connection refLocalId="5"/></connectionPointIn>
        </jumpStep>
      </SFC></body>
    </pou>
  </pous></types>
</project>
"""


def test_codesys_step_actions_and_evaluation_order() -> None:
    """CODESYS entry, active and exit actions are S1 rows, rows and S0 rows; a CODESYS file
    imports with ``ORDER := CODESYS`` (CODESYS runs the actions of the active steps before
    it tests the transitions, so a new step acts in the next call)."""
    result = import_chart(CODESYS, "seq.xml")
    chart = result.chart
    assert chart.options.order == "codesys"
    assert rows_of(chart, "Work") == ["S1 N n := n + 1;", "S lamp;", "S0 R lamp;"]
    assert [(t.sources, t.targets) for t in chart.all_transitions()] == [((1,), (2,)), ((2,), (1,))]
    assert result.problems == []


def test_the_import_export_doc_table_is_the_mapping_table() -> None:
    assert markdown_tables() in DOC.read_text(encoding="utf-8")
    assert set(QUALIFIERS) == {"N", "S", "R", "P", "P1", "P0", "D", "L", "SD", "DS", "SL"}


def test_the_construct_table_covers_every_format_both_ways() -> None:
    """One table in code says, for every format read and written, what each construct
    becomes or why it is refused — each row a format, a construct and an outcome."""
    formats = {row[0] for row in CONSTRUCTS}
    assert formats == {
        "IEC",
        "PLCopen",
        "IEC text",
        "SimaticML",
        "export → PLCopen",
        "export → SimaticML",
    }
    assert all(fmt and construct and becomes for fmt, construct, becomes, _ in CONSTRUCTS)
