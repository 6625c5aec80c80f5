"""One test per rule of docs/semantics.md, "Interlock", "Supervision", "Modes" and "FB pins"
(control inputs), through the real cycle. Chart: scenarios/rules.s7g — S2 is guarded
(interlock I0.0, supervision I0.6, a row per event: L1→M1.1 L0→M1.0 V1→M1.2 V0→M1.3
A1→M1.4 R1→M1.5), S4 the parallel path, S11/S12 a second sequencer."""

from __future__ import annotations

import pytest

from s7graph.sequencer.state import GraphState
from tests.sequencer.helpers import Run, chart_text


def rules(options: str = "") -> Run:
    text, file = chart_text("rules")
    run = Run(text.replace("OPTIONS", options), file=file)
    run.set(I0_0=True).call()
    assert run.active == [1, 11]
    return run


def guarded(options: str = "", **inputs: bool) -> Run:
    """S2 (and S4) active, entered with ``inputs`` held."""
    run = rules(options)
    run.set(I0_1=True, **inputs).call()
    run.set(I0_1=False).call()
    assert run.active == [2, 4, 11]
    return run


def faulted(options: str = "") -> Run:
    """S2 with a supervision fault whose cause has gone, its transition I0.2 holding."""
    run = guarded(options)
    run.set(I0_6=True).call()
    run.set(I0_6=False, I0_2=True).call(3)
    return run


# ---------------------------------------------------------------- interlock


def test_interlock_lost_stops_only_the_c_rows() -> None:
    run = guarded()
    assert run.get("Q0.0") is True and run.get("Q0.1") is True
    run.set(I0_0=False).call()
    assert run.get("Q0.0") is False and run.get("Q0.1") is True


def test_interlock_lost_raises_l1_and_its_return_raises_l0() -> None:
    run = guarded()
    run.set(I0_0=False).call()
    assert "L1" in run.events(2) and run.get("M1.1") is True and run.get("M1.0") is False
    run.call()
    assert "L1" not in run.events(2)  # once, in the call it occurs
    run.set(I0_0=True).call()
    assert "L0" in run.events(2) and run.get("M1.0") is True and run.get("Q0.0") is True


def test_interlock_not_held_on_activation_raises_l1() -> None:
    run = rules()
    run.set(I0_0=False, I0_1=True).call()
    assert {"S1", "L1"} <= run.events(2) and run.get("Q0.0") is False


def test_interlock_error_sets_error_and_err_flt_and_shows_the_step_disturbed() -> None:
    run = guarded()
    run.set(I0_0=False, S_SEL=2).call()
    assert run.out("ERROR") and run.out("ERR_FLT") and not run.out("FAULT")
    assert run.out("S_NO") == 2 and run.out("S_STATE") & 0b10  # LA: red
    run.set(DISP_SEF=True).call()
    run.set(S_NEXT=True).call()
    assert run.out("S_NO") == 2 and not run.out("S_MORE")  # the only disturbed step


def test_interlock_error_freezes_u_while_t_keeps_counting() -> None:
    run = guarded()
    i = run.idx(2)
    u0, t0 = run.st.step_u_ms(i), run.st.step_t_ms(i)
    run.set(I0_0=False).call(10)
    assert run.st.step_u_ms(i) - u0 <= 10 and run.st.step_t_ms(i) - t0 >= 100


def test_interlock_error_never_blocks_the_transition() -> None:
    run = guarded()
    run.set(I0_0=False).call()
    run.set(I0_2=True).call()
    assert run.active == [3, 4, 11]


def test_interlock_error_clears_itself_without_acknowledgement() -> None:
    run = guarded()
    run.set(I0_0=False).call()
    run.set(I0_0=True).call()
    assert not run.out("ERR_FLT") and not run.st.il_err[run.idx(2)]


def test_en_il_zero_treats_every_interlock_as_held() -> None:
    run = guarded(I0_0=False)
    assert run.get("Q0.0") is False
    run.set(EN_IL=False).call()
    assert run.get("Q0.0") is True and not run.out("ERROR") and not run.out("IL_ENABLED")


# ---------------------------------------------------------------- supervision


def test_supervision_fault_raises_v1_and_sets_fault_and_err_flt() -> None:
    run = guarded()
    run.set(I0_6=True).call()
    assert "V1" in run.events(2) and run.get("M1.2") is True
    assert run.out("FAULT") and run.out("ERR_FLT") and not run.out("ERROR")


def test_supervision_fault_freezes_u() -> None:
    run = guarded()
    i = run.idx(2)
    run.set(I0_6=True).call()
    u0 = run.st.step_u_ms(i)
    run.call(10)
    assert run.st.step_u_ms(i) == u0 and run.st.step_t_ms(i) >= u0 + 100


def test_supervision_error_holds_step_until_acknowledged() -> None:
    run = faulted()
    run.call(20)
    assert run.active == [2, 4, 11] and run.out("FAULT")  # cause gone, still latched
    assert run.out("S_STATE") & 0b1000100 == 0b1000100  # VA and ACK_WAIT


def test_supervision_fault_lets_other_paths_and_sequencers_carry_on() -> None:
    run = guarded()
    run.set(I0_6=True).call()
    run.set(I0_2=True, I0_4=True, I1_1=True).call()
    assert run.active == [2, 5, 12]


def test_ack_ef_rising_edge_acknowledges_with_a1_and_v0_and_the_step_switches() -> None:
    run = faulted()
    run.set(ACK_EF=True).call()
    assert {"A1", "V0"} <= run.events(2) and run.active == [3, 4, 11]
    assert not run.out("ERR_FLT")


def test_a1_and_v0_rows_run_when_the_step_stays_after_acknowledgement() -> None:
    run = guarded()
    run.set(I0_6=True).call()
    run.set(I0_6=False).call()
    run.set(ACK_EF=True).call()
    assert run.active == [2, 4, 11] and run.get("M1.4") is True and run.get("M1.3") is True


def test_ack_ef_held_high_does_not_acknowledge_a_later_fault() -> None:
    run = guarded()
    run.set(ACK_EF=True).call()
    run.set(I0_6=True).call()
    run.set(I0_6=False).call(5)
    assert run.out("FAULT")  # no new edge


def test_ack_s_acknowledges_only_the_step_shown_in_s_no() -> None:
    run = faulted()
    run.set(S_SEL=4)
    run.pulse("ACK_S")
    assert run.out("FAULT") and run.active == [2, 4, 11]  # S4 shown: nothing to ack
    run.set(S_SEL=2).call()
    run.set(ACK_S=True).call()
    assert "A1" in run.events(2) and run.active == [3, 4, 11]


def test_without_acknowledge_required_v0_fires_when_the_condition_clears() -> None:
    run = guarded("ACK_REQUIRED := FALSE;")
    run.set(I0_6=True).call()
    run.set(I0_6=False).call()
    assert "V0" in run.events(2) and "A1" not in run.events(2) and not run.out("FAULT")
    assert not run.out("ACKREQ_ENABLED")


def test_en_ackreq_pin_turns_the_acknowledge_requirement_off_at_runtime() -> None:
    run = guarded()
    run.set(EN_ACKREQ=False, I0_6=True).call()
    run.set(I0_6=False).call()
    assert "V0" in run.events(2) and not run.out("FAULT")


def test_acknowledgement_does_not_force_switching_by_default() -> None:
    run = faulted()
    run.set(I0_2=False, ACK_EF=True).call(3)
    assert run.active == [2, 4, 11] and not run.out("FAULT")


def test_ack_forces_switch_option_switches_on_acknowledgement_alone() -> None:
    run = faulted("ACK_FORCES_SWITCH := TRUE;")
    run.set(I0_2=False, ACK_EF=True).call()
    assert run.active == [3, 4, 11]


def test_en_sv_zero_disables_supervision() -> None:
    run = guarded()
    run.set(EN_SV=False, I0_6=True, I0_2=True).call()
    assert not run.out("FAULT") and not run.out("SV_ENABLED") and run.active == [3, 4, 11]


def test_ack_releases_a_time_supervision_frozen_by_its_own_fault() -> None:
    """``S1.U > limit`` stays true once the fault froze U: the acknowledgement must still
    release the step for the call's switching (docs/semantics.md, "Supervision")."""
    run = Run(
        'FUNCTION_BLOCK "U" PARAMETERS := STANDARD; SEQUENCE 1 "s"\n'
        'INITIAL_STEP S1 "a": SUPERVISION := S1.U > T#50MS; END_STEP\n'
        'STEP S2 "b": END_STEP\n'
        "TRANSITION T1 FROM S1 TO S2 := I0.0;\nEND_SEQUENCE\nEND_FUNCTION_BLOCK\n"
    )
    run.call(10)
    assert run.out("ERR_FLT")
    run.set(I0_0=True, ACK_EF=True).call()
    assert run.active == [2]


# ---------------------------------------------------------------- modes


def test_mode_is_chosen_by_sw_edges_and_kept_in_the_instance_db() -> None:
    run = rules()
    run.pulse("SW_TOP")
    assert run.out("TOP_ON") and run.st.mode == "TOP"
    kept = GraphState.from_state(run.st.to_state())
    assert kept.mode == "TOP"
    run.set(SW_TAP=True).call()
    run.set(SW_TAP=True).call(3)
    assert run.out("TAP_ON")


def test_tap_switches_on_condition_and_a_t_push_edge() -> None:
    run = rules()
    run.pulse("SW_TAP")
    run.set(I0_1=True).call(3)
    assert run.active == [1, 11]
    run.set(T_PUSH=True).call()
    assert run.active == [2, 4, 11]
    run.set(I0_2=True).call(3)  # T_PUSH held: no new edge
    assert 2 in run.active


def test_top_switches_on_condition_or_a_t_push_edge() -> None:
    run = rules()
    run.pulse("SW_TOP")
    run.pulse("T_PUSH")
    assert run.active == [2, 4, 12]  # the push switches every valid transition
    run.set(I0_2=True).call()
    assert 3 in run.active


def test_man_selects_a_step_with_s_sel_and_switches_it_with_s_on_and_s_off() -> None:
    run = rules()
    run.pulse("SW_MAN")
    run.set(S_SEL=3)
    run.pulse("S_ON")
    assert run.active == [1, 3, 11] and run.out("S_NO") == 3
    run.pulse("S_OFF")
    assert run.active == [1, 11]


def test_man_never_switches_a_transition() -> None:
    run = rules()
    run.pulse("SW_MAN")
    run.set(I0_1=True, I1_1=True).call(5)
    assert run.active == [1, 11]


# ---------------------------------------------------------------- control inputs


def test_off_sq_switches_every_step_off_while_set() -> None:
    run = guarded()
    run.set(OFF_SQ=True).call()
    assert run.active == [] and run.out("SQ_ISOFF") and run.get("Q0.1") is False
    run.set(I1_1=True).call()
    assert run.active == []


def test_init_sq_edge_restores_the_initial_steps_and_clears_errors() -> None:
    run = guarded()
    run.set(I0_6=True).call()
    run.set(I0_6=False, INIT_SQ=True).call()
    assert run.active == [1, 11] and not run.out("ERR_FLT")
    run.set(I0_1=True).call()
    assert run.active == [2, 4, 11]  # INIT_SQ held: no new initialization


def test_halt_sq_stops_switching_and_keeps_the_steps() -> None:
    run = guarded()
    run.set(HALT_SQ=True, I0_2=True, I0_4=True, I1_1=True).call(3)
    assert run.active == [2, 4, 11] and run.out("SQ_HALTED") and run.get("Q0.1") is True
    run.set(HALT_SQ=False).call()
    assert run.active == [3, 5, 12]


def test_halt_tm_freezes_step_times_and_d_l_timing() -> None:
    run = guarded()
    i = run.idx(2)
    run.set(HALT_TM=True).call(30)
    t = run.st.step_t_ms(i)
    assert t < 100 and run.out("TM_HALTED")
    assert run.get("Q0.5") is False and run.get("Q0.6") is True  # D not yet, L still on
    run.set(HALT_TM=False).call(15)
    assert run.get("Q0.5") is True and run.get("Q0.6") is False


def test_zero_op_forces_n_d_l_operands_to_zero() -> None:
    run = guarded()
    run.call(12)
    assert run.get("Q0.1") is True and run.get("Q0.5") is True
    run.set(ZERO_OP=True).call()
    assert run.out("OP_ZEROED")
    assert run.get("Q0.1") is False and run.get("Q0.0") is False and run.get("Q0.5") is False
    assert run.active == [2, 4, 11]


def test_zero_op_skips_calls() -> None:
    run = Run(
        'FUNCTION_BLOCK "Z" PARAMETERS := MAXIMUM; SEQUENCE 1 "s"\n'
        'INITIAL_STEP S1 "a": CALL FC 1; END_STEP\n'
        "TRANSITION T1 FROM S1 TO STOP := FALSE;\nEND_SEQUENCE\nEND_FUNCTION_BLOCK\n"
    )
    run.set(ZERO_OP=True).call(3)  # the harness binds no block runtime: a CALL would raise
    with pytest.raises(RuntimeError, match="CALL FC 1"):
        run.set(ZERO_OP=False).call()


def test_zero_op_holds_back_assignments_as_it_skips_calls() -> None:
    """An assignment is an N action: under ZERO_OP it does not run (its variable keeps its
    value, as an N bit goes to 0 and a CALL is skipped); released, it runs again."""
    run = Run(
        'FUNCTION_BLOCK "Z" PARAMETERS := MAXIMUM; VAR n : INT := 0; END_VAR\n'
        'SEQUENCE 1 "s"\nINITIAL_STEP S1 "a": N n := n + 1; END_STEP\n'
        "TRANSITION T1 FROM S1 TO STOP := FALSE;\nEND_SEQUENCE\nEND_FUNCTION_BLOCK\n"
    )
    run.call(2)
    assert run.st.vars["n"] == 2
    run.set(ZERO_OP=True).call(3)
    assert run.st.vars["n"] == 2 and run.out("OP_ZEROED")
    run.set(ZERO_OP=False).call()
    assert run.st.vars["n"] == 3


def test_s_prev_s_next_only_page_the_display() -> None:
    run = guarded()
    shown = []
    for pin in ("S_NEXT", "S_NEXT", "S_PREV"):
        run.pulse(pin)
        shown.append(run.out("S_NO"))
    assert shown == [4, 11, 4] and run.active == [2, 4, 11]
    run.pulse("T_NEXT")
    assert run.out("T_NO") == 3 and run.active == [2, 4, 11]  # T2 -> T3 (valid: T2 T3 T11)


def test_reg_ef_and_reg_s_raise_r1() -> None:
    run = guarded()
    run.set(I0_0=False).call()
    run.set(REG_EF=True).call()
    assert "R1" in run.events(2) and run.get("M1.5") is True
    run.set(REG_EF=False, M1_5=False, S_SEL=2).call()
    run.set(REG_S=True).call()
    assert "R1" in run.events(2) and run.get("M1.5") is True
