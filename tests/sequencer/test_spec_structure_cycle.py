"""docs/semantics.md, "Structure" and "One FB call": the rules not pinned elsewhere.

Driven through the real cycle (``GraphRuntime``) by the scenario harness, 10 ms per call.
"""

from __future__ import annotations

import pytest

from s7graph.sequencer.checks.validate import validate
from s7graph.sequencer.text.parse import parse_chart
from tests.sequencer.helpers import Run, chart, enter, leave, seq, source, two_steps

# ---------------------------------------------------------------- structure


def test_every_initial_step_of_a_sequencer_is_active_after_the_first_call() -> None:
    """docs/semantics.md, "Structure": one or more initial steps per sequencer."""
    run = chart(
        seq("""
      INITIAL_STEP S1 "a": N Q0.1; END_STEP
      STEP S2 "b": END_STEP
      INITIAL_STEP S3 "c": N Q0.3; END_STEP
      TRANSITION T1 FROM S1 TO S2 := I0.0;
      TRANSITION T2 FROM S3 TO S2 := I0.1;
    """)
    )
    run.call()
    assert run.active == [1, 3]
    assert run.get("Q0.1") is True and run.get("Q0.3") is True


def test_a_step_may_be_the_target_of_several_transitions() -> None:
    """docs/semantics.md, "Structure": alternative branches and joins (docs/chart-format.md): both
    paths reach S4."""
    body = seq("""
      INITIAL_STEP S1 "a": END_STEP
      STEP S2 "b": END_STEP
      STEP S3 "c": END_STEP
      STEP S4 "d": END_STEP
      TRANSITION T1 FROM S1 TO S2 := I0.0;
      TRANSITION T2 FROM S1 TO S3 := I0.1;
      TRANSITION T3 FROM S2 TO S4 := I0.2;
      TRANSITION T4 FROM S3 TO S4 := I0.3;
      TRANSITION T5 FROM S4 TO S1 := I0.4;
    """)
    for first, second in (("I0_0", "I0_2"), ("I0_1", "I0_3")):
        run = chart(body)
        run.call()
        run.set(**{first: True}).call()
        run.set(**{first: False, second: True}).call()
        assert run.active == [4]


def test_a_branch_stop_in_one_simultaneous_path_ends_only_that_path() -> None:
    """docs/semantics.md, "Structure" branch stops: `TO STOP` ends the path, the other path carries
    on."""
    run = chart(
        seq("""
      INITIAL_STEP S1 "a": END_STEP
      STEP S2 "b": END_STEP
      STEP S3 "c": END_STEP
      STEP S4 "d": END_STEP
      TRANSITION T1 FROM S1 TO (S2, S3) := I0.0;
      TRANSITION T2 FROM S2 TO STOP := I0.1;
      TRANSITION T3 FROM S3 TO S4 := I0.2;
    """)
    )
    run.call()
    run.set(I0_0=True).call()
    run.set(I0_0=False, I0_1=True).call()
    assert run.active == [3]
    run.set(I0_2=True).call()
    assert run.active == [4]


def test_a_simultaneous_join_of_three_paths_waits_for_the_last_one() -> None:
    """docs/semantics.md, "Structure": a join transition needs the last step of every path
    active."""
    run = chart(
        seq("""
      INITIAL_STEP S1 "a": END_STEP
      STEP S2 "b": END_STEP
      STEP S3 "c": END_STEP
      STEP S4 "d": END_STEP
      STEP S5 "e": END_STEP
      TRANSITION T1 FROM S1 TO (S2, S3, S4) := I0.0;
      TRANSITION T2 FROM S4 TO S5 := I0.1;
      TRANSITION T3 FROM (S2, S3, S5) TO S1 := TRUE;
    """)
    )
    run.call()
    run.set(I0_0=True).call()
    run.set(I0_0=False).call(5)
    assert run.active == [2, 3, 4]
    run.set(I0_1=True).call()
    assert run.active == [2, 3, 5]
    run.call()
    assert run.active == [1]


def test_a_jump_from_a_later_sequencer_into_an_earlier_one_activates_the_target() -> None:
    """docs/semantics.md, "Structure" jumps: to any step of any sequencer of the FB (here
    backwards)."""
    run = chart(
        seq("""
      INITIAL_STEP S1 "a": END_STEP
      STEP S2 "b": N Q0.2; END_STEP
      TRANSITION T1 FROM S1 TO S2 := FALSE;
      TRANSITION T2 FROM S2 TO S1 := FALSE;
    """)
        + seq(
            """
      INITIAL_STEP S11 "x": END_STEP
      TRANSITION T11 FROM S11 TO S2 := I0.0;
    """,
            2,
        )
    )
    run.call()
    run.set(I0_0=True).call()
    run.set(I0_0=False).call()
    assert run.active == [1, 2]  # S1 stays: the jump came from sequencer 2
    assert run.get("Q0.2") is True


def _alternatives(n: int) -> str:
    steps = "\n".join(f'STEP S{k} "p": END_STEP' for k in range(2, n + 2))
    trans = "\n".join(f"TRANSITION T{k} FROM S1 TO S{k} := I0.0;" for k in range(2, n + 2))
    back = "\n".join(f"TRANSITION T{k + 500} FROM S{k} TO S1 := I0.1;" for k in range(2, n + 2))
    return seq(f'INITIAL_STEP S1 "a": END_STEP\n{steps}\n{trans}\n{back}')


def _simultaneous(n: int) -> str:
    steps = "\n".join(f'STEP S{k} "p": END_STEP' for k in range(2, n + 2))
    targets = ", ".join(f"S{k}" for k in range(2, n + 2))
    return seq(
        f'INITIAL_STEP S1 "a": END_STEP\n{steps}\n'
        f"TRANSITION T1 FROM S1 TO ({targets}) := I0.0;\n"
        f"TRANSITION T2 FROM ({targets}) TO S1 := I0.1;"
    )


def _chain(n: int) -> str:
    steps = "\n".join(f'STEP S{k} "s": END_STEP' for k in range(2, n + 1))
    trans = "\n".join(f"TRANSITION T{k} FROM S{k - 1} TO S{k} := I0.0;" for k in range(2, n + 1))
    back = f"TRANSITION T1 FROM S{n} TO S1 := I0.1;"
    return seq(f'INITIAL_STEP S1 "a": END_STEP\n{steps}\n{trans}\n{back}')


def _w110(text: str) -> int:
    return sum(d.code == "W110" for d in validate(parse_chart(text, "v.s7g")))


@pytest.mark.parametrize(
    ("build", "limit"),
    [(_chain, 250), (_alternatives, 125), (_simultaneous, 249)],
    ids=["steps_and_transitions", "alternative_paths", "simultaneous_paths"],
)
def test_limits_warn_only_above_the_s7_graph_maximum(build, limit: int) -> None:
    """docs/semantics.md, "Structure": limits that warn — 250 steps / transitions, 125 alternative
    paths, 249 simultaneous paths."""
    assert _w110(source(build(limit))) == 0
    assert _w110(source(build(limit + 1))) >= 1


def test_more_than_250_transitions_warns_with_fewer_steps() -> None:
    """docs/semantics.md, "Structure": 250 transitions is a limit of its own (here 200 steps, 251
    transitions)."""
    steps = "\n".join(f'STEP S{k} "s": END_STEP' for k in range(2, 201))
    trans = "\n".join(
        f"TRANSITION T{k} FROM S1 TO S{(k % 199) + 2} := I0.{k % 8};" for k in range(1, 252)
    )
    text = source(seq(f'INITIAL_STEP S1 "a": END_STEP\n{steps}\n{trans}'))
    diags = [d for d in validate(parse_chart(text, "v.s7g")) if d.code == "W110"]
    assert any("transitions" in d.message for d in diags)


# ---------------------------------------------------------------- one FB call


def test_a_step_activated_by_a_jump_cannot_switch_on_in_the_same_call() -> None:
    """docs/semantics.md, "One FB call", step 4.1: transitions are evaluated on the state at the
    start of the call — S2 entered in this call does not leave through its (true) transition T2 in
    it."""
    run = two_steps("N Q0.0;")
    run.call()
    run.set(I0_0=True, I0_1=True).call()
    assert run.active == [2] and run.get("Q0.0") is True
    run.call()
    assert run.active == [3]


def test_a_later_sequencer_sees_the_switch_of_an_earlier_one_in_the_same_call() -> None:
    """docs/semantics.md, "One FB call", step 4: per sequencer in definition order — sequencer 2
    starts from the state sequencer 1 left, so it sees S2 active; sequencer 1 sees sequencer 2 only
    next call."""
    run = chart(
        seq("""
      INITIAL_STEP S1 "a": END_STEP
      STEP S2 "b": END_STEP
      STEP S3 "c": END_STEP
      TRANSITION T1 FROM S1 TO S2 := I0.0;
      TRANSITION T2 FROM S2 TO S3 := S12.X;
    """)
        + seq(
            """
      INITIAL_STEP S11 "x": END_STEP
      STEP S12 "y": END_STEP
      TRANSITION T11 FROM S11 TO S12 := S2.X;
    """,
            2,
        )
    )
    run.call()
    run.set(I0_0=True).call()
    assert run.active == [2, 12]
    run.call()
    assert run.active == [3, 12]


def test_a_step_left_and_a_step_entered_with_the_same_n_operand_keep_it_on() -> None:
    """docs/semantics.md, "One FB call", step 4.5: the final scan resets the N operands of the left
    step, the rows of the active steps run; an operand N in both steps stays 1 in the switching
    call."""
    run = chart(
        seq("""
      INITIAL_STEP S1 "a": N Q0.0; END_STEP
      STEP S2 "b": N Q0.0; END_STEP
      TRANSITION T1 FROM S1 TO S2 := I0.0;
      TRANSITION T2 FROM S2 TO S1 := I0.1;
    """)
    )
    run.call()
    run.set(I0_0=True).call()
    assert run.active == [2] and run.get("Q0.0") is True
    run.set(I0_0=False, I0_1=True).call()
    assert run.active == [1] and run.get("Q0.0") is True


def test_action_rows_run_top_to_bottom() -> None:
    """docs/semantics.md, "One FB call", step 4.5: run action rows of active steps top to bottom."""
    run = two_steps("N x := 1; N x := x * 5;", header="VAR x : INT := 0; END_VAR")
    enter(run)
    assert run.st.vars["x"] == 5
    run2 = two_steps("N x := x * 5; N x := 1;", header="VAR x : INT := 0; END_VAR")
    enter(run2)
    assert run2.st.vars["x"] == 1


def test_s0_rows_of_the_left_step_run_in_the_switching_call_only() -> None:
    """docs/semantics.md, "One FB call", step 4.5: steps deactivated in (c) run their S0 rows
    (once)."""
    run = two_steps("S0 N n := n + 1;", header="VAR n : INT := 0; END_VAR")
    enter(run)
    run.call(3)
    assert run.st.vars["n"] == 0
    leave(run)
    assert run.st.vars["n"] == 1
    run.call(3)
    assert run.st.vars["n"] == 1


def test_step_time_u_restarts_at_zero_on_activation() -> None:
    """docs/semantics.md, "One FB call", step 4.3: activation restarts T and U at 0 (T keeps its
    last value after exit)."""
    run = two_steps("N Q0.0;")
    enter(run)
    run.call(20)
    i = run.idx(2)
    assert run.st.step_u_ms(i) >= 200
    leave(run)
    t_after_exit = run.st.step_t_ms(i)
    run.call(5)
    assert run.st.step_t_ms(i) == t_after_exit >= 200
    run.set(I0_2=True).call()
    run.set(I0_2=False, I0_0=True).call()
    assert run.active == [2]
    assert run.st.step_t_ms(i) <= 10 and run.st.step_u_ms(i) <= 10


def test_init_sq_held_high_initializes_once_and_the_sequence_then_runs() -> None:
    """docs/semantics.md, "One FB call", step 1 and "FB pins": INIT_SQ acts on its rising edge, not
    while it is held."""
    run = two_steps("N Q0.0;")
    enter(run)
    run.set(INIT_SQ=True).call()
    assert run.active == [1]
    run.set(I0_0=True).call()
    assert run.active == [2]
    run.call(3)
    assert run.active == [2]


def test_s_on_held_high_activates_only_on_its_rising_edge() -> None:
    """docs/semantics.md, "One FB call", step 1 and "Modes": S_ON acts on its rising edge; after
    S_OFF, a held S_ON does not bring the step back."""
    run = two_steps("N Q0.0;")
    run.call()
    run.set(SW_MAN=True).call()
    run.set(SW_MAN=False, S_SEL=2, S_ON=True).call()
    assert run.active == [1, 2]
    run.set(S_OFF=True).call()
    run.set(S_OFF=False).call(3)
    assert run.active == [1]


def test_t_push_held_high_in_tap_switches_only_one_transition() -> None:
    """docs/semantics.md, "Modes" and "One FB call", step 4.2: TAP needs a T_PUSH *edge*; held high
    it allows one switch."""
    run = two_steps("N Q0.0;")
    run.call()
    run.set(SW_TAP=True).call()
    run.set(SW_TAP=False, I0_0=True, I0_1=True).call(2)
    assert run.active == [1]
    run.set(T_PUSH=True).call(5)
    assert run.active == [2]


def test_en_sskip_turns_skip_steps_on_at_runtime() -> None:
    """docs/semantics.md, "One FB call", step 4.3: skip steps is an option (default off) with the
    runtime pin EN_SSKIP."""
    run = chart(
        seq("""
      INITIAL_STEP S1 "a": END_STEP
      STEP S2 "b": S1 S M5.0; END_STEP
      STEP S3 "c": END_STEP
      TRANSITION T1 FROM S1 TO S2 := I0.0;
      TRANSITION T2 FROM S2 TO S3 := I0.1;
    """),
        params="USER",
    )
    run.set(EN_SSKIP=True).call()
    run.set(I0_0=True, I0_1=True).call()
    assert run.active == [3] and run.get("M5.0") is False
    assert run.out("SSKIP_ENABLED") is True


def test_codesys_order_runs_actions_before_transitions() -> None:
    """docs/semantics.md, "One FB call" (CODESYS order option): actions run before transitions, so a
    transition sees the action rows of its own step from the same call."""
    body = seq("""
      INITIAL_STEP S1 "a": N M0.0; END_STEP
      STEP S2 "b": END_STEP
      TRANSITION T1 FROM S1 TO S2 := M0.0;
    """)
    codesys = chart(body, header="ORDER := CODESYS;")
    codesys.call()
    assert codesys.active == [2]
    graph = chart(body)
    graph.call()
    assert graph.active == [1]
    graph.call()
    assert graph.active == [2]


def test_off_sq_is_applied_before_the_transitions_of_the_same_call() -> None:
    """docs/semantics.md, "One FB call", step 2 before 4: with OFF_SQ set nothing switches even if a
    transition holds."""
    run = two_steps("N Q0.0;", params="USER")
    run.call()
    run.set(OFF_SQ=True, I0_0=True).call()
    assert run.active == [] and run.get("Q0.0") is False
    assert run.out("SQ_ISOFF") is True


def test_sequencers_run_in_definition_order_not_number_order() -> None:
    """docs/semantics.md, "One FB call", step 4: per sequencer, in *definition* order — SEQUENCE 2
    written first runs first, so SEQUENCE 1 sees its action in the same call."""
    run = chart(
        seq(
            """
      INITIAL_STEP S11 "x": END_STEP
      STEP S12 "y": N M0.0; END_STEP
      TRANSITION T11 FROM S11 TO S12 := I0.0;
    """,
            2,
        )
        + seq("""
      INITIAL_STEP S1 "a": END_STEP
      STEP S2 "b": END_STEP
      TRANSITION T1 FROM S1 TO S2 := M0.0;
    """)
    )
    run.call()
    run.set(I0_0=True).call()
    assert run.active == [2, 12]


def _shared_n(leaving_sequencer_first: bool) -> Run:
    """Two sequencers whose steps both hold M0.0 with N: S1 stays, S11 leaves on I0.0."""
    stays = seq('INITIAL_STEP S1 "a": N M0.0; END_STEP\nTRANSITION T1 FROM S1 TO STOP := FALSE;')
    leaves = seq(
        'INITIAL_STEP S11 "x": N M0.0; END_STEP\nSTEP S12 "y": END_STEP\n'
        "TRANSITION T11 FROM S11 TO S12 := I0.0;",
        2,
    )
    return chart(leaves + stays if leaving_sequencer_first else stays + leaves)


def test_an_n_operand_shared_across_sequencers_drops_for_the_call_a_later_one_leaves() -> None:
    """docs/semantics.md, "Decisions", an N operand in two sequencers: each sequencer writes
    it in its turn, so the final scan of a step left in a later sequencer writes 0 last —
    the operand is 0 at the end of that call though a step of the earlier one still holds
    it, and 1 again from the next call."""
    run = _shared_n(leaving_sequencer_first=False)
    run.call()
    assert run.get("M0.0") is True
    run.set(I0_0=True).call()
    assert run.active == [1, 12] and run.get("M0.0") is False
    run.call()
    assert run.get("M0.0") is True


def test_an_n_operand_shared_across_sequencers_holds_when_an_earlier_one_leaves() -> None:
    """The same chart with the leaving sequencer written first: the step that stays writes
    1 after the final scan wrote 0, so the operand never drops."""
    run = _shared_n(leaving_sequencer_first=True)
    run.call()
    run.set(I0_0=True).call()
    assert run.active == [1, 12] and run.get("M0.0") is True


def test_permanent_instructions_run_once_per_call_around_all_sequencers() -> None:
    """docs/semantics.md, "Structure" and "One FB call", steps 3 and 5: permanent *before* once
    before the sequencers, *after* once after all of them (it sees the actions of the last sequencer
    of this call)."""
    run = chart(
        seq('INITIAL_STEP S1 "a": END_STEP\nTRANSITION T1 FROM S1 TO STOP := FALSE;')
        + seq('INITIAL_STEP S11 "x": N M1.1; END_STEP\nTRANSITION T11 FROM S11 TO STOP := M9.0;', 2)
        + seq('INITIAL_STEP S21 "y": END_STEP\nTRANSITION T21 FROM S21 TO STOP := FALSE;', 3),
        header="PERMANENT BEFORE\n  M3.0 := NOT M3.0;\nEND_PERMANENT\n"
        "PERMANENT AFTER\n  M3.1 := NOT M3.1;\n  M3.2 := M1.1;\nEND_PERMANENT\n",
    )
    run.call(3)
    assert run.get("M3.0") is True and run.get("M3.1") is True and run.get("M3.2") is True
    run.call()
    assert run.get("M3.0") is False and run.get("M3.1") is False


def test_a_step_time_read_after_exit_is_its_last_activation_time() -> None:
    """docs/semantics.md, "Conditions" `S3.T` (activation time, or the last one after exit) in a
    condition."""
    run = chart(
        seq("""
      INITIAL_STEP S1 "a": END_STEP
      STEP S2 "b": END_STEP
      STEP S3 "c": END_STEP
      STEP S4 "d": END_STEP
      TRANSITION T1 FROM S1 TO S2 := I0.0;
      TRANSITION T2 FROM S2 TO S3 := I0.1;
      TRANSITION T3 FROM S3 TO S4 := S2.T >= T#60MS AND NOT S2.X;
    """)
    )
    run.call()
    run.set(I0_0=True).call()
    run.set(I0_0=False).call(6)  # S2 active 60 ms by the next call
    run.set(I0_1=True).call()
    run.set(I0_1=False).call()
    assert run.active == [4]


def test_not_of_a_parenthesised_or() -> None:
    """docs/semantics.md, "Conditions": NOT, OR and parentheses."""
    body = seq("""
      INITIAL_STEP S1 "a": END_STEP
      STEP S2 "b": END_STEP
      TRANSITION T1 FROM S1 TO S2 := NOT (I0.0 OR I0.1) AND I0.2;
    """)
    for inputs, switched in (({"I0_2": True}, True), ({"I0_2": True, "I0_1": True}, False)):
        run = chart(body)
        run.set(**inputs).call(2)
        assert (run.active == [2]) is switched
