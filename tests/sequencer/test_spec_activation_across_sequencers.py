"""docs/semantics.md, "Decisions", row "activation from an earlier sequencer": a step that a jump
or an ``ON Sx`` of an earlier sequencer activates in this call is active for the whole call,
as a step INIT_SQ activates — its transitions are evaluated and switch in the next call
at the earliest, so its S1 rows and its N rows run and it is never left unseen (with skip
steps off, S7-GRAPH keeps every step active for at least one cycle).

Driven through the real cycle (``GraphRuntime``), on the fast path and on the general path
(``fast=False``), 10 ms per call.
"""

from __future__ import annotations

import pytest

from tests.sequencer.helpers import Run, chart_on_path, seq

_FIRST = """
  INITIAL_STEP S1 "a": END_STEP
  STEP S2 "b": S1 ON S12; END_STEP
  TRANSITION T1 FROM S1 TO S2 := I0.0;
  TRANSITION T2 FROM S2 TO S13 := I0.0;
"""
_SECOND = """
  INITIAL_STEP S11 "x": END_STEP
  STEP S12 "y": N Q1.2; S1 S M1.2; END_STEP
  STEP S13 "z": N Q1.3; S1 S M1.3; END_STEP
  STEP S14 "w": N Q1.4; END_STEP
  TRANSITION T11 FROM S11 TO S14 := FALSE;
  TRANSITION T12 FROM S12 TO S14 := I0.0;
  TRANSITION T13 FROM S13 TO S14 := I0.0;
  TRANSITION T14 FROM S14 TO STOP := FALSE;
"""


def _run(fast: bool) -> Run:
    return chart_on_path(seq(_FIRST) + seq(_SECOND, 2), fast)


@pytest.mark.parametrize("fast", [True, False])
def test_a_step_an_earlier_sequencer_switches_on_stays_for_the_call_and_runs_its_rows(
    fast: bool,
) -> None:
    """S2's ``S1 ON S12`` activates S12 in the second sequencer while T12 already holds:
    S12 is active for that call (its N and S1 rows run, T12.TT shows), and leaves in the
    next."""
    run = _run(fast)
    run.call()
    run.set(I0_0=True).call()
    assert run.active == [2, 11, 12]
    assert run.get("Q1.2") is True and run.get("M1.2") is True
    assert run.st.tt[run.cc.transition_index[12]]
    run.call()
    assert 12 not in run.active and 14 in run.active


@pytest.mark.parametrize("fast", [True, False])
def test_a_jump_into_a_later_sequencer_keeps_its_target_active_for_the_call(fast: bool) -> None:
    """T2 jumps from S2 to S13 of the second sequencer, whose T13 already holds: S13 runs
    its rows in that call and switches to S14 in the next."""
    run = _run(fast)
    run.call()
    run.set(I0_0=True).call()
    run.call()  # T2: S2 -> S13; T12: S12 -> S14
    assert run.active == [11, 13, 14]
    assert run.get("Q1.3") is True and run.get("M1.3") is True
    run.call()
    assert run.active == [11, 14] and run.get("Q1.3") is False
