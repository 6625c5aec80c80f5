"""Display outputs and the S_NO/T_NO cursor (docs/semantics.md, "FB pins" and "Decisions").

The state is set by hand here (the cycle is tested elsewhere): these tests pin what the
display computes from a given instance-DB content.
"""

from __future__ import annotations

import pytest

from s7graph.sequencer.compile import compile_chart
from s7graph.sequencer.compiled import CompiledChart
from s7graph.sequencer.display import (
    S_STATE_BITS,
    compute_outputs,
    criteria_by_name,
    page,
    settle,
    shown_step,
)
from s7graph.sequencer.params import outputs_for
from s7graph.sequencer.state import GraphState
from s7graph.sequencer.text.model import (
    Binary,
    Chart,
    ChartOptions,
    Const,
    Operand,
    Sequence,
    Step,
    StepAttr,
    Transition,
    VarDecl,
)
from s7graph.steps.qualifiers import EV_L1, EV_S1


def chart(parameters: str = "USER") -> CompiledChart:
    """S1 -T1-> (S2, S3); S2 -T2 "Down"-> S4; (S4, S3) -T3-> S1. S2 has IL and SV."""
    steps = (
        Step(1, "Ready", initial=True),
        Step(
            2,
            "Clamp",
            interlock=Binary("AND", Operand("I0.0"), Operand("Cl_ok")),
            supervision=Binary(">", StepAttr(2, "U"), Const(500, "TIME", "T#500MS")),
        ),
        Step(3, "Cool"),
        Step(4, "Drill"),
    )
    trans = (
        Transition(1, "Start", (1,), (2, 3), Operand("I0.7")),
        Transition(2, "Down", (2,), (4,), Binary("OR", Operand("I0.2"), Operand("M1.0"))),
        Transition(3, "", (4, 3), (1,), Operand("I0.3")),
    )
    src = Chart(
        name="disp",
        options=ChartOptions(parameters=parameters),
        vars=(VarDecl("Cl_ok", "BOOL"),),
        sequences=(Sequence(1, "Main", steps, trans),),
    )
    return compile_chart(src)


def state_with(ch: CompiledChart, *active: int) -> GraphState:
    st = GraphState(ch.n_steps, ch.n_transitions)
    for n in active:
        st.x[ch.step_index[n]] = True
    return st


def press(ch: CompiledChart, st: GraphState, *edges: str, **inputs: object) -> dict[str, object]:
    page(ch, st, inputs, edges)
    out = compute_outputs(ch, st, inputs, edges)
    settle(ch, st)
    return out


def test_s_no_follows_the_active_step_when_showing_active_steps() -> None:
    ch = chart()
    st = state_with(ch, 1)
    assert press(ch, st)["S_NO"] == 1
    st.x = [False, False, True, False]
    out = press(ch, st)
    assert out["S_NO"] == 3 and out["S_ACTIVE"] is True and out["SACT_DISP"] is True


def test_s_next_pages_through_active_steps_and_never_moves_the_sequence() -> None:
    ch = chart()
    st = state_with(ch, 2, 3)
    before = list(st.x)
    assert press(ch, st)["S_NO"] == 2
    assert press(ch, st, "S_NEXT")["S_NO"] == 3
    assert press(ch, st, "S_NEXT")["S_NO"] == 2  # wraps around
    assert press(ch, st, "S_PREV")["S_NO"] == 3
    assert st.x == before and st.active == [] and st.fired == []


def test_s_more_says_whether_other_steps_can_be_shown() -> None:
    ch = chart()
    assert press(ch, state_with(ch, 2, 3))["S_MORE"] is True
    assert press(ch, state_with(ch, 1))["S_MORE"] is False


def test_disp_sef_shows_only_disturbed_steps_and_zero_when_none() -> None:
    ch = chart()
    st = state_with(ch, 2, 3)
    out = press(ch, st, "DISP_SEF")
    assert out["S_NO"] == 0 and out["SEF_DISP"] is True and out["SACT_DISP"] is False
    st.sv_err[ch.step_index[3]] = True
    assert press(ch, st)["S_NO"] == 3  # the set is kept without a new edge
    st.il_err[ch.step_index[2]] = True
    assert press(ch, st, "S_NEXT")["S_NO"] == 2


def test_disp_sall_pages_through_every_step_active_or_not() -> None:
    ch = chart()
    st = state_with(ch, 1)
    out = press(ch, st, "DISP_SALL")
    assert out["SALL_DISP"] is True and out["S_NO"] == 1
    shown = [press(ch, st, "S_NEXT")["S_NO"] for _ in range(4)]
    assert shown == [2, 3, 4, 1]
    assert press(ch, st, "DISP_SACT")["SACT_DISP"] is True


def test_s_sel_shows_any_step_until_paging_resumes_the_display_set() -> None:
    ch = chart()
    st = state_with(ch, 1)
    out = press(ch, st, S_SEL=4)
    assert out["S_NO"] == 4 and out["S_ACTIVE"] is False
    assert press(ch, st, S_SEL=4)["S_NO"] == 4  # held value: stays pinned
    assert press(ch, st, "S_NEXT", S_SEL=4)["S_NO"] == 1  # paging leaves the pin
    assert press(ch, st, S_SEL=4)["S_NO"] == 1  # unchanged S_SEL does not re-apply
    assert press(ch, st, "S_SELOK", S_SEL=4)["S_NO"] == 4  # S_SELOK applies it again


def test_s_sel_of_an_unknown_step_shows_no_step_until_one_is_chosen() -> None:
    ch = chart()
    st = state_with(ch, 3)
    assert press(ch, st, S_SEL=99)["S_NO"] == 0  # NO_SNO: the selected step does not exist
    assert shown_step(ch, st) == 0
    assert press(ch, st, S_SEL=0)["S_NO"] == 0  # S_SEL 0 chooses nothing
    assert press(ch, st, S_SEL=2)["S_NO"] == 2
    press(ch, st, S_SEL=99)
    assert press(ch, st, "S_NEXT", S_SEL=99)["S_NO"] == 3  # paging shows the set again


def test_shown_step_outputs_time_criteria_and_state_word() -> None:
    ch = chart()
    st = state_with(ch, 2)
    i = ch.step_index[2]
    st.t_ns[i], st.u_ns[i] = 1_234_000_000, 700_000_000
    st.crit_loc[i], st.crit_loc_err[i], st.crit_sup[i] = 0b01, 0b10, 0b1
    st.il_ok[i], st.il_err[i] = False, True
    st.ev[i] = EV_S1 | EV_L1
    out = press(ch, st)
    assert (out["S_TIME"], out["S_TIMEOK"]) == (1234, 700)
    assert (out["S_CRITLOC"], out["S_CRITLOCERR"], out["S_CRITSUP"]) == (1, 2, 1)
    bits = {name: 1 << k for k, name, _ in S_STATE_BITS}
    assert out["S_STATE"] == bits["X"] | bits["LA"] | bits["DISTURBED"] | bits["S1"] | bits["L1"]


def test_s_state_marks_a_latched_fault_whose_cause_has_gone_and_initial_steps() -> None:
    ch = chart()
    st = state_with(ch, 1)
    i = ch.step_index[1]
    st.sv_err[i] = True
    bits = {name: 1 << k for k, name, _ in S_STATE_BITS}
    word = press(ch, st)["S_STATE"]
    assert isinstance(word, int)
    for name in ("X", "VA", "LS", "DISTURBED", "ACK_WAIT", "INIT"):
        assert word & bits[name], name
    assert not word & bits["VS"]
    assert len(S_STATE_BITS) == 16 and [k for k, _, _ in S_STATE_BITS] == list(range(16))


def test_t_no_pages_through_valid_transitions_only() -> None:
    ch = chart()
    st = state_with(ch, 2, 3)  # T2 valid (S2); T3 needs S4 and S3
    out = press(ch, st)
    assert out["T_NO"] == 2 and out["T_MORE"] is False
    st.x[ch.step_index[4]] = True
    st.crit[ch.transition_index[3]] = 1
    st.crit_old[ch.transition_index[3]] = 0
    st.crit_flt[ch.transition_index[3]] = 1
    out = press(ch, st, "T_NEXT")
    assert (out["T_NO"], out["T_MORE"], out["T_CRIT"], out["T_CRITFLT"]) == (3, True, 1, 1)
    assert press(ch, st, "T_PREV")["T_NO"] == 2
    assert press(ch, state_with(ch))["T_NO"] == 0


def test_group_bits_options_and_modes_come_from_the_state() -> None:
    ch = chart()
    st = state_with(ch, 1)
    st.error, st.fault, st.err_flt = True, False, True
    st.off, st.halted, st.tm_halted, st.zeroed = False, True, True, True
    st.il_enabled, st.sv_enabled, st.ackreq_enabled, st.sskip_enabled = False, False, False, True
    st.mode = "TOP"
    out = press(ch, st)
    assert (out["ERROR"], out["FAULT"], out["ERR_FLT"]) == (True, False, True)
    assert (out["SQ_HALTED"], out["TM_HALTED"], out["OP_ZEROED"]) == (True, True, True)
    assert (out["IL_ENABLED"], out["SV_ENABLED"]) == (False, False)
    assert (out["ACKREQ_ENABLED"], out["SSKIP_ENABLED"]) == (False, True)
    assert [out[m] for m in ("AUTO_ON", "TAP_ON", "TOP_ON", "MAN_ON")] == [
        False,
        False,
        True,
        False,
    ]


def test_outputs_are_exactly_those_of_the_charts_parameter_set() -> None:
    ch = chart("STANDARD")
    out = compute_outputs(ch, state_with(ch, 1), {}, ())
    assert list(out) == [p.name for p in outputs_for("STANDARD")]
    assert compute_outputs(ch, state_with(ch, 1), set_name="MINIMUM") == {}


def test_criteria_by_name_lists_each_contact_of_a_transition_interlock_or_supervision() -> None:
    ch = chart()
    st = state_with(ch, 2)
    st.crit[ch.transition_index[2]] = 0b10
    i = ch.step_index[2]
    st.crit_loc[i] = 0b01
    st.crit_sup[i] = 0b1
    assert criteria_by_name(ch, st, "T2") == [("I0.2", False), ("M1.0", True)]
    assert criteria_by_name(ch, st, "down") == criteria_by_name(ch, st, "T2")
    assert criteria_by_name(ch, st, "S2.IL") == [("I0.0", True), ("Cl_ok", False)]
    assert criteria_by_name(ch, st, "s2.supervision") == [("S2.U > T#500MS", True)]
    assert criteria_by_name(ch, st, "S1.IL") == []
    with pytest.raises(KeyError, match="T9"):
        criteria_by_name(ch, st, "T9")
    with pytest.raises(KeyError, match=r"S9\.IL"):
        criteria_by_name(ch, st, "S9.IL")
