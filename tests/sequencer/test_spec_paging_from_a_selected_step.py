"""docs/semantics.md, "Decisions", row "display paging": paging is by number and wraps, also
from a step ``S_SEL`` chose outside the display set — ``S_PREV`` shows the nearest step of
the set below it, ``S_NEXT`` the nearest above it (TIA: "Output previous step in parameter
S_NO", "Indicate next step in parameter S_NO").

Driven through the real cycle (``GraphRuntime``), on the fast path and on the general path
(``fast=False``), 10 ms per call.
"""

from __future__ import annotations

import pytest

from tests.sequencer.helpers import Run, chart_on_path, seq

_CHART = seq("""
  INITIAL_STEP S1 "a": END_STEP
  STEP S2 "b": END_STEP
  STEP S3 "c": END_STEP
  INITIAL_STEP S4 "d": END_STEP
  STEP S5 "e": END_STEP
  TRANSITION T1 FROM S1 TO S2 := I0.0;
  TRANSITION T2 FROM S2 TO S3 := I0.0;
  TRANSITION T3 FROM S3 TO S1 := I0.0;
  TRANSITION T4 FROM S4 TO S5 := I0.0;
  TRANSITION T5 FROM S5 TO S4 := I0.0;
""")


def _shown(run: Run, **pins: object) -> int:
    run.set(**pins).call()
    return int(run.out("S_NO"))


@pytest.mark.parametrize("fast", [True, False])
def test_s_prev_from_a_selected_step_shows_the_active_step_below_it(fast: bool) -> None:
    """S1 and S4 active; S_SEL shows S3 (inactive): S_PREV shows S1, not S4."""
    run = chart_on_path(_CHART, fast)
    run.call()
    assert _shown(run, S_SEL=3) == 3 and run.out("S_ACTIVE") is False
    assert _shown(run, S_PREV=True) == 1
    assert run.active == [1, 4]  # paging never moves the sequence


@pytest.mark.parametrize("fast", [True, False])
def test_s_next_from_a_selected_step_shows_the_active_step_above_it(fast: bool) -> None:
    run = chart_on_path(_CHART, fast)
    run.call()
    assert _shown(run, S_SEL=2) == 2
    assert _shown(run, S_NEXT=True) == 4


@pytest.mark.parametrize("fast", [True, False])
def test_paging_from_a_selected_step_wraps_past_the_ends(fast: bool) -> None:
    """From S5 (above every active step) S_NEXT wraps to S1; from S_SEL 1 after S1 has
    left, S_PREV wraps to the highest active step."""
    run = chart_on_path(_CHART, fast)
    run.call()
    assert _shown(run, S_SEL=5) == 5
    assert _shown(run, S_NEXT=True) == 1
    run.set(S_NEXT=False, I0_0=True).call()  # S1 -> S2, S4 -> S5
    run.set(I0_0=False).call()
    assert run.active == [2, 5]
    assert _shown(run, S_SEL=1) == 1
    assert _shown(run, S_PREV=True) == 5
