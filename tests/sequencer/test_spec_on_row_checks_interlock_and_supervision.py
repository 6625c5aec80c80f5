"""docs/semantics.md, "Interlock", "Supervision" and "Decisions": a step an `ON Sx` row activates
while the rows of its own sequencer run — an S1 or an S0 row of another step of it — has its
interlock and supervision checked at once, before its rows: L1 and V1 come in its activation
call when the interlock does not hold or the fault is there, its rows marked C do not run, and
`ERROR`/`FAULT` say so in that call (S7-GRAPH manual 13-14, 13-24, 14-8).

Driven through the real cycle (``GraphRuntime``), on the fast path and on the general path
(``fast=False``), 10 ms per call.
"""

from __future__ import annotations

import pytest

from s7graph.steps.qualifiers import EV_L1
from tests.sequencer.helpers import Run, chart_on_path, seq

_CHART = seq("""
  INITIAL_STEP S1 "a": END_STEP
  STEP S2 "b": S1 ON S5; S0 ON S6; END_STEP
  STEP S3 "c": END_STEP
  STEP S5 "e": INTERLOCK := I0.7; SUPERVISION := I0.5;
    N C Q0.5; L1 N Q0.6; S1 S C M0.0; V1 N Q0.7; END_STEP
  STEP S6 "f": INTERLOCK := I0.7; SUPERVISION := I0.5;
    N C Q1.5; L1 N Q1.6; S1 S C M1.0; V1 N Q1.7; END_STEP
  TRANSITION T1 FROM S1 TO S2 := I0.0;
  TRANSITION T2 FROM S2 TO S3 := I0.1;
""")


def _run(fast: bool) -> Run:
    run = chart_on_path(_CHART, fast)
    run.set(I0_5=True).call()
    return run


@pytest.mark.parametrize("fast", [True, False])
def test_a_step_an_s1_on_row_activates_is_checked_in_its_activation_call(fast: bool) -> None:
    """S2's `S1 ON S5`: S5 enters with its interlock lost and its fault there — L1 and V1 in
    that call, its `N C` and `S1 S C` rows held back."""
    run = _run(fast)
    run.set(I0_0=True).call()
    assert run.active == [2, 5]
    assert {"S1", "L1", "V1"} <= run.events(5)
    assert run.get("Q0.6") is True and run.get("Q0.7") is True
    assert run.get("Q0.5") is False and run.get("M0.0") is False
    assert run.st.error and run.st.fault and run.out("ERR_FLT") is True
    run.call()
    assert run.events(5) == set() and run.get("Q0.6") is False and run.get("Q0.5") is False


@pytest.mark.parametrize("fast", [True, False])
def test_a_step_an_s0_on_row_activates_is_checked_in_its_activation_call(fast: bool) -> None:
    """S2's `S0 ON S6` (its final scan): the same for S6, in the call that leaves S2."""
    run = _run(fast)
    run.set(I0_0=True).call()
    run.set(I0_0=False, I0_1=True).call()
    assert run.active == [3, 5, 6]
    assert {"S1", "L1", "V1"} <= run.events(6)
    assert run.get("Q1.6") is True and run.get("Q1.7") is True
    assert run.get("Q1.5") is False and run.get("M1.0") is False


@pytest.mark.parametrize("fast", [True, False])
def test_a_step_an_on_row_activates_with_its_interlock_held_runs_its_c_rows(fast: bool) -> None:
    """With the interlock held and no fault, S5 runs its rows marked C in its activation call,
    without L1 or V1."""
    run = chart_on_path(_CHART, fast)
    run.set(I0_7=True).call()
    run.set(I0_0=True).call()
    assert run.active == [2, 5]
    assert run.events(5) == {"S1"}
    assert run.get("Q0.5") is True and run.get("M0.0") is True
    assert run.out("ERR_FLT") is False


@pytest.mark.parametrize("fast", [True, False])
def test_a_step_the_final_scan_of_the_only_active_step_switches_on_is_checked(fast: bool) -> None:
    """S2 alone, without interlock or supervision, leaves for S3 and its `S0 ON S6` switches
    S6 on: L1 and V1 in that call, the C rows held back, ERR_FLT at once."""
    run = chart_on_path(
        seq("""
  INITIAL_STEP S1 "a": END_STEP
  STEP S2 "b": S0 ON S6; END_STEP
  STEP S3 "c": END_STEP
  STEP S6 "f": INTERLOCK := I0.7; SUPERVISION := I0.5;
    N C Q1.5; L1 N Q1.6; S1 S C M1.0; V1 N Q1.7; END_STEP
  TRANSITION T1 FROM S1 TO S2 := I0.0;
  TRANSITION T2 FROM S2 TO S3 := I0.1;
"""),
        fast,
    )
    run.set(I0_5=True).call()
    run.set(I0_0=True).call()
    run.set(I0_0=False, I0_1=True).call()
    assert run.active == [3, 6]
    assert run.events(6) == {"S1", "L1", "V1"}
    assert run.get("Q1.6") is True and run.get("Q1.7") is True
    assert run.get("Q1.5") is False and run.get("M1.0") is False
    assert run.out("ERR_FLT") is True


@pytest.mark.parametrize("fast", [True, False])
def test_a_step_switched_on_by_a_final_scan_of_step_2_raises_l1_once(fast: bool) -> None:
    """OFF_SQ switches S2 off in step 2 of the call, its `S0 ON S6` switches S6 on: S6 is
    checked once, in step 4.4 of that call — one L1 in the call's events."""
    run = chart_on_path(
        seq("""
  INITIAL_STEP S1 "a": END_STEP
  STEP S2 "b": S0 ON S6; END_STEP
  STEP S6 "f": INTERLOCK := I0.7; N C Q1.5; L1 N Q1.6; END_STEP
  TRANSITION T1 FROM S1 TO S2 := I0.0;
"""),
        fast,
    )
    run.call()
    run.set(I0_0=True).call()
    run.set(I0_0=False, OFF_SQ=True).call()
    assert run.active == [6] and "L1" in run.events(6)
    assert run.get("Q1.6") is True and run.get("Q1.5") is False
    assert run.st.log.count((run.idx(6), EV_L1)) == 1
