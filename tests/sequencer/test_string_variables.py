"""STRING variables of a chart: a ``STRING[n]`` takes any STRING value — an initial value
(``''`` included) or an assignment — and holds at most its ``n`` characters, as an S7
STRING[n] does (its maximum length in the first byte; S7-SCL cuts a longer value)."""

from __future__ import annotations

from pathlib import Path

from s7graph.sequencer.checks.validate import validate
from s7graph.sequencer.text.parse import parse_chart
from tests.sequencer.helpers import seq, sim_trace, source

NAMED = seq("""
  INITIAL_STEP S1 "a": END_STEP
  STEP S2 "b": S1 N name := 'abcdef'; S1 N plain := 'xyz'; END_STEP
  TRANSITION T1 FROM S1 TO S2 := I0.0;
  TRANSITION T2 FROM S2 TO S1 := FALSE;
""")
VARS = "VAR\n  name : STRING[4] := '';\n  plain : STRING := 'ok';\nEND_VAR"


def test_a_string_of_n_characters_takes_an_empty_initial_value_and_keeps_n_characters(
    tmp_path: Path,
) -> None:
    """``name : STRING[4] := ''`` is accepted by the validator (it was E031); assigned
    'abcdef' it holds 'abcd'; a plain STRING takes its value whole."""
    text = source(NAMED, header=VARS)
    stim = [{"at_ms": 10, "set": {"I0.0": True}}]
    rc, lines = sim_trace(tmp_path, text, stim, cycles=3, watch="name,plain")
    assert rc == 0
    assert lines[0]["values"] == {"name": "", "plain": "ok"}
    assert lines[-1]["active"] == ["S2"]
    assert lines[-1]["values"] == {"name": "abcd", "plain": "xyz"}


def test_an_initial_value_longer_than_its_string_is_a_located_error(tmp_path: Path) -> None:
    """``name : STRING[4] := 'abcdef'`` does not fit: E031 at the value, naming the
    variable (S7-SCL refuses such a declaration too)."""
    text = source(NAMED, header="VAR\n  name : String[4] := 'abcdef';\n  plain : STRING;\nEND_VAR")
    diagnostics = validate(parse_chart(text, "long.s7g"))
    assert [(d.code, d.loc.line) for d in diagnostics] == [("E031", 4)]
    assert "longer than STRING[4] (name)" in diagnostics[0].message
