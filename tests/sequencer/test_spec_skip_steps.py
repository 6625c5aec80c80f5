"""docs/semantics.md, "Decisions" (skip steps): with skip steps on, a step entered in a call
whose leaving transition already holds is passed through without ever being active — no S1
or S0, no rows — so afterwards it looks as if it had never been entered: the transition out
of it is not valid (``Tn.TT`` reads 0 from the next call on), its ``Sn.T`` and ``Sn.U`` are
those of its last activation, and a step whose rows already ran in the call (entered by an
earlier sequencer) is never taken back unseen.

Driven through the real cycle (``GraphRuntime``, the general path: skip steps never takes the
fast one), 10 ms per call.
"""

from __future__ import annotations

from tests.sequencer.helpers import Run, chart, seq

SKIP = "SKIP_STEPS := TRUE;"


def _loop(t3: str = "I0.3") -> Run:
    """S1 -T1 I0.0-> S2 -T2 I0.2-> S3 -T3-> S1, skip steps on."""
    return chart(
        seq(f"""
  INITIAL_STEP S1 "a": END_STEP
  STEP S2 "b": END_STEP
  STEP S3 "c": END_STEP
  TRANSITION T1 FROM S1 TO S2 := I0.0;
  TRANSITION T2 FROM S2 TO S3 := I0.2;
  TRANSITION T3 FROM S3 TO S1 := {t3};
"""),
        header=SKIP,
    )


def _tt(run: Run, number: int) -> bool:
    return run.st.tt[run.cc.transition_index[number]]


def test_the_transition_out_of_a_skipped_step_reads_unsatisfied_from_the_next_call() -> None:
    """S2 is passed through (T2 holds as it is entered): T2.TT is 1 in that call, as for any
    transition that switched, and 0 from the next on — S2 is not active, T2 not valid."""
    run = _loop()
    run.set(I0_2=True).call()
    run.set(I0_0=True).call()
    assert run.active == [3] and _tt(run, 2) is True
    run.set(I0_0=False, I0_2=False).call(3)
    assert run.active == [3] and _tt(run, 2) is False


def test_a_condition_reading_the_satisfied_bit_of_a_skipped_step_is_not_fooled() -> None:
    """T3 reads ``T2.TT``: after S2 was passed through T2.TT is 0, so T3 does not switch."""
    run = _loop("I0.3 AND T2.TT")
    run.set(I0_2=True).call()
    run.set(I0_0=True).call()
    run.set(I0_0=False, I0_2=False).call()
    run.set(I0_3=True).call(3)
    assert run.active == [3]


def test_a_skipped_step_keeps_the_times_of_its_last_activation() -> None:
    """S2 active for 70 ms keeps S2.T = S2.U = 70 after it is left; passed through later, it
    never became active, so they stay 70."""
    run = _loop()
    run.call()
    run.set(I0_0=True).call()
    run.set(I0_0=False).call(6)
    run.set(I0_2=True).call()
    i = run.idx(2)
    assert run.active == [3] and run.st.step_t_ms(i) == 70 and run.st.step_u_ms(i) == 70
    run.set(I0_2=False, I0_3=True).call()
    run.set(I0_3=False, I0_2=True, I0_0=True).call()
    assert run.active == [3] and run.events(2) == set()
    assert run.st.step_t_ms(i) == 70 and run.st.step_u_ms(i) == 70


def test_skip_steps_never_takes_back_a_step_an_earlier_sequencer_entered_and_ran() -> None:
    """Sequencer 1 enters S2 while T2 does not hold, and S2's rows run (M0.0 = 1, which T2
    reads); sequencer 2 then switches too. S2 stays active for the call — skipping it now
    would leave its N operand at 1 with the step gone — and leaves in the next, with its S0
    and final scan."""
    run = chart(
        seq("""
  INITIAL_STEP S1 "a": END_STEP
  STEP S2 "b": S1 N MW10 := MW10 + 1; N M0.0; END_STEP
  STEP S3 "c": END_STEP
  TRANSITION T1 FROM S1 TO S2 := I0.0;
  TRANSITION T2 FROM S2 TO S3 := M0.0;
  TRANSITION T3 FROM S3 TO S1 := I0.3;
""")
        + seq(
            """
  INITIAL_STEP S10 "d": END_STEP
  STEP S11 "e": END_STEP
  TRANSITION T10 FROM S10 TO S11 := I0.0;
  TRANSITION T11 FROM S11 TO S10 := I0.3;
""",
            2,
        ),
        header=SKIP,
        params="USER",
    )
    run.call()
    run.set(I0_0=True).call()
    assert run.active == [2, 11] and run.get("M0.0") is True and run.get("MW10") == 1
    assert run.events(2) == {"S1"}
    run.set(I0_0=False).call()
    assert run.active == [3, 11] and run.events(2) == {"S0"}
    assert run.get("M0.0") is False and run.get("MW10") == 1


def test_a_transition_valid_again_keeps_its_satisfied_bit_into_the_next_call() -> None:
    """T2 jumps from S2 back to S2: S2 is left and entered again, T2 is valid again, so the
    permanent instruction before the sequencer reads the T2.TT of the call it switched (1),
    as it does for any valid transition between two evaluations."""
    run = chart(
        seq("""
  INITIAL_STEP S1 "a": END_STEP
  STEP S2 "b": END_STEP
  TRANSITION T1 FROM S1 TO S2 := I0.0;
  TRANSITION T2 FROM S2 TO S2 := I0.1;
"""),
        header="PERMANENT BEFORE\n  M0.0 := T2.TT;\nEND_PERMANENT\n",
    )
    run.call()
    run.set(I0_0=True).call()
    run.set(I0_0=False, I0_1=True).call()
    assert run.events(2) == {"S0", "S1"}
    run.set(I0_1=False).call()
    assert run.get("M0.0") is True and _tt(run, 2) is False
    run.call()
    assert run.get("M0.0") is False
