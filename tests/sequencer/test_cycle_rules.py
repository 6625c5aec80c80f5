"""The per-call algorithm of docs/semantics.md, "Structure" and "One FB call", one test per rule, on
the virtual clock."""

from __future__ import annotations

import itertools
import re
from typing import Any

from s7graph.sequencer.cycle import GraphRuntime
from tests.sequencer.helpers import Chart, seq

LINEAR = seq("""
  INITIAL_STEP S1 "a": END_STEP
  STEP S2 "b": N Q0.0; END_STEP
  TRANSITION T1 FROM S1 TO S2 := I0.0;
  TRANSITION T2 FROM S2 TO S1 := I0.1;
""")


def test_first_call_activates_the_initial_steps() -> None:
    c = Chart(LINEAR)
    c.call()
    assert c.active == ["S1"]


def test_linear_chain_switches_when_the_transition_holds() -> None:
    c = Chart(LINEAR)
    c.call()
    c.set(I0_0=True)
    c.call()
    assert c.active == ["S2"] and c.fired == ["T1"]
    assert c.q("Q0.0")


def test_new_step_acts_in_the_switching_call_and_left_step_gets_final_scan() -> None:
    c = Chart(LINEAR)
    c.set(I0_0=True)
    c.call(2)
    assert c.q("Q0.0")
    c.set(I0_0=False, I0_1=True)
    c.call()
    assert c.active == ["S1"] and not c.q("Q0.0")


def test_only_one_step_per_call_without_skip_steps() -> None:
    c = Chart(LINEAR)
    c.call()
    c.set(I0_0=True, I0_1=True)
    c.call()
    assert c.active == ["S2"]
    c.call()
    assert c.active == ["S1"]


ALT = seq("""
  INITIAL_STEP S1 "a": END_STEP
  STEP S2 "b": END_STEP
  STEP S3 "c": END_STEP
  TRANSITION T9 FROM S1 TO S3 := I0.1;
  TRANSITION T2 FROM S1 TO S2 := I0.0;
""")


def test_alternative_divergence_takes_only_the_first_listed_true_transition() -> None:
    c = Chart(ALT)
    c.call()
    c.set(I0_0=True, I0_1=True)
    c.call()
    assert c.active == ["S3"] and c.fired == ["T9"]


def test_alternative_divergence_takes_a_later_path_when_the_first_is_false() -> None:
    c = Chart(ALT)
    c.call()
    c.set(I0_0=True)
    c.call()
    assert c.active == ["S2"]


ALT3 = seq("""
  INITIAL_STEP S1 "a": END_STEP
  STEP S2 "b": END_STEP
  STEP S3 "c": END_STEP
  STEP S4 "d": END_STEP
  TRANSITION T5 FROM S1 TO S2 := I0.0;
  TRANSITION T9 FROM S1 TO S3 := I0.1;
  TRANSITION T3 FROM S1 TO S4 := I0.2;
""")


def test_alternative_branch_takes_the_path_below_the_step_then_the_lowest_number() -> None:
    """Manual 6-7: the transition directly below the step (the first written) has priority 1,
    the other paths go by transition number, lowest first — not by written order. The fast
    path and the general path agree."""
    cases = (
        ({"I0_0": True, "I0_1": True, "I0_2": True}, ["S2"], ["T5"]),
        ({"I0_1": True, "I0_2": True}, ["S4"], ["T3"]),  # written order would take T9
        ({"I0_0": True, "I0_2": True}, ["S2"], ["T5"]),  # T5 wins though T3 is lower
        ({"I0_1": True}, ["S3"], ["T9"]),
    )
    for (inputs, active, fired), fast in itertools.product(cases, (True, False)):
        c = Chart(ALT3)
        c.rt = GraphRuntime(c.cc, c.cc.bind(c.mem), fast=fast)
        c.call()
        c.set(**inputs)
        c.call()
        assert (c.active, c.fired) == (active, fired), inputs


SIM = seq("""
  INITIAL_STEP S1 "a": END_STEP
  STEP S2 "b": END_STEP
  STEP S3 "c": END_STEP
  STEP S4 "d": END_STEP
  TRANSITION T1 FROM S1 TO (S2, S3) := I0.0;
  TRANSITION T2 FROM S3 TO S4 := I0.1;
  TRANSITION T3 FROM (S2, S4) TO S1 := I0.2;
""")


def test_simultaneous_divergence_activates_every_path() -> None:
    c = Chart(SIM)
    c.set(I0_0=True)
    c.call(2)
    assert c.active == ["S2", "S3"]


def test_join_waits_for_the_last_step_of_every_path() -> None:
    c = Chart(SIM)
    c.set(I0_0=True, I0_2=True)
    c.call(3)
    assert c.active == ["S2", "S3"]  # S4 not yet active: T3 not valid
    c.set(I0_0=False, I0_1=True)
    c.call()
    assert c.active == ["S2", "S4"]
    c.call()
    assert c.active == ["S1"] and c.fired == ["T3"]


def test_jump_to_the_step_before_the_transition_restarts_it() -> None:
    c = Chart(
        seq("""
      INITIAL_STEP S1 "a": S1 S M0.0; END_STEP
      TRANSITION T1 FROM S1 TO S1 := I0.0;
    """)
    )
    c.call()
    c.set(I0_0=True)
    c.call(3)
    assert c.active == ["S1"] and c.fired == ["T1"]
    st = c.rt.st
    assert st.t_ns[0] == 0


def test_branch_stop_ends_the_path() -> None:
    c = Chart(
        seq("""
      INITIAL_STEP S1 "a": END_STEP
      TRANSITION T1 FROM S1 TO STOP := I0.0;
    """)
    )
    c.set(I0_0=True)
    c.call(2)
    assert c.active == []


def test_jump_into_another_sequencer() -> None:
    c = Chart(
        seq("""
      INITIAL_STEP S1 "a": END_STEP
      TRANSITION T1 FROM S1 TO S12 := I0.0;
    """)
        + seq(
            '  STEP S11 "x": END_STEP\n  STEP S12 "y": END_STEP\n'
            "  TRANSITION T11 FROM S11 TO S12 := FALSE;",
            2,
        )
    )
    c.set(I0_0=True)
    c.call(2)
    assert c.active == ["S12"]


def test_sequencers_run_in_definition_order_and_see_earlier_actions() -> None:
    c = Chart(
        seq("""
      INITIAL_STEP S1 "a": END_STEP
      STEP S2 "b": N M0.0; END_STEP
      TRANSITION T1 FROM S1 TO S2 := I0.0;
    """)
        + seq(
            """
      INITIAL_STEP S11 "x": END_STEP
      STEP S12 "y": END_STEP
      TRANSITION T11 FROM S11 TO S12 := M0.0;
    """,
            2,
        )
    )
    c.call()
    c.set(I0_0=True)
    c.call()  # sequencer 1 enters S2 and sets M0.0 before sequencer 2 evaluates T11
    assert c.active == ["S2", "S12"]


def test_transitions_are_evaluated_on_the_state_at_the_start_of_the_sequencer() -> None:
    # T2 reads S2.X: S2 becomes active in this call, but T2 is evaluated before switching
    c = Chart(
        seq("""
      INITIAL_STEP S1 "a": END_STEP
      STEP S2 "b": END_STEP
      INITIAL_STEP S3 "c": END_STEP
      STEP S4 "d": END_STEP
      TRANSITION T1 FROM S1 TO S2 := I0.0;
      TRANSITION T2 FROM S3 TO S4 := S2.X;
    """)
    )
    c.call()
    c.set(I0_0=True)
    c.call()
    assert c.active == ["S2", "S3"]
    c.call()
    assert c.active == ["S2", "S4"]


def test_permanent_before_runs_before_the_sequencer_and_after_after_it() -> None:
    c = Chart(
        seq("""
      INITIAL_STEP S1 "a": N M1.0; END_STEP
      STEP S2 "b": END_STEP
      TRANSITION T1 FROM S1 TO S2 := M0.0;
    """),
        header="PERMANENT BEFORE\n M0.0 := I0.0;\nEND_PERMANENT\n"
        "PERMANENT AFTER\n M0.1 := M1.0;\nEND_PERMANENT\n",
    )
    c.call()  # first call: init; S1 active
    c.set(I0_0=True)
    c.call()  # M0.0 set before the sequencer: T1 switches in the same call
    assert c.active == ["S2"]
    c2 = Chart(
        seq('INITIAL_STEP S1 "a": N M1.0; END_STEP\nTRANSITION T1 FROM S1 TO STOP := FALSE;'),
        header="PERMANENT AFTER\n M0.1 := M1.0;\nEND_PERMANENT\n",
    )
    c2.call()
    assert c2.q("M0.1")  # after sees the action of this call


def test_step_time_T_keeps_the_last_activation_time_after_exit() -> None:
    c = Chart(LINEAR)
    c.call()
    c.set(I0_0=True)
    c.call()  # S2 active from t=10 ms
    c.call(5)
    c.set(I0_0=False, I0_1=True)
    c.call()
    assert c.active == ["S1"]
    c.call(3)
    assert c.rt.st.step_t_ms(1) == 60


def test_skip_steps_passes_through_a_step_whose_transition_already_holds() -> None:
    body = seq("""
      INITIAL_STEP S1 "a": END_STEP
      STEP S2 "b": S1 S M5.0; END_STEP
      STEP S3 "c": END_STEP
      TRANSITION T1 FROM S1 TO S2 := I0.0;
      TRANSITION T2 FROM S2 TO S3 := I0.1;
    """)
    c = Chart(body, header="SKIP_STEPS := TRUE;")
    c.call()
    c.set(I0_0=True, I0_1=True)
    c.call()
    assert c.active == ["S3"] and not c.q("M5.0")
    off = Chart(body)
    off.call()
    off.set(I0_0=True, I0_1=True)
    off.call()
    assert off.active == ["S2"] and off.q("M5.0")


def test_codesys_order_lets_a_new_step_act_in_the_next_call() -> None:
    body = seq("""
      INITIAL_STEP S1 "a": END_STEP
      STEP S2 "b": N Q0.0; END_STEP
      TRANSITION T1 FROM S1 TO S2 := I0.0;
    """)
    c = Chart(body, header="ORDER := CODESYS;")
    c.call()
    c.set(I0_0=True)
    c.call()
    assert c.active == ["S2"] and not c.q("Q0.0")
    c.call()
    assert c.q("Q0.0")


def test_cost_visits_only_transitions_of_active_steps() -> None:
    """On the general path (the fast path runs the active step's fused function, which
    holds only that step's transitions)."""
    steps = "\n".join(f'STEP S{n} "s": END_STEP' for n in range(2, 50))
    trans = "\n".join(f"TRANSITION T{n} FROM S{n} TO S{n + 1} := TRUE;" for n in range(2, 49))
    first = 'INITIAL_STEP S1 "a": END_STEP\nTRANSITION T1 FROM S1 TO S2 := FALSE;'
    c = Chart(seq(f"{first}\n{steps}\n{trans}"))
    calls: list[int] = []
    prog = c.rt.prog
    c.rt = GraphRuntime(c.cc, prog, fast=False)

    def spy(j: int, f: Any) -> Any:
        return lambda st: (calls.append(j), f(st))[1]

    wrapped = tuple(spy(j, f) for j, f in enumerate(prog.tcond))
    object.__setattr__(prog, "tcond", wrapped)
    c.call(5)
    assert set(calls) == {0}


def test_a_condition_reading_a_word_works_in_a_chart_of_seventeen_steps() -> None:
    """The functions generated per step share one namespace with the runtime's helpers:
    step 17's (index 16) once replaced the helper that reads a signed word."""
    steps = "".join(f"  STEP S{n}: END_STEP\n" for n in range(2, 18))
    arcs = "".join(f"  TRANSITION T{n} FROM S{n} TO S{n + 1} := TRUE;\n" for n in range(2, 17))
    c = Chart(
        seq(
            f"  INITIAL_STEP S1: END_STEP\n{steps}  TRANSITION T1 FROM S1 TO S2 := MW4 > 3;\n{arcs}"
        )
    )
    c.call()
    c.set(MW4=5)
    c.call()
    assert c.active == ["S2"]


def test_no_runtime_helper_is_named_like_a_generated_function() -> None:
    """Generated names are a letter prefix and an element index (``_t3``, ``_s16``)."""
    from s7graph.steps.expressions import RUNTIME as EXPRESSIONS
    from s7graph.steps.operands import RUNTIME as OPERANDS

    assert not [name for name in (*EXPRESSIONS, *OPERANDS) if re.fullmatch(r"_[a-z]+\d+", name)]
