"""docs/semantics.md, "Decisions" (a chart writing its own input pin): an FB input pin lives
in the instance DB, so a row or permanent instruction that writes one (``S1 S SW_MAN``,
``OFF_SQ := I0.6``) writes it there, as S7-GRAPH lets an action set the mode bits (manual
15-18: "By setting MOP.MAN once, the mode changes to MANUAL … controlled by the program (for
example action in the sequencer)"); the FB's next call latches it like a value its caller
wrote — an edge counts — and a value the caller writes later wins.

Through ``s7graph sim`` (the black-box contract), 10 ms per cycle."""

from __future__ import annotations

from pathlib import Path

from tests.sequencer.helpers import seq, sim_trace, source

MODE = source(
    seq("""
  INITIAL_STEP S1 "wait":
  END_STEP
  STEP S2 "to manual":
    S1 S SW_MAN;
  END_STEP
  TRANSITION T1 FROM S1 TO S2 := I0.0;
  TRANSITION T2 FROM S2 TO S1 := I0.1;
"""),
    params="STANDARD",
)

OFF = source(
    seq("""
  INITIAL_STEP S1 "run":
    N Q0.0;
  END_STEP
  TRANSITION T1 FROM S1 TO S1 := FALSE;
"""),
    header="PERMANENT BEFORE\n  OFF_SQ := I0.6;\nEND_PERMANENT\n",
    params="STANDARD",
)


def test_a_row_that_sets_sw_man_selects_manual_at_the_next_call(tmp_path: Path) -> None:
    stim = [{"at_ms": 10, "set": {"I0.0": True}}]
    rc, lines = sim_trace(tmp_path, MODE, stim, cycles=4, watch="SW_MAN,MAN_ON")
    assert rc == 0
    assert [line["mode"] for line in lines] == ["AUTO", "AUTO", "MAN", "MAN"]
    assert lines[1]["values"] == {"SW_MAN": True, "MAN_ON": False}  # in the instance DB
    assert lines[2]["values"]["MAN_ON"] is True


def test_a_value_the_caller_writes_later_wins(tmp_path: Path) -> None:
    stim = [
        {"at_ms": 10, "set": {"I0.0": True}},
        {"at_ms": 30, "set": {"SW_MAN": False, "SW_AUTO": True}},
    ]
    rc, lines = sim_trace(tmp_path, MODE, stim, cycles=5, watch="SW_MAN")
    assert rc == 0
    assert [line["mode"] for line in lines] == ["AUTO", "AUTO", "MAN", "AUTO", "AUTO"]
    assert lines[-1]["values"]["SW_MAN"] is False


def test_a_permanent_instruction_writing_off_sq_switches_the_sequencer_off(
    tmp_path: Path,
) -> None:
    stim = [{"at_ms": 20, "set": {"I0.6": True}}, {"at_ms": 50, "set": {"I0.6": False}}]
    rc, lines = sim_trace(tmp_path, OFF, stim, cycles=7, watch="OFF_SQ,Q0.0")
    assert rc == 0
    # written in cycle 2's permanent instruction, latched by cycle 3's call; the sequencer
    # stays off when OFF_SQ goes (INIT_SQ starts it again)
    assert [line["active"] for line in lines] == [["S1"]] * 3 + [[]] * 4
    assert [line["values"]["Q0.0"] for line in lines] == [True] * 3 + [False] * 4
    assert lines[4]["values"]["OFF_SQ"] is True and lines[6]["values"]["OFF_SQ"] is False
