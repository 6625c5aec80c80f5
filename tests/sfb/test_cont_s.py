"""SFB42 CONT_S: up/down signals worked out by hand from its equations (``sfb.cont_s``;
docs/runtime.md, "Process control: CONT_C, CONT_S, PULSEGEN"; Siemens, *System Software for
S7-300/400, System and Standard Functions*, chapter "SFB 42/FB 42 CONT_S").

Unless a test says otherwise: CYCLE 1 s, MTR_TM 10 s (a call of signal moves the valve
10 %), PULSE_TM = BREAK_TM = 2 s (a signal starts when 20 % of travel is wanted and ends when
5 % or less is), GAIN 1, no dead band, TI 300 s, SP_INT 30, PV_IN 0: ErKp = 30, and the I
part takes 30 * 1 / 300 = 0.1 % a call off the feedback F."""

from __future__ import annotations

from dataclasses import replace

import pytest

from s7graph.sfb.cont_s import ContS, ContSIn, ContSOut

AUTO = ContSIn(
    SP_INT=30.0,
    GAIN=1.0,
    DEADB_W=0.0,
    MTR_TM=10_000,
    PULSE_TM=2000,
    BREAK_TM=2000,
    TI=300_000,
)


def signals(outs: list[ContSOut]) -> list[str]:
    return ["up" if o.QLMNUP else "down" if o.QLMNDN else "-" for o in outs]


def run(p: ContSIn, calls: int, block: ContS) -> list[ContSOut]:
    return [block(p) for _ in range(calls)]


def test_an_error_gives_one_pulse_as_long_as_the_travel_it_asks_for() -> None:
    # call 0: F = -0.1, x = 30 - F = 30.1 >= 20: up. call 1: F = -0.1 + 10 - 0.1 = 9.8,
    # x = 20.2 > 5: on. call 2: F = 19.7, x = 10.3: on. call 3: F = 29.6, x = 0.4 <= 5: off.
    # Three calls up = 30 % of travel for ErKp 30; then x grows by 0.1 a call, no new pulse.
    block = ContS()
    outs = run(AUTO, 6, block)
    assert signals(outs) == ["up", "up", "up", "-", "-", "-"]
    assert block.sFbPVal == pytest.approx(29.4)
    down = run(replace(AUTO, SP_INT=-30.0), 4, ContS())
    assert signals(down) == ["down", "down", "down", "-"]


def test_no_pulse_starts_for_less_travel_than_a_minimum_pulse() -> None:
    # ErKp 15 < 20 (the travel of PULSE_TM): nothing for now.
    assert signals(run(replace(AUTO, SP_INT=15.0), 3, ContS())) == ["-", "-", "-"]


def test_a_manual_signal_lasts_pulse_tm_and_a_reversal_waits_break_tm() -> None:
    # LMNS_ON, PULSE_TM 3 s, BREAK_TM 2 s. LMNUP for one call: up for calls 0-2 (3 s). LMNDN
    # from call 3: off for calls 3-4 (2 s), down from call 5.
    block = ContS()
    p = replace(AUTO, LMNS_ON=True, PULSE_TM=3000, BREAK_TM=2000)
    outs = [block(replace(p, LMNUP=True))]
    outs += run(p, 2, block)
    outs += run(replace(p, LMNDN=True), 4, block)
    assert signals(outs) == ["up", "up", "up", "-", "-", "down", "down"]
    assert signals(run(replace(p, LMNUP=True, LMNDN=True), 1, ContS())) == ["-"]


def test_an_end_stop_ends_the_signal_towards_it_at_once() -> None:
    # Up from call 0; LMNR_HS in call 1 ends it before PULSE_TM; no up signal while it is
    # set, and the I part stops integrating upwards: F keeps 9.9 (the travel of call 0).
    block = ContS()
    outs = run(AUTO, 1, block)
    outs += run(replace(AUTO, LMNR_HS=True), 3, block)
    assert signals(outs) == ["up", "-", "-", "-"]
    assert block.sFbPVal == pytest.approx(9.9)
    low = replace(AUTO, SP_INT=-30.0, LMNR_LS=True)
    assert signals(run(low, 2, ContS())) == ["-", "-"]


def test_switching_back_from_manual_sends_no_pulse() -> None:
    # In manual the feedback follows ErKp + DISV (x = 0); back in automatic x is one call's
    # I part, 0.1: no pulse.
    block = ContS()
    run(replace(AUTO, LMNS_ON=True, DISV=5.0), 2, block)
    assert signals(run(replace(AUTO, DISV=5.0), 3, block)) == ["-", "-", "-"]


def test_pv_and_the_dead_band() -> None:
    # The initial DEADB_W is 1: SP 10, PV_PER 13824 = 50 %: ER = -40 + 1 = -39.
    p = ContSIn(SP_INT=10.0, PVPER_ON=True, PV_PER=13824)
    out = ContS()(p)
    assert (out.PV, out.ER) == (50.0, -39.0)


def test_com_rst_ends_the_signal_and_clears_the_integrator() -> None:
    block = ContS()
    run(AUTO, 2, block)
    assert block(replace(AUTO, COM_RST=True)) == ContSOut()
    assert block == ContS()
