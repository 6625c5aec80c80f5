"""docs/semantics.md, "Actions" and "Conditions": the rules not pinned elsewhere.

Driven through the real cycle (``GraphRuntime``) by the scenario harness, 10 ms per call;
the CALL rules through a CPU (OB1 calls the GraphFB, which calls an FC).
"""

from __future__ import annotations

import pytest

from s7graph.engine.blocks import fc
from s7graph.engine.clock import VirtualClock
from s7graph.engine.cpu import Cpu
from s7graph.sequencer.checks.validate import validate
from s7graph.sequencer.compile import compile_chart
from s7graph.sequencer.fb import GraphFB, install_all
from s7graph.sequencer.text.parse import parse_chart
from tests.sequencer.helpers import chart, enter, leave, seq, source, two_steps

# ---------------------------------------------------------------- qualifiers


def test_plain_s_row_re_issues_the_set_every_cycle_while_s1_s_sets_once() -> None:
    """docs/semantics.md, "One FB call", step 4.5 and "Actions": a plain S row runs every cycle
    while the step is active; an S1 S row only in the activation call."""
    run = two_steps("S M0.0; S1 S M0.1;")
    enter(run)
    assert run.get("M0.0") is True and run.get("M0.1") is True
    run.set(M0_0=False, M0_1=False).call()
    assert run.get("M0.0") is True and run.get("M0.1") is False


def test_n_operand_is_zero_after_the_step_is_left_but_s_stays_set() -> None:
    """docs/semantics.md, "Actions": N is 0 after the step is left; S / R latch."""
    run = two_steps("N Q0.0; S Q0.1;")
    enter(run)
    leave(run)
    run.call(3)
    assert run.get("Q0.0") is False and run.get("Q0.1") is True


def test_d_operand_is_never_set_when_the_step_is_left_before_its_time() -> None:
    """docs/semantics.md, "Actions" D: never set if left earlier — also not after a re-entry that is
    again shorter than the time (the delay restarts at each activation)."""
    run = two_steps("D Q0.0, T#50MS;")
    enter(run)
    run.call(2)
    leave(run)
    run.set(I0_2=True).call()
    run.set(I0_2=False, I0_0=True).call()
    run.set(I0_0=False).call(2)
    assert run.active == [2] and run.get("Q0.0") is False
    run.call(3)
    assert run.get("Q0.0") is True


def test_d_time_may_be_a_time_variable() -> None:
    """docs/semantics.md, "Actions": D takes a bit and a TIME (here an FB variable)."""
    run = two_steps("D Q0.0, dwell;", header="VAR dwell : TIME := T#40MS; END_VAR")
    enter(run)
    run.call(2)
    assert run.get("Q0.0") is False
    run.call(3)
    assert run.get("Q0.0") is True


def test_l_operand_is_one_from_activation_and_zero_after_its_time_while_active() -> None:
    """docs/semantics.md, "Actions" L: 1 from activation for the time, then 0 (the step stays
    active)."""
    run = two_steps("L Q0.0, T#50MS;")
    enter(run)
    assert run.get("Q0.0") is True
    run.call(3)
    assert run.get("Q0.0") is True
    run.call(5)
    assert run.active == [2] and run.get("Q0.0") is False


def test_halt_tm_keeps_a_d_operand_from_being_set() -> None:
    """docs/semantics.md, "FB pins" HALT_TM: D timing frozen — D does not come while the time is
    halted."""
    run = two_steps("D Q0.0, T#50MS;")
    enter(run)
    run.set(HALT_TM=True).call(20)
    assert run.get("Q0.0") is False and run.out("TM_HALTED") is True
    run.set(HALT_TM=False).call(6)
    assert run.get("Q0.0") is True


def test_zero_op_forces_d_and_l_operands_to_zero_and_they_return_after() -> None:
    """docs/semantics.md, "FB pins" ZERO_OP: N, D, L operands forced to 0 while set; S rows still
    run."""
    run = two_steps("N Q0.0; D Q0.1, T#20MS; L Q0.2, T#1S; S Q0.3;")
    enter(run)
    run.call(3)
    assert [run.get(f"Q0.{k}") for k in range(4)] == [True, True, True, True]
    run.set(Q0_3=False, ZERO_OP=True).call()
    assert [run.get(f"Q0.{k}") for k in range(3)] == [False, False, False]
    assert run.get("Q0.3") is True
    run.set(ZERO_OP=False).call()
    assert [run.get(f"Q0.{k}") for k in range(3)] == [True, True, True]


def test_time_assignment_every_cycle() -> None:
    """docs/semantics.md, "Actions": `N A := expr` with TIME runs every cycle while the step is
    active."""
    run = two_steps("N t := t + T#10MS;", header="VAR t : TIME := T#0MS; END_VAR")
    enter(run)
    run.call(4)
    assert run.st.vars["t"] == 50


def test_dint_and_real_assignments() -> None:
    """docs/semantics.md, "Actions": assignments of DINT and REAL values."""
    run = two_steps(
        "S1 N d := d * 1000; S1 N r := r / 4.0;",
        header="VAR d : DINT := L#70000; r : REAL := 1.0; END_VAR",
    )
    enter(run)
    assert run.st.vars["d"] == 70_000_000 and run.st.vars["r"] == pytest.approx(0.25)
    assert not run.st.ov


def test_int_overflow_in_an_assignment_leaves_the_sequencer_running() -> None:
    """docs/semantics.md, "Actions": INT overflow sets the overflow status; the chart keeps
    switching."""
    run = two_steps("N x := x + 20000;", header="VAR x : INT := 20000; END_VAR")
    enter(run)
    assert run.st.ov
    leave(run)
    assert run.active == [3]


def _cpu_with_fc(rows: str) -> tuple[Cpu, VirtualClock, GraphFB]:
    text = source(
        seq(f"""
      INITIAL_STEP S1 "a": END_STEP
      STEP S2 "b": {rows} END_STEP
      TRANSITION T1 FROM S1 TO S2 := I0.0;
      TRANSITION T2 FROM S2 TO S1 := I0.1;
    """)
    )

    @fc(1, "Count")
    def count(ctx, params) -> None:
        ctx.mem.set("MW20", ctx.mem.get("MW20") + 1)

    clock = VirtualClock()
    cpu = Cpu(clock)
    g = GraphFB(compile_chart(parse_chart(text, "call.s7g")))
    cpu.load(count)
    install_all(cpu, [g])
    cpu.start("warm")
    return cpu, clock, g


def _scan(cpu: Cpu, clock: VirtualClock, n: int = 1, **inputs: bool) -> None:
    for name, value in inputs.items():
        cpu.mem.set(name.replace("_", "."), value)
    for _ in range(n):
        clock.advance(10)
        cpu.scan()


def test_call_row_calls_the_block_every_cycle_while_the_step_is_active() -> None:
    """docs/semantics.md, "Actions" CALL: called every cycle (and not once the step is left)."""
    cpu, clock, _ = _cpu_with_fc("CALL FC 1;")
    _scan(cpu, clock, 2)
    assert cpu.mem.get("MW20") == 0
    cpu.mem.periph_in[0] = 1
    _scan(cpu, clock, 1)
    cpu.mem.periph_in[0] = 0
    _scan(cpu, clock, 4)
    assert cpu.mem.get("MW20") == 5
    cpu.mem.periph_in[0] = 2
    _scan(cpu, clock, 1)
    cpu.mem.periph_in[0] = 0
    _scan(cpu, clock, 3)
    assert cpu.mem.get("MW20") == 5


def test_s1_call_row_calls_the_block_once_per_activation() -> None:
    """docs/semantics.md, "Actions": an event row (S1 CALL) runs once, in the call of its event."""
    cpu, clock, _ = _cpu_with_fc("S1 CALL FC 1;")
    cpu.mem.periph_in[0] = 1
    _scan(cpu, clock, 1)
    cpu.mem.periph_in[0] = 0
    _scan(cpu, clock, 5)
    assert cpu.mem.get("MW20") == 1


def test_a_timer_or_counter_given_to_a_call_arrives_as_its_parameter_type_asks() -> None:
    """docs/semantics.md, "Decisions", timers and counters as operands: a CALL passes a timer or
    counter as an operand, so a TIMER or COUNTER parameter gets its number (S7 passes the
    cell, not its value), a BOOL its status bit and an INT its value."""
    text = source(
        seq("""
      INITIAL_STEP S1 "a": S1 CS C1, C#3; CALL FC 2 (tmr := "Tmr", cnt := C1, bit := C1, num := C1);
      END_STEP
      TRANSITION T1 FROM S1 TO S1 := FALSE;
    """),
        header='SYMBOLS "Tmr" : T12 : TIMER; END_SYMBOLS',
    )
    seen: list[dict[str, object]] = []

    @fc(2, "Probe", IN={"tmr": "TIMER", "cnt": "COUNTER", "bit": "BOOL", "num": "INT"})
    def probe(ctx, params) -> None:
        seen.append(dict(params))

    clock = VirtualClock()
    cpu = Cpu(clock)
    cpu.load(probe)
    install_all(cpu, [GraphFB(compile_chart(parse_chart(text, "call.s7g")))])
    cpu.start("warm")
    _scan(cpu, clock, 2)
    assert seen[-1] == {"tmr": 12, "cnt": 1, "bit": True, "num": 3}


# ---------------------------------------------------------------- ON / OFF


def test_on_and_off_reach_steps_of_another_sequencer() -> None:
    """docs/semantics.md, "Actions": `ON Sx` / `OFF Sx` (de)activate another step — of any
    sequencer."""
    run = chart(
        seq("""
      INITIAL_STEP S1 "a": END_STEP
      STEP S2 "b": S1 ON S12; S1 OFF S11; END_STEP
      TRANSITION T1 FROM S1 TO S2 := I0.0;
      TRANSITION T2 FROM S2 TO S1 := FALSE;
    """)
        + seq(
            """
      INITIAL_STEP S11 "x": END_STEP
      STEP S12 "y": N Q2.0; END_STEP
      TRANSITION T11 FROM S11 TO S12 := FALSE;
      TRANSITION T12 FROM S12 TO S11 := FALSE;
    """,
            2,
        )
    )
    run.call()
    assert run.active == [1, 11]
    run.set(I0_0=True).call()
    run.set(I0_0=False).call()
    assert run.active == [2, 12]
    assert run.get("Q2.0") is True


def test_off_s_all_clears_every_sequencer_but_keeps_the_step_holding_it() -> None:
    """docs/semantics.md, "Actions": `OFF S_ALL` deactivates every step except the one holding the
    action (here V1 OFF S_ALL, steps of two sequencers)."""
    run = chart(
        seq("""
      INITIAL_STEP S1 "a": END_STEP
      STEP S2 "b": SUPERVISION := I0.6; V1 OFF S_ALL; END_STEP
      INITIAL_STEP S3 "c": END_STEP
      TRANSITION T1 FROM S1 TO S2 := I0.0;
      TRANSITION T2 FROM S2 TO S1 := FALSE;
      TRANSITION T3 FROM S3 TO S1 := FALSE;
    """)
        + seq('INITIAL_STEP S11 "x": END_STEP\nTRANSITION T11 FROM S11 TO STOP := FALSE;', 2)
    )
    run.call()
    run.set(I0_0=True).call()
    assert run.active == [2, 3, 11]
    run.set(I0_6=True).call(2)
    assert run.active == [2]


# ---------------------------------------------------------------- allowed rows

ALLOWED = [
    "S1 NC Q0.0;",
    "V1 SC Q0.0;",
    "A1 RC Q0.0;",
    "R1 ONC S1;",
    "S1 OFFC S1;",
    "S1 OFF S_ALL;",
    "V1 OFF S_ALL;",
    "L1 OFF S_ALL;",
    "S0 N Q0.0;",
    "V0 S Q0.0;",
    "L0 R Q0.0;",
    "L1 ON S1;",
    "S0 OFF S1;",
    "S0 CS C 1, C#5;",
    "L0 CU C 1;",
    "V0 CD C 1;",
    "A1 CR C 1;",
    "R1 TL T 1, S5T#1S;",
    "S0 TD T 1, S5T#1S;",
    "L1 TF T 1, S5T#1S;",
    "V1 TR T 1;",
    "L0 N x := x + 1;",
]

REFUSED = [
    ("S0 NC Q0.0;", "E020"),
    ("V0 SC Q0.0;", "E020"),
    ("L0 RC Q0.0;", "E020"),
    ("L1 ONC S1;", "E020"),
    ("S1 D Q0.0, T#1S;", "E020"),
    ("V1 L Q0.0, T#1S;", "E020"),
    ("A1 OFF S_ALL;", "E025"),
    ("R1 OFF S_ALL;", "E025"),
    ("L0 OFF S_ALL;", "E025"),
    ("V0 OFF S_ALL;", "E025"),
]


def _row_chart(row: str) -> str:
    return source(
        seq(f"""
      INITIAL_STEP S1 "a": N Q1.0; END_STEP
      STEP S2 "b": INTERLOCK := I0.5; SUPERVISION := I0.6;
        N Q1.1;
        {row}
      END_STEP
      TRANSITION T1 FROM S1 TO S2 := I0.0;
      TRANSITION T2 FROM S2 TO S1 := I0.1;
    """),
        header="VAR x : INT := 0; END_VAR",
    )


@pytest.mark.parametrize("row", ALLOWED)
def test_rows_of_the_allowed_table_compile(row: str) -> None:
    """docs/semantics.md, "Actions" table of allowed event / qualifier / C combinations."""
    errors = [d for d in validate(parse_chart(_row_chart(row), "r.s7g")) if d.is_error]
    assert errors == []


@pytest.mark.parametrize(("row", "code"), REFUSED)
def test_rows_outside_the_table_are_compile_errors_naming_step_and_row(row, code) -> None:
    """docs/semantics.md, "Actions": any other combination is a compile error naming the step and
    row."""
    errors = [d for d in validate(parse_chart(_row_chart(row), "r.s7g")) if d.is_error]
    assert [d.code for d in errors] == [code]
    assert errors[0].element == "step S2 row 2"


# ---------------------------------------------------------------- conditions


def test_xor_in_a_transition() -> None:
    """docs/semantics.md, "Conditions": XOR of contacts."""
    body = seq("""
      INITIAL_STEP S1 "a": END_STEP
      STEP S2 "b": END_STEP
      TRANSITION T1 FROM S1 TO S2 := I0.0 XOR I0.1;
    """)
    for a, b, switched in (
        (True, True, False),
        (False, False, False),
        (True, False, True),
        (False, True, True),
    ):
        run = chart(body)
        run.set(I0_0=a, I0_1=b).call(2)
        assert (run.active == [2]) is switched, (a, b)


def test_time_comparison_with_a_step_time_and_a_time_variable() -> None:
    """docs/semantics.md, "Conditions": comparisons of TIME (`S2.T >= dwell`)."""
    run = chart(
        seq("""
      INITIAL_STEP S1 "a": END_STEP
      STEP S2 "b": END_STEP
      STEP S3 "c": END_STEP
      TRANSITION T1 FROM S1 TO S2 := TRUE;
      TRANSITION T2 FROM S2 TO S3 := S2.T >= dwell AND dwell <> T#0MS;
    """),
        header="VAR dwell : TIME := T#50MS; END_VAR",
    )
    run.call(2)  # t = 0: S1 on for the first call; t = 10: T1 switches, S2 from t = 10
    assert run.active == [2]
    run.call(4)  # t = 20 .. 50: S2.T < 50
    assert run.active == [2]
    run.call()  # t = 60
    assert run.active == [3]


def test_comparisons_of_int_dint_and_real() -> None:
    """docs/semantics.md, "Conditions": comparisons (= <> < > <= >=) of same-typed INT, DINT,
    REAL."""
    run = chart(
        seq("""
      INITIAL_STEP S1 "a": END_STEP
      STEP S2 "b": END_STEP
      TRANSITION T1 FROM S1 TO S2 := i <= 3 AND d > L#70000 AND r < 1.5 AND i <> 2;
    """),
        header="VAR i : INT := 3; d : DINT := L#70001; r : REAL := 1.25; END_VAR",
    )
    run.call(2)
    assert run.active == [2]
    run2 = chart(
        seq("""
      INITIAL_STEP S1 "a": END_STEP
      STEP S2 "b": END_STEP
      TRANSITION T1 FROM S1 TO S2 := r >= 1.5;
    """),
        header="VAR r : REAL := 1.25; END_VAR",
    )
    run2.call(3)
    assert run2.active == [1]


def test_tt_says_that_the_transition_condition_holds() -> None:
    """docs/semantics.md, "Conditions": `T2.TT` (condition holds) — read here while TAP holds the
    switch back."""
    run = chart(
        seq("""
      INITIAL_STEP S1 "a": END_STEP
      STEP S2 "b": END_STEP
      TRANSITION T1 FROM S1 TO S2 := I0.0;
    """),
        header="PERMANENT AFTER\n  M0.0 := T1.TT;\nEND_PERMANENT\n",
    )
    run.set(SW_TAP=True).call()
    run.call()
    assert run.get("M0.0") is False
    run.set(I0_0=True).call()
    assert run.get("M0.0") is True and run.active == [1]
    run.set(I0_0=False).call()
    assert run.get("M0.0") is False


def test_permanent_s_and_r_coils_latch() -> None:
    """docs/semantics.md, "Conditions": permanent instructions write with coils `:=`, `S`, `R`."""
    run = chart(
        seq('INITIAL_STEP S1 "a": END_STEP\nTRANSITION T1 FROM S1 TO STOP := FALSE;'),
        header="PERMANENT BEFORE\n  S M0.2 := I0.3;\n  R M0.2 := I0.4;\n"
        "  M0.1 := I0.3;\nEND_PERMANENT\n",
    )
    run.set(I0_3=True).call()
    assert run.get("M0.2") is True and run.get("M0.1") is True
    run.set(I0_3=False).call(2)
    assert run.get("M0.2") is True and run.get("M0.1") is False
    run.set(I0_4=True).call()
    run.set(I0_4=False).call()
    assert run.get("M0.2") is False


def test_empty_transition_condition_holds_and_warns() -> None:
    """docs/semantics.md, "Conditions": an empty transition condition holds (compile warning)."""
    body = seq("""
      INITIAL_STEP S1 "a": END_STEP
      STEP S2 "b": N Q0.0; END_STEP
      TRANSITION T1 FROM S1 TO S2;
    """)
    assert "W120" in [d.code for d in validate(parse_chart(source(body), "e.s7g"))]
    run = chart(body)
    run.call(2)
    assert run.active == [2] and run.get("Q0.0") is True


def test_an_action_row_may_not_write_with_a_coil() -> None:
    """docs/semantics.md, "Conditions": only permanent instructions may write with coils (E035 in a
    step)."""
    codes = [d.code for d in validate(parse_chart(_row_chart("N M0.0 := I0.1;"), "c.s7g"))]
    assert "E035" in codes


def test_a_permanent_coil_may_not_write_a_step_attribute() -> None:
    """docs/semantics.md, "Conditions": `S3.X` is a read-only operand (E045)."""
    text = source(
        seq("""
      INITIAL_STEP S1 "a": END_STEP
      TRANSITION T1 FROM S1 TO STOP := FALSE;
    """),
        header="PERMANENT BEFORE\n  M0.0 := S1.X;\n  AUTO_ON := I0.0;\nEND_PERMANENT\n",
    )
    codes = [d.code for d in validate(parse_chart(text, "c.s7g"))]
    assert codes == ["E045"]


def test_the_criteria_word_of_a_single_contact_is_an_int_like_any_other() -> None:
    """CRIT and CRIT_LOC are words (bit k = contact k): a condition of one contact stores
    0 or 1, not its bool, so each word has one type in the instance DB and the state file
    rewrites no row whose criteria did not change."""
    run = two_steps("", interlock="I1.0")
    enter(run)
    run.set(I1_0=True).call(2)
    st = run.st
    words = [*st.crit, *st.crit_old, *st.crit_loc, *st.crit_loc_err, *st.crit_sup]
    assert {type(w) for w in words} == {int}
    assert st.crit_loc[run.idx(2)] == 1


def test_a_chart_may_not_write_the_peripheral_inputs() -> None:
    """docs/semantics.md, "Decisions", I/O access error: PI is the modules' side, read-only to
    the program — an assignment, a permanent instruction or a call output writing it is E045
    (reading it is fine)."""
    text = source(
        seq("""
      INITIAL_STEP S1 "a": N PIW0 := 5; CALL FC 9 (X := PIW2, Y => "In_word"); END_STEP
      TRANSITION T1 FROM S1 TO STOP := PIW4 > 3;
    """),
        header='SYMBOLS "In_word" : PIW6 : INT; END_SYMBOLS\n'
        "PERMANENT BEFORE\n  PIW8 := MW0;\nEND_PERMANENT\n",
    )
    found = [(d.code, d.message) for d in validate(parse_chart(text, "c.s7g"))]
    assert [c for c, _ in found] == ["E045"] * 3, found
    assert all("peripheral input" in m for _, m in found), found
