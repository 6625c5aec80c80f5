"""docs/semantics.md, "One FB call", steps 4.1–4.2: every transition whose preceding steps are all
active is evaluated (``Tn.TT``) — those of lower priority than the one that switches too — and at
an alternative divergence the path of highest priority wins (the first written, then the lowest
number), also when one of the paths is a simultaneous join, whatever the order in which its
preceding steps became active.

Driven through the real cycle (``GraphRuntime``), on the fast path and on the general path
(``fast=False``), 10 ms per call.
"""

from __future__ import annotations

import pytest

from tests.sequencer.helpers import Run, chart_on_path, seq


def _run(sequences: str, fast: bool) -> Run:
    return chart_on_path(sequences, fast)


def _tt(run: Run, number: int) -> bool:
    return bool(run.st.tt[run.cc.transition_index[number]])


@pytest.mark.parametrize("fast", [True, False])
def test_every_transition_of_an_alternative_divergence_is_evaluated_when_one_switches(
    fast: bool,
) -> None:
    """T5 (first written) switches; T2 and T3, whose conditions hold too, show TT."""
    run = _run(
        seq("""
      INITIAL_STEP S1 "a": END_STEP
      STEP S2 "b": END_STEP
      STEP S3 "c": END_STEP
      STEP S4 "d": END_STEP
      TRANSITION T5 FROM S1 TO S2 := I0.0;
      TRANSITION T3 FROM S1 TO S4 := I0.0;
      TRANSITION T2 FROM S1 TO S3 := I0.0 AND NOT I0.1;
    """),
        fast,
    )
    run.call()
    run.set(I0_0=True).call()
    assert run.active == [2]
    assert _tt(run, 5) and _tt(run, 3) and _tt(run, 2)


_JOIN = """
  INITIAL_STEP S1 "a": END_STEP
  STEP S2 "b": END_STEP
  STEP S3 "c": END_STEP
  STEP S4 "d": N Q0.4; END_STEP
  STEP S6 "f": END_STEP
  STEP S7 "g": N Q0.7; END_STEP
  TRANSITION T1 FROM S1 TO ({first}) := I0.0;
  TRANSITION T2 FROM S2 TO {late} := I0.1;
  TRANSITION T4 FROM S3 TO S4 := I0.2;
  TRANSITION T5 FROM (S3, S6) TO S7 := I0.2;
"""


@pytest.mark.parametrize("fast", [True, False])
@pytest.mark.parametrize(
    ("first", "late"),
    [("S6, S2", "S3"), ("S3, S2", "S6")],
    ids=["join-partner-first", "divergence-step-first"],
)
def test_a_join_leaving_an_alternative_divergence_yields_to_the_path_of_higher_priority(
    fast: bool, first: str, late: str
) -> None:
    """S3 diverges into T4 (first written, lowest number) and the join T5 with S6. Both hold:
    T4 switches and S6 stays, whether S6 or S3 became active first."""
    run = _run(seq(_JOIN.format(first=first, late=late)), fast)
    run.call()
    run.set(I0_0=True).call()
    run.set(I0_0=False, I0_1=True).call()
    assert run.active == [3, 6]
    run.set(I0_2=True).call()
    assert run.active == [4, 6]
    assert run.get("Q0.4") is True and run.get("Q0.7") is False


@pytest.mark.parametrize("fast", [True, False])
def test_a_join_switches_when_the_path_of_higher_priority_does_not_hold(fast: bool) -> None:
    """With T4 false, the join T5 takes S3 and S6 to S7."""
    run = _run(
        seq(_JOIN.format(first="S6, S2", late="S3").replace("TO S4 := I0.2", "TO S4 := I0.3")), fast
    )
    run.call()
    run.set(I0_0=True).call()
    run.set(I0_0=False, I0_1=True).call()
    run.set(I0_2=True).call()
    assert run.active == [7]
    assert run.get("Q0.7") is True
