"""docs/semantics.md, "Actions" and "Decisions": a row `OFF Sn` naming the step that holds it
switches that step off in the call it runs — S0, the final scan (its N, D and L operands back
to 0, its S0 rows) — and the rows written below it do not run, so no N, D or L operand of the
step is left at 1 once the step is no longer active (S7-GRAPH manual ch. 13, standard
actions: an N operand is 1 as long as the step is active; docs/semantics.md, "Actions": N,
D, L are 0 once it is left).

Driven through the real cycle (``GraphRuntime``), on the fast path and on the general path
(``fast=False``), 10 ms per call.
"""

from __future__ import annotations

import pytest

from tests.sequencer.helpers import chart_on_path, seq

_LINEAR = seq("""
  INITIAL_STEP S1 "a": END_STEP
  STEP S2 "b": N Q0.1; S1 OFF S2; N Q0.0; L Q0.2, T#50MS; S M0.0; S0 S M0.1; END_STEP
  TRANSITION T1 FROM S1 TO S2 := I0.0;
  TRANSITION T2 FROM S2 TO S1 := I0.2;
""")

_FAULT = seq("""
  INITIAL_STEP S1 "a": END_STEP
  STEP S2 "b": N Q0.2; END_STEP
  STEP S3 "c": SUPERVISION := I0.3; N Q0.3; V1 OFF S3; N Q0.4; D Q0.5, T#20MS; END_STEP
  TRANSITION T1 FROM S1 TO (S2, S3) := I0.0;
  TRANSITION T2 FROM S2 TO S1 := I0.2;
""")


@pytest.mark.parametrize("fast", [True, False])
def test_a_step_switching_itself_off_on_entry_leaves_none_of_its_operands_set(
    fast: bool,
) -> None:
    """S2's `S1 OFF S2` switches S2 off in the call T1 activates it: S1 and S0 in that call,
    its final scan ran (`S0 S M0.1`), the N row above is back at 0 and the N, L and S rows
    below did not run — nothing of S2 stays 1 once S2 is inactive."""
    run = chart_on_path(_LINEAR, fast)
    run.call()
    run.set(I0_0=True).call()
    assert run.active == []
    assert run.events(2) == {"S1", "S0"}
    assert run.get("M0.1") is True
    for name in ("Q0.0", "Q0.1", "Q0.2", "M0.0"):
        assert run.get(name) is False, name
    run.call(3)
    assert run.active == []
    assert run.get("Q0.0") is False and run.get("Q0.2") is False


@pytest.mark.parametrize("fast", [True, False])
def test_a_v1_row_switching_its_own_step_off_ends_the_steps_n_and_d_operands(
    fast: bool,
) -> None:
    """S3 faults (V1) after 30 ms, while its D operand is 1: its `V1 OFF S3` switches it off;
    its N rows above and below and its D row are 0 from that call on, S2 goes on."""
    run = chart_on_path(_FAULT, fast)
    run.call()
    run.set(I0_0=True).call()
    run.set(I0_0=False).call(3)
    assert run.active == [2, 3]
    assert run.get("Q0.3") is True and run.get("Q0.4") is True and run.get("Q0.5") is True
    run.set(I0_3=True).call()
    assert run.active == [2]
    assert run.events(3) == {"V1", "S0"}
    for name in ("Q0.3", "Q0.4", "Q0.5"):
        assert run.get(name) is False, name
    assert run.get("Q0.2") is True
    run.call()
    assert run.get("Q0.4") is False and run.get("Q0.5") is False
