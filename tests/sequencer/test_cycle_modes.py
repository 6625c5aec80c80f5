"""Interlock, supervision, acknowledgement, modes and control inputs in the cycle
(docs/semantics.md, "One FB call", steps 1-2, 4.2 and 4.4; "Interlock", "Supervision",
"Modes" and "FB pins")."""

from __future__ import annotations

from s7graph.steps.qualifiers import EV_A1, EV_V0, EV_V1
from tests.sequencer.helpers import Chart, seq

IL = seq("""
  INITIAL_STEP S1 "a":
    INTERLOCK := I0.5;
    N C Q0.0;
    N Q0.1;
    L1 S M1.0;
    L0 S M1.1;
  END_STEP
  STEP S2 "b": END_STEP
  TRANSITION T1 FROM S1 TO S2 := I0.0;
""")


def test_interlock_gates_only_C_rows_and_raises_L1_then_L0() -> None:
    c = Chart(IL)
    c.set(I0_5=True)
    c.call()
    assert c.q("Q0.0") and c.q("Q0.1") and not c.q("M1.0")
    c.set(I0_5=False)
    c.call()
    assert not c.q("Q0.0") and c.q("Q0.1") and c.q("M1.0")
    assert c.rt.st.err_flt and c.rt.st.outputs["ERR_FLT"]
    c.set(I0_5=True)
    c.call()
    assert c.q("Q0.0") and c.q("M1.1") and not c.rt.st.err_flt


def test_interlock_not_held_at_activation_raises_L1() -> None:
    c = Chart(IL)
    c.call()
    assert c.q("M1.0")


def test_interlock_never_blocks_the_transition() -> None:
    c = Chart(IL)
    c.call()
    c.set(I0_0=True)
    c.call()
    assert c.active == ["S2"]


def test_interlock_error_freezes_U_but_not_T() -> None:
    c = Chart(IL)
    c.call(4)
    st = c.rt.st
    assert st.step_t_ms(0) == 30 and st.step_u_ms(0) == 0


def test_en_il_zero_treats_every_interlock_as_held() -> None:
    c = Chart(IL)
    c.set(EN_IL=False)
    c.call()
    assert c.q("Q0.0") and not c.rt.st.err_flt


SV = seq("""
  INITIAL_STEP S1 "a":
    SUPERVISION := I0.6;
    V1 S M2.0;
    A1 S M2.1;
  END_STEP
  STEP S2 "b": END_STEP
  INITIAL_STEP S3 "c": END_STEP
  STEP S4 "d": END_STEP
  TRANSITION T1 FROM S1 TO S2 := I0.0;
  TRANSITION T3 FROM S3 TO S4 := I0.0;
""")


def test_supervision_fault_blocks_only_that_step() -> None:
    c = Chart(SV)
    c.set(I0_6=True)
    c.call()
    assert c.q("M2.0") and c.rt.st.fault
    c.set(I0_0=True)
    c.call()
    assert c.active == ["S1", "S4"]


def test_supervision_fault_stays_latched_until_ack_ef_rising_edge() -> None:
    c = Chart(SV)
    c.set(I0_6=True)
    c.call()
    c.set(I0_6=False, I0_0=True)
    c.call(3)
    assert "S1" in c.active and c.rt.st.outputs["ERR_FLT"]
    c.set(ACK_EF=True)
    c.call()
    assert (0, EV_A1) in c.rt.st.log and (0, EV_V0) in c.rt.st.log
    assert c.active == ["S2", "S4"]


def test_ack_releases_the_step_and_a_persisting_cause_faults_again() -> None:
    c = Chart(SV)
    c.set(I0_6=True)
    c.call()
    c.set(ACK_EF=True)
    c.call()
    assert (0, EV_A1) in c.rt.st.log and (0, EV_V1) in c.rt.st.log
    assert c.rt.st.sv_err[0]
    c.set(ACK_EF=False)
    c.call()
    c.set(ACK_EF=True, I0_0=True)
    c.call()
    assert c.active == ["S2", "S4"]


def test_without_ack_required_the_fault_clears_with_its_cause() -> None:
    c = Chart(SV, header="ACK_REQUIRED := FALSE;")
    c.set(I0_6=True)
    c.call()
    c.set(I0_6=False)
    c.call()
    assert not c.rt.st.fault


def test_supervision_on_step_time_U() -> None:
    c = Chart(
        seq("""
      INITIAL_STEP S1 "a": SUPERVISION := S1.U > T#30MS; END_STEP
      TRANSITION T1 FROM S1 TO STOP := FALSE;
    """)
    )
    c.call(4)
    assert not c.rt.st.fault
    c.call()
    assert c.rt.st.fault


MODES = seq("""
  INITIAL_STEP S1 "a": END_STEP
  STEP S2 "b": END_STEP
  STEP S3 "c": END_STEP
  TRANSITION T1 FROM S1 TO S2 := I0.0;
  TRANSITION T2 FROM S2 TO S3 := I0.1;
""")


def test_man_mode_never_switches_and_s_on_activates_the_selected_step() -> None:
    c = Chart(MODES)
    c.set(SW_MAN=True, I0_0=True)
    c.call(2)
    assert c.active == ["S1"] and c.rt.st.outputs["MAN_ON"]
    c.set(S_SEL=3, S_ON=True)
    c.call()
    assert c.active == ["S1", "S3"]
    c.set(S_SEL=1, S_ON=False, S_OFF=True)
    c.call()
    assert c.active == ["S3"]


def test_tap_mode_needs_condition_and_a_t_push_edge() -> None:
    c = Chart(MODES)
    c.set(SW_TAP=True)
    c.call()
    c.set(T_PUSH=True)
    c.call()
    assert c.active == ["S1"]
    c.set(T_PUSH=False, I0_0=True)
    c.call()
    assert c.active == ["S1"]
    c.set(T_PUSH=True)
    c.call()
    assert c.active == ["S2"]


def test_top_mode_switches_on_condition_or_t_push_edge() -> None:
    c = Chart(MODES)
    c.set(SW_TOP=True)
    c.call()
    c.set(T_PUSH=True)
    c.call()
    assert c.active == ["S2"]
    c.call()  # T_PUSH held: no new edge
    assert c.active == ["S2"]
    c.set(I0_1=True)
    c.call()
    assert c.active == ["S3"]


def test_mode_is_selected_by_a_rising_edge_and_kept() -> None:
    c = Chart(MODES)
    c.set(SW_MAN=True)
    c.call()
    c.set(SW_MAN=False)
    c.call()
    assert c.rt.st.mode == "MAN"
    c.set(SW_AUTO=True)
    c.call()
    assert c.rt.st.mode == "AUTO"


def test_off_sq_deactivates_all_steps_and_init_sq_edge_restores_the_initial_ones() -> None:
    c = Chart(MODES)
    c.set(I0_0=True)
    c.call(2)
    c.set(OFF_SQ=True)
    c.call()
    assert c.active == []
    c.set(OFF_SQ=False, INIT_SQ=True, I0_0=False)
    c.call()
    assert c.active == ["S1"]


def test_off_sq_is_applied_before_init_sq_so_both_in_one_call_initialize() -> None:
    """Step 2 applies OFF_SQ, then INIT_SQ: an INIT_SQ edge while OFF_SQ holds brings the
    initial steps for that call (no switching: OFF_SQ blocks it); the held OFF_SQ switches
    them off again in the next call."""
    c = Chart(MODES)
    c.set(I0_0=True)
    c.call(2)
    assert c.active == ["S2"]
    c.set(OFF_SQ=True, INIT_SQ=True)
    c.call()
    assert c.active == ["S1"]
    c.set(INIT_SQ=False)
    c.call()
    assert c.active == []


def test_halt_sq_stops_switching_and_halt_tm_freezes_times() -> None:
    c = Chart(MODES)
    c.set(HALT_SQ=True, HALT_TM=True, I0_0=True)
    c.call(3)
    assert c.active == ["S1"] and c.rt.st.step_t_ms(0) == 0
    c.set(HALT_SQ=False, HALT_TM=False)
    c.call()
    assert c.active == ["S2"]
