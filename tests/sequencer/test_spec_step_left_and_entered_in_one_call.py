"""docs/semantics.md, "One FB call", step 4.3 and "Decisions": when several transitions switch in
one call, every preceding step leaves before any following step enters — so a step that one
switching transition leaves and another enters is active afterwards, left and entered again
(S0, then S1; its time restarts), whatever order the steps of the branch were written in.

Driven through the real cycle (``GraphRuntime``), on the fast path and on the general path
(``fast=False``), 10 ms per call.
"""

from __future__ import annotations

import pytest

from tests.sequencer.helpers import Run, chart_on_path, seq


def _branch(order: str) -> str:
    """S1 -T1-> (S2, S3) in ``order``; T2 leaves S2 for S4 while T3 jumps from S3 into S2."""
    return seq(f"""
  INITIAL_STEP S1 "a": END_STEP
  STEP S2 "b": N Q0.2; S1 N Q0.4; S0 N Q0.5; END_STEP
  STEP S3 "c": END_STEP
  STEP S4 "d": END_STEP
  TRANSITION T1 FROM S1 TO ({order}) := I0.0;
  TRANSITION T2 FROM S2 TO S4 := I0.1;
  TRANSITION T3 FROM S3 TO S2 := I0.1;
""")


def _switch_both(run: Run) -> None:
    run.call()
    run.set(I0_0=True).call()
    run.set(I0_0=False).call(3)
    assert run.active == [2, 3]
    assert run.st.step_t_ms(run.idx(2)) == 30
    run.set(I0_1=True).call()
    run.set(I0_1=False)


@pytest.mark.parametrize("fast", [True, False])
@pytest.mark.parametrize("order", ["S2, S3", "S3, S2"])
def test_a_step_left_by_one_transition_and_entered_by_another_stays_active(
    fast: bool, order: str
) -> None:
    """T2 (S2 → S4) and T3 (S3 → S2) switch in the same call: S2 ends active beside S4,
    with S0 and S1 in that call, its N row still 1 and its time back at 0 — also when S3
    became active before S2."""
    run = chart_on_path(_branch(order), fast)
    _switch_both(run)
    assert run.active == [2, 4]
    assert run.events(2) == {"S0", "S1"}
    assert run.get("Q0.2") is True
    assert run.get("Q0.4") is True and run.get("Q0.5") is True  # S1 and S0 pulses
    assert run.st.step_t_ms(run.idx(2)) == 0
    run.call()
    assert run.active == [2, 4] and run.get("Q0.2") is True
    assert run.get("Q0.4") is False and run.get("Q0.5") is False


@pytest.mark.parametrize("fast", [True, False])
def test_a_jump_into_an_active_step_nobody_leaves_keeps_it_without_an_event(fast: bool) -> None:
    """T3 jumps from S3 into S2 while S2 stays (T2 does not hold): S2 is not entered again —
    no event, its time runs on."""
    run = chart_on_path(
        seq("""
  INITIAL_STEP S1 "a": END_STEP
  STEP S2 "b": N Q0.2; END_STEP
  STEP S3 "c": END_STEP
  STEP S4 "d": END_STEP
  TRANSITION T1 FROM S1 TO (S3, S2) := I0.0;
  TRANSITION T2 FROM S2 TO S4 := I0.1;
  TRANSITION T3 FROM S3 TO S2 := I0.2;
"""),
        fast,
    )
    run.call()
    run.set(I0_0=True).call()
    run.set(I0_0=False).call(3)
    run.set(I0_2=True).call()
    assert run.active == [2]
    assert run.events(2) == set()
    assert run.st.step_t_ms(run.idx(2)) == 40


@pytest.mark.parametrize("fast", [True, False])
def test_a_path_moving_into_the_step_another_path_leaves_keeps_both_steps(fast: bool) -> None:
    """S2 and S3 active; T2 (S2 → S3) and T3 (S3 → S4) switch together: S3 is left and
    entered again, S4 entered — no path is lost, whichever transition comes first."""
    run = chart_on_path(
        seq("""
  INITIAL_STEP S1 "a": END_STEP
  STEP S2 "b": END_STEP
  STEP S3 "c": N Q0.3; END_STEP
  STEP S4 "d": END_STEP
  TRANSITION T1 FROM S1 TO (S2, S3) := I0.0;
  TRANSITION T2 FROM S2 TO S3 := I0.1;
  TRANSITION T3 FROM S3 TO S4 := I0.1;
"""),
        fast,
    )
    run.call()
    run.set(I0_0=True).call()
    run.set(I0_0=False, I0_1=True).call()
    assert run.active == [3, 4]
    assert run.events(3) == {"S0", "S1"} and run.get("Q0.3") is True
