"""docs/semantics.md, "Actions": in an assignment `NOT` of an INT or a DINT is its one's
complement (the type check's rule: NOT of INT is INT, of DINT is DINT), never a BOOL written
into the number; `NOT` of a bit, a timer or a counter stays the negated contact."""

from __future__ import annotations

from pathlib import Path

from tests.sequencer.helpers import seq, sim_trace, source

CHART = source(
    seq("""
  INITIAL_STEP S1 "a": S1 TL T 1, S5T#30MS; END_STEP
  STEP S2 "b": S1 N r1 := NOT i; S1 N r2 := NOT d; S1 N r3 := NOT (i + 1); END_STEP
  TRANSITION T1 FROM S1 TO S2 := NOT T1 AND NOT C1 AND NOT (I0.2 OR I0.3);
"""),
    header="VAR i : INT := 5; d : DINT := L#-1; r1 : INT; r2 : DINT := 1; r3 : INT; END_VAR",
)


def test_not_of_an_int_or_a_dint_is_its_ones_complement(tmp_path: Path) -> None:
    rc, lines = sim_trace(tmp_path, CHART, [], cycles=5, watch="r1,r2,r3,T1")
    assert rc == 0
    assert [line["values"]["T1"] for line in lines[:3]] == [True, True, True]
    assert lines[3]["active"] == ["S2"]  # NOT T1 is the timer's status bit negated
    assert lines[3]["values"] == {"r1": -6, "r2": 0, "r3": -7, "T1": False}
