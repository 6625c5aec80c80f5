"""docs/semantics.md, "Interlock", "Supervision", "Modes" and "FB pins" (control inputs): the
rules not pinned in ``test_interlock_supervision_modes.py`` / ``test_cycle_modes.py``.

Driven through the real cycle (``GraphRuntime``) by the scenario harness, 10 ms per call;
the warm restart through a CPU.
"""

from __future__ import annotations

from s7graph.engine.clock import VirtualClock
from s7graph.engine.cpu import Cpu
from s7graph.sequencer.compile import compile_chart
from s7graph.sequencer.fb import GraphFB, install_all
from s7graph.sequencer.text.parse import parse_chart
from tests.sequencer.helpers import chart, enter, seq, source, two_steps

# ---------------------------------------------------------------- interlock


def test_l1_row_runs_once_while_the_interlock_stays_lost_and_l0_once_on_return() -> None:
    """docs/semantics.md, "Interlock" and "Actions": L1 fires when the interlock is lost, L0 when it
    returns — once each."""
    run = two_steps(
        "L1 N lost := lost + 1; L0 N back := back + 1;",
        header="VAR lost : INT := 0; back : INT := 0; END_VAR",
        interlock="I0.5",
    )
    run.set(I0_5=True)
    enter(run)
    run.set(I0_5=False).call(5)
    assert run.st.vars["lost"] == 1 and run.out("ERR_FLT") is True
    run.set(I0_5=True).call(5)
    assert run.st.vars["back"] == 1 and run.st.vars["lost"] == 1
    assert run.out("ERR_FLT") is False


def test_interlock_lost_stops_u_so_a_supervision_on_u_waits() -> None:
    """docs/semantics.md, "Interlock": while the interlock does not hold U stops counting (a
    supervision `S2.U > T#50MS` is then not reached)."""
    run = chart(
        seq("""
      INITIAL_STEP S1 "a": END_STEP
      STEP S2 "b": INTERLOCK := I0.5; SUPERVISION := S2.U > T#50MS; END_STEP
      TRANSITION T1 FROM S1 TO S2 := I0.0;
      TRANSITION T2 FROM S2 TO S1 := FALSE;
    """)
    )
    run.call()
    run.set(I0_0=True).call()  # S2 without its interlock from the start
    run.set(I0_0=False).call(20)
    assert run.out("ERR_FLT") is True and run.st.step_u_ms(run.idx(2)) == 0
    assert "V1" not in run.events(2)
    run.set(I0_5=True).call(2)
    assert run.out("ERR_FLT") is False  # interlock back, U at 10 ms: no fault yet
    run.call(5)
    assert run.out("ERR_FLT") is True  # U passed 50 ms: a supervision fault


# ---------------------------------------------------------------- supervision


def test_a_fault_present_on_activation_raises_v1_and_holds_the_step() -> None:
    """docs/semantics.md, "Supervision": a supervision fault raises V1 (also when already present as
    the step becomes active) and stops that step from switching."""
    run = chart(
        seq("""
      INITIAL_STEP S1 "a": END_STEP
      STEP S2 "b": SUPERVISION := I0.6; V1 S M1.2; END_STEP
      STEP S3 "c": END_STEP
      TRANSITION T1 FROM S1 TO S2 := I0.0;
      TRANSITION T2 FROM S2 TO S3 := I0.1;
    """)
    )
    run.call()
    run.set(I0_6=True, I0_0=True).call()
    assert run.active == [2] and "V1" in run.events(2) and run.get("M1.2") is True
    run.set(I0_6=False, I0_1=True).call(3)
    assert run.active == [2]  # acknowledge required: still latched
    run.pulse("ACK_EF")
    run.call()
    assert run.active == [3]


def test_a_fault_in_one_path_blocks_the_join_of_a_simultaneous_branch() -> None:
    """docs/semantics.md, "One FB call", step 4.2 and "Supervision": no preceding step of a
    switching transition may hold an unacknowledged supervision error — also at a join."""
    run = chart(
        seq("""
      INITIAL_STEP S1 "a": END_STEP
      STEP S2 "b": SUPERVISION := I0.6; END_STEP
      STEP S3 "c": END_STEP
      TRANSITION T1 FROM S1 TO (S2, S3) := I0.0;
      TRANSITION T2 FROM (S2, S3) TO S1 := I0.1;
    """)
    )
    run.call()
    run.set(I0_0=True).call()
    run.set(I0_0=False, I0_6=True).call()
    run.set(I0_6=False, I0_1=True).call(3)
    assert run.active == [2, 3]
    run.pulse("ACK_EF")
    assert run.active == [1]


def test_a_supervision_fault_sets_fault_and_acknowledgement_clears_it() -> None:
    """docs/semantics.md, "Supervision": a fault sets FAULT and ERR_FLT (USER set) until
    acknowledged."""
    run = chart(
        seq("""
      INITIAL_STEP S1 "a": SUPERVISION := I0.6; END_STEP
      TRANSITION T1 FROM S1 TO STOP := FALSE;
    """),
        params="USER",
    )
    run.set(I0_6=True).call()
    run.set(I0_6=False).call(2)
    assert run.out("FAULT") is True and run.out("ERR_FLT") is True
    run.pulse("ACK_EF")
    assert run.out("FAULT") is False and run.out("ERR_FLT") is False


# ---------------------------------------------------------------- modes

CPU_CHART = source(
    seq("""
  INITIAL_STEP S1 "a": END_STEP
  STEP S2 "b": N Q0.0; END_STEP
  TRANSITION T1 FROM S1 TO S2 := I0.0;
""")
)


def test_the_mode_survives_a_warm_restart_of_the_cpu() -> None:
    """docs/semantics.md, "Modes": the mode is kept in the instance DB (survives warm restart)."""
    clock = VirtualClock()
    cpu = Cpu(clock)
    g = GraphFB(compile_chart(parse_chart(CPU_CHART, "m.s7g")))
    install_all(cpu, [g])
    cpu.start("warm")
    assert g.idb is not None
    g.idb.values["SW_MAN"] = True
    clock.advance(10)
    cpu.scan()
    g.idb.values["SW_MAN"] = False
    clock.advance(10)
    cpu.scan()
    assert g.outputs["MAN_ON"] is True
    cpu.stop()
    cpu.start("warm")
    cpu.mem.periph_in[0] = 1
    for _ in range(3):
        clock.advance(10)
        cpu.scan()
    assert g.outputs["MAN_ON"] is True and g.state.mode == "MAN"
    assert cpu.mem.get("Q0.0") is False  # MAN: T1 never switches


def test_top_push_at_an_alternative_divergence_switches_only_the_first_listed_path() -> None:
    """docs/semantics.md, "One FB call", step 4.2 and "Modes": in TOP a T_PUSH edge switches, but at
    an alternative divergence at most one path — the first-listed."""
    run = chart(
        seq("""
      INITIAL_STEP S1 "a": END_STEP
      STEP S2 "b": END_STEP
      STEP S3 "c": END_STEP
      TRANSITION T7 FROM S1 TO S3 := FALSE;
      TRANSITION T2 FROM S1 TO S2 := FALSE;
    """)
    )
    run.call()
    run.pulse("SW_TOP")
    run.pulse("T_PUSH")
    assert run.active == [3]


def test_tap_push_without_the_condition_does_not_switch() -> None:
    """docs/semantics.md, "One FB call", step 4.2: TAP is condition AND a T_PUSH edge."""
    run = two_steps("N Q0.0;")
    run.call()
    run.pulse("SW_TAP")
    run.pulse("T_PUSH")
    assert run.active == [1]


# ---------------------------------------------------------------- control inputs


def test_halt_tm_freezes_u_so_a_time_supervision_waits() -> None:
    """docs/semantics.md, "FB pins": HALT_TM freezes the step times (a supervision on S2.U does not
    fire)."""
    run = chart(
        seq("""
      INITIAL_STEP S1 "a": END_STEP
      STEP S2 "b": SUPERVISION := S2.U > T#50MS; END_STEP
      TRANSITION T1 FROM S1 TO S2 := I0.0;
      TRANSITION T2 FROM S2 TO S1 := FALSE;
    """)
    )
    run.call()
    run.set(I0_0=True, HALT_TM=True).call()
    run.set(I0_0=False).call(20)
    assert run.out("ERR_FLT") is False and run.st.step_t_ms(run.idx(2)) == 0
    run.set(HALT_TM=False).call(7)
    assert run.out("ERR_FLT") is True


def test_halt_sq_keeps_the_steps_and_their_actions() -> None:
    """docs/semantics.md, "FB pins": HALT_SQ: no switching, steps stay active (and keep acting)."""
    run = two_steps("N Q0.0; N n := n + 1;", header="VAR n : INT := 0; END_VAR")
    enter(run)
    run.set(HALT_SQ=True, I0_1=True).call(4)
    assert run.active == [2] and run.get("Q0.0") is True and run.st.vars["n"] == 5
    assert run.out("SQ_HALTED") is True
    run.set(HALT_SQ=False).call()
    assert run.active == [3] and run.out("SQ_HALTED") is False


def test_off_sq_runs_the_s0_rows_of_the_steps_it_switches_off() -> None:
    """docs/semantics.md, "FB pins" OFF_SQ: all steps off — as deactivation, with the final scan (N
    to 0)."""
    run = two_steps("N Q0.0; S0 S M0.7;")
    enter(run)
    run.set(OFF_SQ=True).call()
    assert run.active == [] and run.get("Q0.0") is False and run.get("M0.7") is True


def test_a_t_push_in_top_does_not_switch_a_step_with_a_latched_fault() -> None:
    """docs/semantics.md, "One FB call", step 4.2 and "Supervision": an unacknowledged supervision
    error blocks switching in any mode — also a TOP push."""
    run = chart(
        seq("""
      INITIAL_STEP S1 "a": SUPERVISION := I0.6; END_STEP
      STEP S2 "b": END_STEP
      TRANSITION T1 FROM S1 TO S2 := FALSE;
    """)
    )
    run.set(I0_6=True).call()
    run.set(I0_6=False).call()
    run.pulse("SW_TOP")
    run.pulse("T_PUSH")
    assert run.active == [1]
    run.pulse("ACK_EF")
    run.pulse("T_PUSH")
    assert run.active == [2]


def test_man_s_on_raises_the_s1_event_of_the_step() -> None:
    """docs/semantics.md, "Modes" and "Actions": a step activated by S_ON runs its S1 rows."""
    run = two_steps("S1 S M4.0;")
    run.call()
    run.pulse("SW_MAN")
    run.set(S_SEL=2)
    run.pulse("S_ON")
    assert run.active == [1, 2] and run.get("M4.0") is True


def test_rows_marked_c_do_not_run_while_the_interlock_does_not_hold() -> None:
    """docs/semantics.md, "Interlock": while the interlock does not hold, rows marked C (N, S, D) do
    not run; they run once it holds."""
    run = two_steps("NC Q0.0; SC Q0.1; D C Q0.2, T#20MS; N Q0.3;", interlock="I0.5")
    enter(run)
    run.call(3)
    assert [run.get(f"Q0.{k}") for k in range(4)] == [False, False, False, True]
    run.set(I0_5=True).call()
    assert run.get("Q0.0") is True and run.get("Q0.1") is True


def test_l1_off_s_all_switches_every_other_step_off() -> None:
    """docs/semantics.md, "Actions": `L1 OFF S_ALL` — on losing the interlock every other step goes
    off."""
    run = chart(
        seq("""
      INITIAL_STEP S1 "a": END_STEP
      INITIAL_STEP S3 "c": INTERLOCK := I0.5; L1 OFF S_ALL; END_STEP
      TRANSITION T1 FROM S1 TO STOP := FALSE;
      TRANSITION T3 FROM S3 TO STOP := FALSE;
    """)
    )
    run.set(I0_5=True).call()
    assert run.active == [1, 3]
    run.set(I0_5=False).call()
    assert run.active == [3]


def test_counter_rows_on_events_preset_and_count() -> None:
    """docs/semantics.md, "Actions": counters with any event — `S1 CS C 1, C#5` then `S0 CU C 1`."""
    run = two_steps("S1 CS C 1, C#5; S0 CU C 1;")
    enter(run)
    assert run.mem.counters[1].value == 5
    run.set(I0_1=True).call()
    assert run.mem.counters[1].value == 6
