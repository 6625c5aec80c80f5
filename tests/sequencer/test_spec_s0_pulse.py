"""docs/semantics.md, "Decisions" (event-qualified N on a bit: a one-call pulse) and "Actions" (N: 0
once the step is left): an `S0 N` row sets its operand in the call that leaves the step — after
the final scan — and the operand is 0 again from the next call on, whether the step was left by
its transition, by `OFF Sx` or by OFF_SQ; an active step's own N row on the operand keeps it 1.

Driven through the real cycle (``GraphRuntime``), on the fast path and on the general path
(``fast=False``), 10 ms per call.
"""

from __future__ import annotations

import pytest

from s7graph.sequencer.cycle import GraphRuntime
from tests.sequencer.helpers import Run, chart, seq

STEPS = """
  INITIAL_STEP S1 "a": END_STEP
  STEP S2 "b": S0 N Q0.0; S0 N Q0.2; S1 N Q0.1; END_STEP
  STEP S3 "c": N Q0.2; S1 OFF S4; END_STEP
  STEP S4 "d": S0 N Q0.4; END_STEP
  TRANSITION T1 FROM S1 TO (S2, S4) := I0.0;
  TRANSITION T2 FROM S2 TO S3 := I0.1;
"""


def _run(fast: bool) -> Run:
    run = chart(seq(STEPS))
    run.rt = GraphRuntime(
        run.cc, run.cc.bind(run.mem), counter=run._counter, timer=run._timer, fast=fast
    )
    return run


@pytest.mark.parametrize("fast", [True, False])
def test_an_s0_n_row_is_a_one_call_pulse(fast: bool) -> None:
    run = _run(fast)
    run.call()
    run.set(I0_0=True).call()
    assert run.active == [2, 4] and run.get("Q0.1") is True
    run.set(I0_0=False, I0_1=True).call()  # S2 left: its S0 rows; S3 switches S4 off
    assert run.active == [3]
    assert run.get("Q0.0") is True and run.get("Q0.4") is True and run.get("Q0.2") is True
    run.set(I0_1=False).call()
    assert run.get("Q0.0") is False and run.get("Q0.4") is False
    assert run.get("Q0.2") is True  # S3's own N row
    run.call(3)
    assert run.get("Q0.0") is False and run.get("Q0.1") is False


@pytest.mark.parametrize("fast", [True, False])
def test_the_s0_n_pulse_of_off_sq_ends_in_the_next_call(fast: bool) -> None:
    run = _run(fast)
    run.call()
    run.set(I0_0=True).call()
    run.set(I0_0=False, OFF_SQ=True).call()
    assert run.active == [] and run.get("Q0.0") is True and run.get("Q0.4") is True
    run.call()
    assert run.get("Q0.0") is False and run.get("Q0.4") is False
