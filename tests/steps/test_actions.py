"""Action rows (docs/semantics.md, "Actions") and arithmetic with overflow (STEP7 comprehensive
guide vol. 2, ch. 14)."""

from __future__ import annotations

from tests.sequencer.helpers import Chart, seq


def two(rows: str, *, header: str = "") -> object:
    return Chart(
        seq(f"""
      INITIAL_STEP S1 "a": END_STEP
      STEP S2 "b": {rows} END_STEP
      STEP S3 "c": END_STEP
      TRANSITION T1 FROM S1 TO S2 := I0.0;
      TRANSITION T2 FROM S2 TO S3 := I0.1;
    """),
        header=header,
    )


def enter(c: object) -> None:
    c.call()
    c.set(I0_0=True)
    c.call()


def leave(c: object) -> None:
    c.set(I0_1=True)
    c.call()


def test_s_and_r_latch_after_the_step_is_left() -> None:
    c = two("S Q0.0; R Q0.1;")
    c.set(Q0_1=True)
    enter(c)
    leave(c)
    assert c.q("Q0.0") and not c.q("Q0.1")


def test_d_sets_the_operand_after_the_delay_until_the_step_is_left() -> None:
    c = two("D Q0.0, T#30MS;")
    enter(c)
    c.call(2)
    assert not c.q("Q0.0")
    c.call()
    assert c.q("Q0.0")
    leave(c)
    assert not c.q("Q0.0")


def test_d_never_sets_the_operand_if_the_step_is_left_earlier() -> None:
    c = two("D Q0.0, T#30MS;")
    enter(c)
    leave(c)
    c.call(5)
    assert not c.q("Q0.0")


def test_l_pulses_from_activation_for_the_time_and_is_cut_short_on_exit() -> None:
    c = two("L Q0.0, T#30MS;")
    enter(c)
    assert c.q("Q0.0")
    c.call(3)
    assert not c.q("Q0.0")
    c2 = two("L Q0.0, T#1S;")
    enter(c2)
    leave(c2)
    assert not c2.q("Q0.0")


def test_event_rows_run_once_in_the_event_call() -> None:
    c = two("S1 N count := count + 1; S0 S M0.0;", header="VAR count : INT := 0; END_VAR")
    enter(c)
    c.call(3)
    assert c.rt.st.vars["count"] == 1
    assert not c.q("M0.0")
    leave(c)
    assert c.q("M0.0")


def test_zero_op_forces_n_operands_zero() -> None:
    c = two("N Q0.0;")
    enter(c)
    c.set(ZERO_OP=True)
    c.call()
    assert not c.q("Q0.0") and c.rt.st.outputs["OP_ZEROED"]


def test_on_and_off_activate_and_deactivate_other_steps() -> None:
    c = two("S1 ON S3; S1 OFF S1;")
    enter(c)
    assert c.active == ["S2", "S3"]


def test_off_s_all_keeps_only_the_step_holding_the_action() -> None:
    c = Chart(
        seq("""
      INITIAL_STEP S1 "a": END_STEP
      INITIAL_STEP S2 "b": END_STEP
      STEP S3 "c": S1 OFF S_ALL; END_STEP
      TRANSITION T1 FROM S1 TO S3 := I0.0;
      TRANSITION T2 FROM S2 TO STOP := FALSE;
    """)
    )
    c.call()
    c.set(I0_0=True)
    c.call()
    assert c.active == ["S3"]


def test_int_overflow_sets_the_overflow_status_instead_of_crashing() -> None:
    c = two("N x := x * 300;", header="VAR x : INT := 300; END_VAR")
    enter(c)
    st = c.rt.st
    assert st.ov and st.ov_count >= 1 and "INT overflow" in st.diag[0]
    assert -32768 <= st.vars["x"] <= 32767


def test_round_takes_a_half_to_the_even_number_and_a_real_without_a_whole_value_gives_zero() -> (
    None
):
    """ROUND is STL's RND (a half to the even number); NaN, infinity or a value beyond
    DINT from ROUND or TRUNC set the overflow status and give 0, never stop the CPU."""
    c = two(
        "N a := ROUND(r); N b := ROUND(-r); N e := ROUND(3.5); N f := TRUNC(-2.7); "
        "N g := ROUND(SQRT(m)); N h := TRUNC(r / 0.0); N k := ROUND(3.0E10);",
        header="VAR r : REAL := 2.5; m : REAL := -1.0; "
        + " ".join(f"{n} : DINT := L#7;" for n in "abefghk")
        + " END_VAR",
    )
    enter(c)
    v, st = c.rt.st.vars, c.rt.st
    assert (v["a"], v["b"], v["e"], v["f"]) == (2, -2, 4, -2)
    assert (v["g"], v["h"], v["k"]) == (0, 0, 0) and st.ov and st.ov_count >= 3


def test_division_by_zero_sets_overflow_and_gives_zero() -> None:
    c = two("N x := 7 / y;", header="VAR x : INT := 1; y : INT := 0; END_VAR")
    enter(c)
    assert c.rt.st.vars["x"] == 0 and c.rt.st.ov


def test_word_arithmetic_and_functions() -> None:
    c = two(
        "N w := (w SHL 4) OR W#16#000F; N r := SQRT(16.0); N d := ROUND(2.5);",
        header="VAR w : WORD := W#16#0F00; r : REAL := 0.0; d : DINT := L#0; END_VAR",
    )
    enter(c)
    v = c.rt.st.vars
    assert v["w"] == 0xF00F and v["r"] == 4.0 and v["d"] == 2  # RND: a half to the even
