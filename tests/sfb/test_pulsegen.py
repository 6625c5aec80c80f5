"""SFB43 PULSEGEN: pulse trains worked out by hand from its rules (``sfb.pulsegen``;
docs/runtime.md, "Process control: CONT_C, CONT_S, PULSEGEN"; Siemens, *System Software for
S7-300/400, System and Standard Functions*, chapter "SFB 43/FB 43 PULSEGEN").

Unless a test says otherwise: CYCLE 100 ms and PER_TM 1 s, so a period is 10 calls and a
call is 10 % of it; P_B_TM its initial 50 ms."""

from __future__ import annotations

from dataclasses import replace

import pytest

from s7graph.sfb.pulsegen import PulseGen, PulseGenIn, PulseGenOut

THREE = PulseGenIn(CYCLE=100, PER_TM=1000)
TWO = replace(THREE, STEP3_ON=False)


def trains(p: PulseGenIn, calls: int, block: PulseGen | None = None) -> tuple[str, str]:
    """QPOS_P and QNEG_P over ``calls`` calls as strings of 1 and 0."""
    block = block if block is not None else PulseGen()
    outs = [block(p) for _ in range(calls)]
    return "".join(str(int(o.QPOS_P)) for o in outs), "".join(str(int(o.QNEG_P)) for o in outs)


def test_thirty_percent_is_three_calls_of_ten_on() -> None:
    # The manual's example: pulse = 30 / 100 * 1000 ms = 300 ms = 3 calls, then 7 off.
    assert trains(replace(THREE, INV=30.0), 20) == ("11100000001110000000", "0" * 20)


def test_a_negative_value_pulses_the_negative_output() -> None:
    # -40 %: 400 ms = 4 calls on QNEG_P.
    assert trains(replace(THREE, INV=-40.0), 10) == ("0" * 10, "1111000000")


@pytest.mark.parametrize(
    ("ratio", "inv", "pos", "neg"),
    [
        (0.5, -40.0, "0" * 10, "1100000000"),  # negative 400 * 0.5 = 200 ms
        (0.5, 40.0, "1111000000", "0" * 10),  # positive unchanged
        (2.0, 40.0, "1100000000", "0" * 10),  # positive 400 / 2 = 200 ms
        (2.0, -40.0, "0" * 10, "1111000000"),  # negative unchanged
    ],
)
def test_ratiofac_shortens_one_side(ratio: float, inv: float, pos: str, neg: str) -> None:
    assert trains(replace(THREE, RATIOFAC=ratio, INV=inv), 10) == (pos, neg)


@pytest.mark.parametrize(
    ("inv", "pos"),
    [
        (15.0, "0000000000"),  # 150 ms < P_B_TM 200 ms: no pulse
        (20.0, "1100000000"),  # 200 ms: not below it
        (80.0, "1111111100"),  # 800 ms: not above 1000 - 200
        (85.0, "1111111111"),  # 850 ms > 800 ms: the whole period
    ],
)
def test_p_b_tm_suppresses_short_pulses_and_short_breaks(inv: float, pos: str) -> None:
    assert trains(replace(THREE, P_B_TM=200, INV=inv), 10)[0] == pos


@pytest.mark.parametrize(
    ("inv", "pos"),
    [(0.0, "1111100000"), (-60.0, "1100000000"), (100.0, "1111111111"), (-100.0, "0" * 10)],
)
def test_bipolar_two_step_maps_minus_100_to_100_onto_the_period(inv: float, pos: str) -> None:
    # (INV + 100) / 200 of the period: 0 % -> 5 calls, -60 % -> 2; QNEG_P is the negation.
    neg = "".join("0" if c == "1" else "1" for c in pos)
    assert trains(replace(TWO, ST2BI_ON=True, INV=inv), 10) == (pos, neg)


def test_unipolar_two_step_maps_0_to_100_onto_the_period() -> None:
    assert trains(replace(TWO, INV=30.0), 10) == ("1110000000", "0001111111")
    assert trains(replace(TWO, INV=-20.0), 10) == ("0" * 10, "1" * 10)


def test_a_change_mid_period_starts_a_new_period_with_syn_on() -> None:
    # 30 % for calls 0-4, then 70 % from call 5 (the period's 6th call: neither of the first
    # two nor of the last two): a new period starts there, 7 calls on. Without SYN_ON the
    # 70 % waits for the period's end (call 10).
    for syn_on, want in ((True, "111001111111000"), (False, "111000000011111")):
        block = PulseGen()
        p = replace(THREE, SYN_ON=syn_on, INV=30.0)
        first, _ = trains(p, 5, block)
        rest, _ = trains(replace(p, INV=70.0), 10, block)
        assert first + rest == want


def test_a_change_in_the_last_two_calls_of_a_period_waits() -> None:
    # Changed in call 8 (the period's 9th): no synchronisation; the next period has it.
    block = PulseGen()
    first, _ = trains(replace(THREE, INV=30.0), 8, block)
    rest, _ = trains(replace(THREE, INV=70.0), 6, block)
    assert first + rest == "11100000" + "00" + "1111"


@pytest.mark.parametrize(
    ("pos_on", "neg_on", "three", "two"),
    [
        (False, False, (False, False), (False, True)),
        (True, False, (True, False), (True, False)),
        (False, True, (False, True), (False, True)),
        (True, True, (False, False), (True, False)),
    ],
)
def test_manual_mode_sets_the_outputs_from_pos_p_on_and_neg_p_on(
    pos_on: bool, neg_on: bool, three: tuple[bool, bool], two: tuple[bool, bool]
) -> None:
    # The manual's table; INV does not matter.
    for base, want in ((THREE, three), (TWO, two)):
        p = replace(base, MAN_ON=True, POS_P_ON=pos_on, NEG_P_ON=neg_on, INV=50.0)
        assert PulseGen()(p) == PulseGenOut(*want)


def test_com_rst_clears_the_outputs_and_starts_a_new_period() -> None:
    block = PulseGen()
    trains(replace(THREE, INV=30.0), 4, block)
    assert block(replace(THREE, COM_RST=True, INV=30.0)) == PulseGenOut()
    assert trains(replace(THREE, INV=30.0), 4, block)[0] == "1110"


def test_an_input_that_is_no_number_pulses_neither_output() -> None:
    """INV := NaN (0.0 / 0.0 upstream) gives no pulse — never a Python error stopping the
    CPU."""
    assert trains(replace(THREE, INV=float("nan")), 20) == ("0" * 20, "0" * 20)
