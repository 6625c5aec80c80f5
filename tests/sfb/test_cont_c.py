"""SFB41 CONT_C against step responses worked out by hand from its equations (``sfb.cont_c``;
docs/runtime.md, "Process control: CONT_C, CONT_S, PULSEGEN"; Siemens, *System Software for
S7-300/400, System and Standard Functions*, chapter "SFB 41/FB 41 CONT_C").

Unless a test says otherwise: CYCLE = 1 s, automatic mode, SP_INT = 50 and PV_IN = 45, so
ER = 5 and, with GAIN = 2, ErKp = GAIN * ER = 10."""

from __future__ import annotations

import math
from dataclasses import replace

import pytest

from s7graph.sfb.cont_c import ContC, ContCIn, ContCOut

AUTO = ContCIn(MAN_ON=False, SP_INT=50.0, PV_IN=45.0, GAIN=2.0, CYCLE=1000)


def run(p: ContCIn, calls: int, block: ContC | None = None) -> list[ContCOut]:
    block = block if block is not None else ContC()
    return [block(p) for _ in range(calls)]


def of(out: ContCOut, *pins: str) -> tuple[object, ...]:
    """The named output pins of one call."""
    return tuple(getattr(out, pin) for pin in pins)


def test_p_only_answers_a_step_with_gain_times_error_at_once() -> None:
    # GAIN 2.5, ER 10: LMN = 25 in the first call and every call after; LMN_PER = 25 * 276.48.
    p = replace(AUTO, I_SEL=False, GAIN=2.5, PV_IN=40.0)
    for out in run(p, 3):
        assert out.LMN == 25.0 and out.LMN_P == 25.0 and out.LMN_I == 0.0
        assert out.ER == 10.0 and out.PV == 40.0 and out.LMN_PER == 6912


def test_the_i_part_ramps_by_gain_times_error_times_cycle_over_ti() -> None:
    # TI 10 s: a full call adds ErKp * CYCLE / TI = 10 * 1 / 10 = 1; the first call after the
    # step only half of it (trapezoid: (10 + 0) / 2 * 0.1 = 0.5). LMN = P 10 + I.
    outs = run(replace(AUTO, TI=10_000), 4)
    assert [o.LMN_I for o in outs] == pytest.approx([0.5, 1.5, 2.5, 3.5])
    assert [o.LMN for o in outs] == pytest.approx([10.5, 11.5, 12.5, 13.5])


def test_the_d_part_jumps_then_decays_with_tm_lag() -> None:
    # D only, TD 10 s, TM_LAG 2 s: gain TD / (CYCLE/2 + TM_LAG) = 10 / 2.5 = 4, so the step of
    # ErKp = 10 gives 40 at once; each call it keeps 1 - CYCLE / 2.5 = 0.6 of itself:
    # 40, 24, 14.4, 8.64. The error back to 0 after two calls (feedback 0.1*40 + 0.1*24 = 6.4)
    # gives (0 - 6.4) * 4 = -25.6.
    p = replace(AUTO, P_SEL=False, I_SEL=False, D_SEL=True, TD=10_000, TM_LAG=2000)
    p = replace(p, LMN_LLM=-100.0)
    block = ContC()
    assert [o.LMN_D for o in run(p, 4, block)] == pytest.approx([40.0, 24.0, 14.4, 8.64])
    block = ContC()
    run(p, 2, block)
    assert of(block(replace(p, PV_IN=50.0)), "LMN") == pytest.approx((-25.6,))


def test_switching_the_d_part_on_gives_no_kick() -> None:
    # While D_SEL is off its feedback follows ErKp: on, the error has not moved, D = 0.
    block = ContC()
    run(replace(AUTO, I_SEL=False), 3, block)
    assert block(replace(AUTO, I_SEL=False, D_SEL=True)).LMN_D == 0.0


@pytest.mark.parametrize(("pv", "er"), [(49.0, 0.0), (52.0, 0.0), (45.0, 3.0), (55.0, -3.0)])
def test_the_dead_band_zeroes_small_errors_and_shifts_larger_ones(pv: float, er: float) -> None:
    # DEADB_W 2: |50 - pv| <= 2 gives 0; 50 - 45 = 5 gives 5 - 2 = 3; -5 gives -5 + 2 = -3.
    p = replace(AUTO, I_SEL=False, GAIN=1.0, PV_IN=pv, DEADB_W=2.0, LMN_LLM=-100.0)
    out = ContC()(p)
    assert of(out, "ER", "LMN") == (er, er)


def test_at_the_high_limit_the_integral_stops() -> None:
    # GAIN 1, TI = CYCLE = 1 s, ER 50 (PV 0): call 1 P 50 + I (50 + 0)/2 = 25 -> 75; call 2
    # I 25 + 50 = 75, LMN 125 -> 100 with QLMN_HLM; the I part is not beyond 100 - DISV, so it
    # stays 75, and from call 3 it integrates no more (LMN was at the limit). The error
    # reversing to -10 (PV 60): the trapezoid (-10 + 50)/2 still points up, held: I 75, LMN
    # 65; then (-10 - 10)/2 = -10: I 65, LMN 55. Unlimited, I would have been 175 by now.
    p = replace(AUTO, GAIN=1.0, TI=1000, PV_IN=0.0)
    block = ContC()
    outs = run(p, 4, block)
    assert [o.LMN for o in outs] == [75.0, 100.0, 100.0, 100.0]
    assert [o.QLMN_HLM for o in outs] == [False, True, True, True]
    assert [o.LMN_I for o in outs] == [25.0, 75.0, 75.0, 75.0]
    back = run(replace(p, PV_IN=60.0), 2, block)
    assert [of(o, "LMN_I", "LMN", "QLMN_HLM") for o in back] == [
        (75.0, 65.0, False),
        (65.0, 55.0, False),
    ]


def test_an_i_part_beyond_the_limit_is_pulled_back_to_it() -> None:
    # I only, GAIN 1, TI 1 s, ER 80: call 1 I = 40; call 2 I = 40 + 80 = 120 > 100 - DISV and
    # LMN 120 > 100: pulled back by min(120 - 100, 120 - 100) = 20 to 100. Then held there.
    p = replace(AUTO, P_SEL=False, GAIN=1.0, TI=1000, SP_INT=80.0, PV_IN=0.0)
    outs = run(p, 3)
    assert [(o.LMN_I, o.LMN, o.QLMN_HLM) for o in outs] == [
        (40.0, 40.0, False),
        (100.0, 100.0, True),
        (100.0, 100.0, True),
    ]


def test_the_low_limit_is_reported_and_held() -> None:
    # P only, ER -10: LMN -10 is limited to LMN_LLM 0; LMN_P still shows -10.
    out = ContC()(replace(AUTO, I_SEL=False, GAIN=1.0, PV_IN=60.0))
    assert (out.LMN, out.LMN_P, out.QLMN_LLM, out.QLMN_HLM) == (0.0, -10.0, True, False)


def test_manual_mode_outputs_man_and_switches_back_bumplessly() -> None:
    # MAN_ON (the initial value): LMN = MAN = 30, the I part follows 30 - P 10 - DISV 0 = 20.
    # Automatic: I = 20 + 0.1 * (10 + 10)/2 = 21, LMN = 10 + 21 = 31 — on from 30 by one
    # call's integration, no jump to P + I of before.
    block = ContC()
    manual = replace(AUTO, MAN_ON=True, MAN=30.0, TI=10_000)
    assert [(o.LMN, o.LMN_I) for o in run(manual, 2, block)] == [(30.0, 20.0), (30.0, 20.0)]
    out = block(replace(manual, MAN_ON=False))
    assert of(out, "LMN", "LMN_I") == pytest.approx((31.0, 21.0))


def test_switching_back_continues_from_the_last_manual_value_with_disv() -> None:
    # MAN moved to 35 in the last manual call, DISV 5: I follows 35 - 10 - 5 = 20; automatic
    # I = 21, LMN = 10 + 21 + 5 = 36.
    block = ContC()
    manual = replace(AUTO, MAN_ON=True, MAN=30.0, TI=10_000, DISV=5.0)
    block(manual)
    block(replace(manual, MAN=35.0))
    assert of(block(replace(manual, MAN_ON=False)), "LMN") == pytest.approx((36.0,))


def test_the_manual_value_is_limited_too() -> None:
    out = ContC()(replace(AUTO, MAN_ON=True, MAN=150.0))
    assert (out.LMN, out.QLMN_HLM) == (100.0, True)


def test_i_itl_on_sets_the_i_part_and_integration_goes_on_from_it() -> None:
    # I_ITLVAL 40 while I_ITL_ON: LMN = P 10 + 40 = 50 whatever the error; off: 40 + 1 = 41
    # (the trapezoid has ErKp 10 on both sides), LMN 51.
    block = ContC()
    init = replace(AUTO, TI=10_000, I_ITL_ON=True, I_ITLVAL=40.0)
    assert [o.LMN for o in run(init, 2, block)] == [50.0, 50.0]
    assert of(block(replace(init, I_ITL_ON=False)), "LMN") == pytest.approx((51.0,))


def test_int_hold_freezes_the_i_part() -> None:
    block = ContC()
    run(replace(AUTO, TI=10_000), 2, block)  # I = 0.5, 1.5
    held = run(replace(AUTO, TI=10_000, INT_HOLD=True), 3, block)
    assert [o.LMN_I for o in held] == pytest.approx([1.5, 1.5, 1.5])


def test_pv_per_is_scaled_from_27648_and_normalised() -> None:
    # PV_PER 13824 = 50 %; PV_FAC 2, PV_OFF -10: 50 * 2 - 10 = 90. W#16#9400 is -27648:
    # -100 % -> -210. PV_FAC/PV_OFF leave PV_IN alone.
    p = replace(AUTO, PVPER_ON=True, PV_PER=13824, PV_FAC=2.0, PV_OFF=-10.0, I_SEL=False)
    assert ContC()(p).PV == 90.0
    assert ContC()(replace(p, PV_PER=0x9400)).PV == -210.0
    assert ContC()(replace(p, PVPER_ON=False)).PV == 45.0


def test_lmn_is_normalised_and_given_as_an_io_word() -> None:
    # P only, GAIN 1, ER 25 (PV 25): LMN 25 * LMN_FAC 2 + LMN_OFF 10 = 60, LMN_PER
    # 60 * 276.48 = 16588.8 -> 16589. ER -50 with LMN_LLM -100: LMN -50, -13824 as a WORD
    # is W#16#CA00.
    p = replace(AUTO, I_SEL=False, GAIN=1.0, PV_IN=25.0, LMN_FAC=2.0, LMN_OFF=10.0)
    out = ContC()(p)
    assert (out.LMN, out.LMN_PER) == (60.0, 16589)
    out = ContC()(replace(AUTO, I_SEL=False, GAIN=1.0, PV_IN=100.0, LMN_LLM=-100.0))
    assert (out.LMN, out.LMN_PER) == (-50.0, 0xCA00)


def test_com_rst_zeroes_the_outputs_and_starts_the_i_part_at_i_itlval() -> None:
    # After COM_RST with I_ITLVAL 7: every output 0; the next call I = 7 + 0.5 (the first
    # half step, the trapezoid's old side is 0 again), LMN = 10 + 7.5.
    block = ContC()
    run(replace(AUTO, TI=10_000, D_SEL=True), 5, block)
    assert block(replace(AUTO, COM_RST=True, I_ITLVAL=7.0)) == ContCOut()
    assert block.sIanteilAlt == 7.0 and block.sInvAlt == 0.0 and block.sRueck == 0.0
    out = block(replace(AUTO, TI=10_000))
    assert of(out, "LMN_I", "LMN") == pytest.approx((7.5, 17.5))


def test_times_below_their_range_are_raised_to_it() -> None:
    # TI T#0MS is taken as CYCLE: a full call adds ErKp * 1 / 1 = 10.
    outs = run(replace(AUTO, TI=0, LMN_HLM=1000.0), 2)
    assert [o.LMN_I for o in outs] == [5.0, 15.0]


def test_the_state_round_trips() -> None:
    block = ContC()
    run(replace(AUTO, TI=10_000, D_SEL=True), 3, block)
    assert ContC.from_state(block.to_state()) == block


def test_a_manual_value_that_is_no_number_leaves_the_io_word_at_0_and_the_block_running() -> None:
    """MAN := NaN (a division 0.0 / 0.0 upstream): LMN shows it, LMN_PER is 0 — never a
    Python error stopping the CPU."""
    out = run(replace(AUTO, MAN_ON=True, MAN=float("nan")), 2)[-1]
    assert math.isnan(out.LMN) and out.LMN_PER == 0
