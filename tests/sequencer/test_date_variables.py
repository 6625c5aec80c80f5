"""A chart's DATE and DATE_AND_TIME variables hold dates: without an initial value the first
the CPU knows (D#1990-01-01, DT#1990-01-01-0:0:0, as S7 starts them), and after their
instance DB went through the state file (which keeps them as ISO text) dates again — so a
block they are passed to (SFC0 SET_CLK) gets a date, never a number or a text."""

from __future__ import annotations

from datetime import date, datetime
from pathlib import Path

import msgspec

from s7graph.sequencer.state import GraphState
from tests.sequencer.helpers import chart, seq, sim_trace, source

CHART = seq("""
  INITIAL_STEP S1 "a": END_STEP
""")
VARS = "VAR when : DATE_AND_TIME; at : DATE_AND_TIME := DT#2000-01-02-03:04:05; day : DATE; END_VAR"


def test_a_date_variable_starts_at_the_first_date_the_cpu_knows() -> None:
    run = chart(CHART, header=VARS)
    run.call()
    assert run.st.vars["when"] == datetime(1990, 1, 1) and run.st.vars["day"] == date(1990, 1, 1)


def test_date_variables_are_dates_again_after_a_snapshot_went_through_the_state_file() -> None:
    run = chart(CHART, header=VARS)
    run.call()
    stored = msgspec.msgpack.decode(msgspec.msgpack.encode(run.st.to_state()))
    assert stored["vars"]["at"] == "2000-01-02T03:04:05"  # as the state file keeps it
    run.rt.rebind(GraphState.from_state(stored))
    run.call()
    assert run.st.vars["at"] == datetime(2000, 1, 2, 3, 4, 5)
    assert run.st.vars["day"] == date(1990, 1, 1)


def test_a_stimulus_sets_a_date_and_refuses_a_text_that_is_none(tmp_path: Path) -> None:
    chart_text = source(CHART, header=VARS)
    stim = [{"at_ms": 0, "set": {"when": "DT#2001-02-03-04:05:06", "day": "2002-03-04"}}]
    rc, lines = sim_trace(tmp_path, chart_text, stim, cycles=1, watch="when,day")
    assert rc == 0
    assert lines[0]["values"] == {"when": "2001-02-03 04:05:06", "day": "2002-03-04"}
    rc, lines = sim_trace(tmp_path, chart_text, [{"at_ms": 0, "set": {"when": "soon"}}], cycles=1)
    assert rc == 2 and lines == []
