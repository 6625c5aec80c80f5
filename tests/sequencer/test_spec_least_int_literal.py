"""``-32768`` is an INT constant, the least INT (S7's integer constants run from -32768 to
+32767; Program Design for S7-300/400, appendix C): it initializes an INT variable, is
assigned to one and compares with one. Its digits alone, ``32768``, are beyond INT, and a
prefixed ``L#32768`` stays a DINT when negated."""

from __future__ import annotations

from pathlib import Path

from s7graph.sequencer.checks.validate import validate
from s7graph.sequencer.text.parse import parse_chart
from tests.sequencer.helpers import seq, sim_trace, source

STEPS = seq("""
  INITIAL_STEP S1 "a": END_STEP
  STEP S2 "b": S1 N m := -32768; END_STEP
  STEP S3 "c": END_STEP
  TRANSITION T1 FROM S1 TO S2 := m > -32768 AND I0.0;
  TRANSITION T2 FROM S2 TO S3 := m = -32768;
""")


def test_minus_32768_is_the_least_int_constant(tmp_path: Path) -> None:
    text = source(STEPS, header="VAR m : INT := -32767; n : INT := -32768; END_VAR")
    stimulus = [{"at_ms": 10, "set": {"I0.0": True}}]
    rc, lines = sim_trace(tmp_path, text, stimulus, cycles=4, watch="m,n")
    assert rc == 0
    assert [line["active"] for line in lines] == [["S1"], ["S2"], ["S3"], ["S3"]]
    assert lines[1]["values"] == {"m": -32768, "n": -32768}


def test_a_negated_dint_constant_stays_a_dint() -> None:
    text = source(STEPS, header="VAR m : INT := L#-32768; END_VAR").replace(
        "S1 N m := -32768;", "S1 N m := -L#32768;"
    )
    codes = [d.code for d in validate(parse_chart(text, "int.s7g")) if d.severity == "error"]
    assert codes == ["E031", "E031"]
