"""docs/semantics.md, "One FB call", step 4.5 and "Actions": the rows of every active step run, in
activation order, even when a row of an earlier step switches another step off (`OFF Sx`) in the
same call — the switched-off step runs only its final scan, the steps after it their rows.

Driven through the real cycle (``GraphRuntime``), on the fast path and on the general path
(``fast=False``), 10 ms per call.
"""

from __future__ import annotations

import pytest

from tests.sequencer.helpers import Run, chart_on_path, seq


def _run(sequences: str, fast: bool) -> Run:
    return chart_on_path(sequences, fast)


_BRANCH = """
  INITIAL_STEP S1 "a": END_STEP
  STEP S2 "b": N Q0.2; END_STEP
  STEP S3 "c": N Q0.3; S1 OFF S2; END_STEP
  STEP S4 "d": N Q0.4; S1 S M0.4; END_STEP
  STEP S5 "e": N Q0.5; END_STEP
  STEP S6 "f": INTERLOCK := NOT I0.5; L1 OFF S5; END_STEP
  STEP S7 "g": N Q0.7; S M0.7; END_STEP
  TRANSITION T1 FROM S1 TO (S2, S3, S4) := I0.0;
  TRANSITION T2 FROM S4 TO (S5, S6, S7) := I0.1;
  TRANSITION T3 FROM S7 TO S1 := FALSE;
"""


@pytest.mark.parametrize("fast", [True, False])
def test_a_row_switching_off_an_earlier_step_lets_the_later_steps_run_their_rows(
    fast: bool,
) -> None:
    """S2, S3, S4 enter together; S3's `S1 OFF S2` switches S2 off while the rows run. S4,
    activated after S3, still runs its S1 and N rows in that call."""
    run = _run(seq(_BRANCH), fast)
    run.call()
    run.set(I0_0=True).call()
    assert run.active == [3, 4]
    assert run.get("Q0.2") is False and run.get("Q0.3") is True
    assert run.get("Q0.4") is True and run.get("M0.4") is True


@pytest.mark.parametrize("fast", [True, False])
def test_an_l1_row_switching_off_a_step_does_not_hold_back_the_rows_of_the_next_one(
    fast: bool,
) -> None:
    """Later, with S3, S5, S6, S7 active, S6's `L1 OFF S5` switches S5, entered before it,
    off: S7, entered after S6, runs its rows in that call (its S row sets M0.7 again)."""
    run = _run(seq(_BRANCH), fast)
    run.call()
    run.set(I0_0=True).call()
    run.set(I0_0=False, I0_1=True).call()
    assert run.active == [3, 5, 6, 7]
    run.set(I0_1=False).call()
    run.set(I0_5=True, M0_7=False).call()
    assert run.events(6) == {"L1"}
    assert run.active == [3, 6, 7]
    assert run.get("Q0.5") is False
    assert run.get("Q0.7") is True and run.get("M0.7") is True


@pytest.mark.parametrize("fast", [True, False])
def test_off_of_an_earlier_step_in_a_second_sequencer_keeps_the_rows_of_the_later_ones(
    fast: bool,
) -> None:
    """The same in the second sequencer of an FB (its own list of active steps)."""
    run = _run(
        seq('INITIAL_STEP S1 "a": N Q1.0; END_STEP\nTRANSITION T1 FROM S1 TO STOP := FALSE;')
        + seq(
            """
      INITIAL_STEP S11 "x": END_STEP
      STEP S12 "y": N Q2.2; END_STEP
      STEP S13 "z": S1 OFF S12; END_STEP
      STEP S14 "w": N Q2.4; S1 S M2.4; END_STEP
      TRANSITION T11 FROM S11 TO (S12, S13, S14) := I0.0;
    """,
            2,
        ),
        fast,
    )
    run.call()
    run.set(I0_0=True).call()
    assert run.active == [1, 13, 14]
    assert run.get("Q2.2") is False
    assert run.get("Q2.4") is True and run.get("M2.4") is True
    assert run.get("Q1.0") is True
