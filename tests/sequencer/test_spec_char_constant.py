"""A CHAR variable of a chart takes a one-character string constant as its initial value
(``c : CHAR := 'A'``): in S7 ``'A'`` is the CHAR constant (Program Design for S7-300/400,
appendix C); a longer string does not fit a CHAR (E031)."""

from __future__ import annotations

from pathlib import Path

from s7graph.sequencer.checks.validate import validate
from s7graph.sequencer.text.parse import parse_chart
from tests.sequencer.helpers import seq, sim_trace, source

STEPS = seq("""
  INITIAL_STEP S1 "a": END_STEP
  STEP S2 "b": END_STEP
  TRANSITION T1 FROM S1 TO S2 := I0.0;
""")


def test_a_char_variable_takes_a_one_character_string_as_its_initial_value(
    tmp_path: Path,
) -> None:
    text = source(STEPS, header="VAR c : CHAR := 'A'; q : CHAR := '$''; END_VAR")
    rc, lines = sim_trace(tmp_path, text, [], cycles=1, watch="c,q")
    assert rc == 0
    assert lines[0]["values"] == {"c": "A", "q": "'"}


def test_a_longer_string_does_not_fit_a_char() -> None:
    text = source(STEPS, header="VAR c : CHAR := 'AB'; END_VAR")
    codes = [d.code for d in validate(parse_chart(text, "char.s7g")) if d.severity == "error"]
    assert codes == ["E031"]
