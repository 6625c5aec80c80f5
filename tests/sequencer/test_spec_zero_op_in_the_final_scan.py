"""docs/semantics.md, "FB pins" (ZERO_OP) and "Decisions": `ZERO_OP` holds back the N actions and
CALLs of the S0 rows a step runs in its final scan as it does those of the active steps — an
`S0 N` bit stays 0, an `S0 N x := …` assignment does not run — while its S and R rows act.

Driven through the real cycle (``GraphRuntime``), on the fast path and on the general path
(``fast=False``), 10 ms per call.
"""

from __future__ import annotations

import pytest

from tests.sequencer.helpers import chart_on_path, seq

_STEPS = """
  INITIAL_STEP S1 "a": END_STEP
  STEP S2 "b": S0 N n := n + 1; S0 N Q0.0; S0 S M0.0; S1 N m := m + 1; END_STEP
  TRANSITION T1 FROM S1 TO S2 := I0.0;
  TRANSITION T2 FROM S2 TO S1 := I0.1;
"""
_VARS = "VAR n : INT := 0; m : INT := 0; END_VAR"


def _leave(fast: bool, zero_op: bool) -> tuple[int, int, bool, bool]:
    """Enter S2 and leave it with ``ZERO_OP`` = ``zero_op``: (n, m, Q0.0, M0.0)."""
    run = chart_on_path(_VARS + "\n" + seq(_STEPS), fast)
    run.set(ZERO_OP=zero_op).call()
    run.set(I0_0=True).call()
    run.set(I0_0=False, I0_1=True).call()
    assert run.active == [1]
    return run.st.vars["n"], run.st.vars["m"], run.get("Q0.0"), run.get("M0.0")


@pytest.mark.parametrize("fast", [True, False])
def test_zero_op_holds_back_the_n_rows_of_a_final_scan(fast: bool) -> None:
    assert _leave(fast, zero_op=True) == (0, 0, False, True)


@pytest.mark.parametrize("fast", [True, False])
def test_without_zero_op_the_s0_rows_run_in_the_final_scan(fast: bool) -> None:
    assert _leave(fast, zero_op=False) == (1, 1, True, True)
