"""docs/semantics.md, "One FB call", step 4.1 and "Decisions": ``Tn.TT`` says that a *valid*
transition (all its preceding steps active) is satisfied. A transition whose preceding step was
left — by its own switching, by another transition, by ``S_OFF`` — is no longer valid and reads 0
from the next call on, whatever its condition; in the call it switched it still reads 1.

Driven through the real cycle (``GraphRuntime``), on the fast path and on the general path
(``fast=False``), 10 ms per call.
"""

from __future__ import annotations

import pytest

from tests.sequencer.helpers import Run, chart_on_path, seq


def _tt(run: Run, number: int) -> bool:
    return run.st.tt[run.cc.transition_index[number]]


def _loop() -> str:
    return seq("""
  INITIAL_STEP S1 "a": END_STEP
  STEP S2 "b": END_STEP
  STEP S3 "c": END_STEP
  TRANSITION T1 FROM S1 TO S2 := I0.0;
  TRANSITION T2 FROM S2 TO S3 := I0.1;
  TRANSITION T3 FROM S3 TO S1 := I0.2;
""")


@pytest.mark.parametrize("fast", [True, False])
def test_a_transition_that_switched_reads_satisfied_in_that_call_only(fast: bool) -> None:
    """T1 switches with I0.0 still held: T1.TT is 1 in that call, 0 in the next ones."""
    run = chart_on_path(_loop(), fast)
    run.call()
    run.set(I0_0=True).call()
    assert run.active == [2] and _tt(run, 1) is True
    run.call(2)
    assert run.active == [2] and _tt(run, 1) is False


@pytest.mark.parametrize("fast", [True, False])
def test_an_alternative_path_not_taken_reads_unsatisfied_once_its_step_is_left(fast: bool) -> None:
    """S1 has T1 (to S2) and T4 (to S3), both holding: T1 wins, both read 1 in that call, and
    T4 — no longer valid — reads 0 from the next call on."""
    run = chart_on_path(
        seq("""
  INITIAL_STEP S1 "a": END_STEP
  STEP S2 "b": END_STEP
  STEP S3 "c": END_STEP
  TRANSITION T1 FROM S1 TO S2 := I0.0;
  TRANSITION T4 FROM S1 TO S3 := I0.0;
  TRANSITION T2 FROM S2 TO S1 := I0.1;
  TRANSITION T3 FROM S3 TO S1 := I0.1;
"""),
        fast,
    )
    run.call()
    run.set(I0_0=True).call()
    assert run.active == [2] and _tt(run, 1) is True and _tt(run, 4) is True
    run.call()
    assert _tt(run, 4) is False and _tt(run, 1) is False


def test_a_step_switched_off_in_man_leaves_its_transition_unsatisfied() -> None:
    """In MAN nothing switches but valid transitions are still evaluated: T2.TT is 1 while S2
    is active; once S_OFF deactivates S2 it reads 0."""
    run = chart_on_path(_loop(), False)
    run.call()
    run.set(I0_0=True).call()
    run.set(I0_0=False, I0_1=True)
    run.pulse("SW_MAN")
    assert run.active == [2] and _tt(run, 2) is True
    run.set(S_SEL=2)
    run.pulse("S_OFF")
    run.call()
    assert run.active == [] and _tt(run, 2) is False
