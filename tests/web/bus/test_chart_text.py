"""What the CPU tells a view about a chart beyond its boxes and bars
(``web.bus.chart_text``): each step's action table as S7-GRAPH shows it, and where each
contact of every condition stands in its text — in the order of the CRIT bits, so the view
colours the contact the CPU evaluated."""

from __future__ import annotations

from pathlib import Path

import pytest

from s7graph.sequencer.compile import compile_chart
from s7graph.sequencer.text.parse import parse_chart
from s7graph.web.bus.chart_text import contact_spans
from s7graph.web.bus.live import prepare_chart
from s7graph.web.bus.protocol import ChartLayout, StepStateUpdate, condition_text
from s7graph.web.harness.session import ChartLoadError, load_chart
from s7graph.web.view.texts import permanent_html
from tests.paths import ROOT

pytestmark = pytest.mark.timeout(60)

CHARTS = sorted((ROOT / "examples").glob("*/*.s7g")) + sorted(
    (ROOT / "tests" / "sequencer").glob("[cs]*/*.s7g")  # charts/, scenarios/
)


@pytest.mark.parametrize("path", CHARTS, ids=lambda p: p.name)
def test_every_contact_stands_where_its_crit_bit_says(path: Path) -> None:
    symbols = path.parent / "symbols.txt"
    try:
        cc, _ = load_chart(path, symbols if symbols.is_file() else None)
    except ChartLoadError:
        pytest.skip("a chart that needs other symbols to compile")
    chart = cc.chart
    conditions = [t.condition for t in chart.all_transitions()]
    labels = list(cc.crit_labels)
    conditions += [s.interlock for s in chart.all_steps()] + [
        s.supervision for s in chart.all_steps()
    ]
    labels += list(cc.il_labels) + list(cc.sv_labels)
    for condition, crit in zip(conditions, labels, strict=True):
        text, spans = contact_spans(condition)
        assert text == condition_text(condition)  # the text a view draws
        assert [text[a:b] for a, b in spans] == list(crit)  # each CRIT bit's contact


def test_a_steps_action_table_comes_with_the_values_the_cpu_sends() -> None:
    chart = parse_chart((ROOT / "examples/drill/drill.s7g").read_text(), "drill.s7g")
    layout = ChartLayout.from_chart(chart)
    rows = {
        s.number: [(a.event, a.qualifier, a.operand, a.value, a.watch) for a in s.actions]
        for s in layout.steps
    }
    assert rows[2] == [
        ("S1", "S", '"Clamp_workp"', "", "Clamp_workp"),
        ("S1", "S", '"Dr_mot_on"', "", "Dr_mot_on"),
    ]
    assert rows[5] == [("S1", "N", "pieces := pieces + 1", "", "pieces")]
    s2 = layout.step(2)
    assert s2 is not None and s2.supervision_condition == "S2.U > T#500MS"
    assert s2.supervision_contacts == [(0, 14)]
    drill = ROOT / "examples" / "drill"
    cc, _ = load_chart(drill / "drill.s7g", drill / "symbols.txt")
    live = prepare_chart(cc, fb="Seq_drill", version=1)
    index = live.cc.step_index
    assert live.operands[index[2]] == ("Clamp_workp", "Dr_mot_on")
    assert live.operands[index[1]] == ()


def test_timers_counters_and_step_switches_name_what_the_table_shows() -> None:
    source = """\
FUNCTION_BLOCK "Rows" FB 1 DB 1
  PARAMETERS := STANDARD;
SEQUENCE 1 "Main"
  INITIAL_STEP S1 "One":
    D "Valve", T#2S;
    TD T3, S5T#1S;
    CS C4, C#5;
    NC "Pump";
    S1 ON S2;
    S1 OFF S_ALL;
  END_STEP
  STEP S2 "Two":
  END_STEP
  TRANSITION T1 FROM S1 TO S2 := "Go";
  TRANSITION T2 FROM S2 TO S1 := NOT "Go";
END_SEQUENCE
END_FUNCTION_BLOCK
"""
    step = ChartLayout.from_chart(parse_chart(source, "rows.s7g")).step(1)
    assert step is not None
    assert [(a.event, a.qualifier, a.operand, a.value, a.watch) for a in step.actions] == [
        ("", "D", '"Valve"', "T#2S", "Valve"),
        ("", "TD", "T3", "S5T#1S", "T3"),
        ("", "CS", "C4", "C#5", "C4"),
        ("", "NC", '"Pump"', "", "Pump"),
        ("S1", "ON", "S2", "", "S2.X"),
        ("S1", "OFF", "S_ALL", "", ""),
    ]


PERMANENT = """\
FUNCTION_BLOCK "Perm" FB 1 DB 1
  PARAMETERS := STANDARD;
SYMBOLS
  "Start" : I0.0 : BOOL;
  "Trip" : I0.1 : BOOL;
  "Lamp" : Q0.0 : BOOL;
  "Motor" : Q0.1 : BOOL;
  "Ready" : M0.0 : BOOL;
END_SYMBOLS
VAR
  runs : INT := 0;
END_VAR
PERMANENT BEFORE
  "Ready" := "Start" AND NOT "Trip";
END_PERMANENT
PERMANENT AFTER
  S "Lamp" := "Trip";  R "Motor" := "Trip";
  runs := runs + 1;
  CALL FC 3;
END_PERMANENT
SEQUENCE 1 "Main"
  INITIAL_STEP S1 "Idle":
    N "Motor";
  END_STEP
  STEP S2 "Run":
  END_STEP
  TRANSITION T1 FROM S1 TO S2 := "Ready";
  TRANSITION T2 FROM S2 TO S1 := NOT "Start";
END_SEQUENCE
END_FUNCTION_BLOCK
"""


def test_the_permanent_instructions_come_with_the_operands_they_write() -> None:
    """S7-GRAPH's permanent pre- and post-instructions, as the chart file writes them, those
    before the sequences first; each names the operand it writes (a block call none)."""
    layout = ChartLayout.from_chart(parse_chart(PERMANENT, "perm.s7g"))
    assert [(p.place, p.text, p.watch) for p in layout.permanent] == [
        ("before", '"Ready" := "Start" AND NOT "Trip";', "Ready"),
        ("after", 'S "Lamp" := "Trip";', "Lamp"),
        ("after", 'R "Motor" := "Trip";', "Motor"),
        ("after", "runs := runs + 1;", "runs"),
        ("after", "CALL FC 3;", ""),
    ]
    live = prepare_chart(compile_chart(parse_chart(PERMANENT, "perm.s7g")), fb="Perm", version=1)
    assert live.permanent == ("Ready", "Lamp", "Motor", "runs", "Start", "Trip")


def state_with(values: dict[str, bool | int]) -> StepStateUpdate:
    return StepStateUpdate(cycle=1, t_ms=0, mode="AUTO", active=[1], values=values)


def test_a_permanent_coils_contacts_come_with_the_bits_they_read_and_their_nots() -> None:
    """As TIA Portal's status shows the contacts of the permanent instructions: each coil's
    contacts in order, the bit each reads (the CPU sends its value) and whether a NOT
    inverts it; an assignment and a call have none, a comparison reads no single bit."""
    text = PERMANENT.replace('S "Lamp" := "Trip";', 'S "Lamp" := "Trip" OR runs > 3 OR S2.X;')
    layout = ChartLayout.from_chart(parse_chart(text, "perm.s7g"))
    contacts = [[(c.text, c.watch, c.negated) for c in p.contacts] for p in layout.permanent]
    assert contacts == [
        [('"Start"', "Start", False), ('NOT "Trip"', "Trip", True)],
        [('"Trip"', "Trip", False), ("runs > 3", "", False), ("S2.X", "S2.X", False)],
        [('"Trip"', "Trip", False)],
        [],
        [],
    ]
    shown = permanent_html(layout, state_with({"Start": True, "Trip": True, "S2.X": False}))
    assert "✓</span> &quot;Start&quot;" in shown and "✗</span> NOT &quot;Trip&quot;" in shown
    assert "· runs &gt; 3" in shown and "✗</span> S2.X" in shown
