"""The contacts *Details* offers to *Modify to 1/0* (web/view/contact_modify.py): the bit
operands of a step's outgoing transitions, interlock and supervision, or of one
transition's condition, each once, in the order they stand; no comparison, no step or
transition attribute, no word."""

from __future__ import annotations

from s7graph.sequencer.compile import compile_chart
from s7graph.sequencer.text.parse import parse_chart
from s7graph.web.bus.live import prepare_chart
from s7graph.web.bus.protocol import ChartLayout
from s7graph.web.view.contact_modify import contact_operands

CHART = """\
FUNCTION_BLOCK "Plant" FB 1 DB 1
SYMBOLS
  "Start" : I0.0 : BOOL;
  "Door" : I0.2 : BOOL;
  "Level" : MW20 : INT;
END_SYMBOLS
SEQUENCE 1 "Fill"
  INITIAL_STEP S1 "Idle":
  END_STEP
  STEP S2 "Fill":
    INTERLOCK := "Door" AND DB20.DBX0.1;
    SUPERVISION := S2.T > T#10S OR M10.1;
  END_STEP
  STEP S3 "Drain":
  END_STEP
  TRANSITION T1 "Go" FROM S1 TO S2 := "Start";
  TRANSITION T2 "Full" FROM S2 TO S3 := "Level" > 50 AND NOT "Start" AND Q4.0;
  TRANSITION T3 "Empty" FROM S2 TO S1 := T2.TT OR "Door";
  TRANSITION T4 "Back" FROM S3 TO S1 := S2.X OR I0.7;
END_SEQUENCE
END_FUNCTION_BLOCK
"""


def _layout() -> ChartLayout:
    cc = compile_chart(parse_chart(CHART, "plant.s7g"))
    return prepare_chart(cc, fb="Plant", version=1).layout


def test_a_steps_contacts_are_its_transitions_then_its_interlock_and_supervision() -> None:
    layout = _layout()
    assert contact_operands(layout, ("S", 2)) == [
        '"Start"',
        "Q4.0",
        '"Door"',
        "DB20.DBX0.1",
        "M10.1",
    ]
    assert contact_operands(layout, ("S", 1)) == ['"Start"']
    assert contact_operands(layout, ("S", 3)) == ["I0.7"]  # not S2.X


def test_a_transitions_contacts_are_its_conditions_bits() -> None:
    layout = _layout()
    assert contact_operands(layout, ("T", 2)) == ['"Start"', "Q4.0"]  # not "Level" > 50
    assert contact_operands(layout, ("T", 3)) == ['"Door"']  # not T2.TT
    assert contact_operands(layout, ("T", 9)) == [] and contact_operands(layout, ("S", 0)) == []
