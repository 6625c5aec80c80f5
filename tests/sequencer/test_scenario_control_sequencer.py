"""The book's "Control Sequencer" checks 1-9 (STEP7 comprehensive guide vol. 2, ch. 14),
each through the FB pins that dialog drives. Chart: scenarios/control_sequencer.s7g."""

from __future__ import annotations

from tests.sequencer.helpers import Run

MODES = ("AUTO_ON", "MAN_ON", "TAP_ON", "TOP_ON")


def started() -> Run:
    run = Run.scenario("control_sequencer")
    run.set(I0_0=True).call()
    assert run.active == [1]
    return run


def mode(run: Run) -> list[str]:
    return [m for m in MODES if run.out(m)]


def to_step_3(run: Run) -> Run:
    run.set(I0_1=True).call()
    run.set(I0_1=False, I0_2=True).call()
    run.set(I0_2=False).call()
    assert run.active == [3]
    return run


def test_check_1_mode_buttons_change_the_mode_and_its_effect() -> None:
    run = started()
    run.pulse("SW_MAN")
    assert mode(run) == ["MAN_ON"]
    run.set(I0_1=True).call(5)
    assert run.active == [1]  # MAN: the satisfied T1 does not switch
    run.pulse("SW_AUTO")
    assert mode(run) == ["AUTO_ON"] and run.active == [2]
    run.pulse("SW_TAP")
    assert mode(run) == ["TAP_ON"]
    run.pulse("SW_TOP")
    assert mode(run) == ["TOP_ON"]


def test_check_2_initialize_returns_to_the_initial_step_and_clears_errors() -> None:
    run = to_step_3(started())
    run.set(I0_6=True).call()
    assert run.out("FAULT") and run.out("ERR_FLT")
    run.set(I0_6=False)
    run.pulse("INIT_SQ")
    assert run.active == [1] and not run.out("ERR_FLT") and run.get("Q0.2") is False


def test_check_3_disable_switches_every_step_off() -> None:
    run = started()
    run.set(I0_1=True).call()
    assert run.active == [2] and run.get("Q0.1") is True
    run.set(OFF_SQ=True).call(3)
    assert run.active == [] and run.out("SQ_ISOFF") and run.get("Q0.1") is False
    assert run.out("S_NO") == 0
    run.set(OFF_SQ=False).call()
    assert run.active == []  # stays off until initialized
    run.set(I0_1=False)
    run.pulse("INIT_SQ")
    assert run.active == [1]


def test_check_4_interlock_on_off_in_auto() -> None:
    run = started()
    run.set(I0_0=False, I0_1=True).call()
    assert run.active == [2] and run.get("Q0.0") is False and run.get("Q0.1") is True
    assert run.out("ERROR") and run.out("ERR_FLT")
    run.set(EN_IL=False).call()
    assert run.get("Q0.0") is True and not run.out("ERR_FLT") and not run.out("IL_ENABLED")
    run.set(EN_IL=True).call()
    assert run.get("Q0.0") is False and run.out("IL_ENABLED") and run.out("ERROR")


def test_check_5_supervision_on_off() -> None:
    run = to_step_3(started())
    run.set(EN_SV=False, I0_6=True, I0_3=True).call()
    assert not run.out("SV_ENABLED") and not run.out("FAULT")
    assert run.active == [4]  # no supervision: the transition switches
    run.pulse("INIT_SQ")
    run.set(EN_SV=True, I0_3=False)
    to_step_3(run)
    run.set(I0_3=True).call(3)
    assert run.active == [3] and run.out("FAULT") and run.get("M2.0") is True


def test_check_6_acknowledge_turns_the_red_step_green_and_it_switches() -> None:
    run = to_step_3(started())
    run.set(I0_6=True).call()
    run.set(I0_6=False, I0_3=True).call(5)
    assert run.active == [3] and run.out("S_STATE") & 0b100  # latched, red, no switch
    run.set(ACK_EF=True).call()
    assert run.active == [4] and not run.out("ERR_FLT")
    assert {"A1", "V0", "S0"} <= run.events(3)


def test_check_7_manual_deactivate_the_current_step_activate_any_other() -> None:
    run = started()
    run.pulse("SW_MAN")
    run.set(S_SEL=1)
    run.pulse("S_OFF")
    assert run.active == [] and run.out("S_NO") == 1 and not run.out("S_ACTIVE")
    run.set(S_SEL=4)
    run.pulse("S_ON")
    assert run.active == [4] and run.get("Q0.3") is True and run.out("S_ACTIVE")
    run.set(I0_4=True).call(5)
    assert run.active == [4]  # transitions have no effect in MAN


def test_check_8_top_switches_on_continue_or_on_the_condition() -> None:
    run = started()
    run.pulse("INIT_SQ")
    run.pulse("SW_TOP")
    run.pulse("T_PUSH")
    assert run.active == [2]  # Continue, T2 false
    run.set(I0_2=True).call()
    assert run.active == [3]  # the condition alone


def test_check_9_tap_needs_continue_and_the_condition() -> None:
    run = started()
    run.pulse("INIT_SQ")
    run.pulse("SW_TAP")
    run.pulse("T_PUSH")
    assert run.active == [1]  # Continue alone
    run.set(I0_1=True).call(5)
    assert run.active == [1]  # condition alone
    run.pulse("T_PUSH")
    assert run.active == [2]
