"""The book's exercises 1-4 on the FB parameters (STEP7 comprehensive guide vol. 2, ch. 14),
run through the real cycle with the pins wired to markers as in ``CALL FB 2, DB 2``.
Charts: tests/sequencer/scenarios/exercise_*.s7g."""

from __future__ import annotations

import pytest

from s7graph.sequencer.params import PinError
from tests.sequencer.helpers import Run


def started(name: str) -> Run:
    run = Run.scenario(name)
    run.call()
    assert run.active == [1]
    return run


def test_exercise_1_tap_holds_a_satisfied_transition_until_t_push() -> None:
    """Ex. 1: SW_TAP := M0.0, T_PUSH := M0.1."""
    run = started("exercise_modes").wire(SW_TAP="M0.0", T_PUSH="M0.1")
    run.set(I0_1=True).call()
    assert run.active == [2] and run.out("AUTO_ON")  # M0.0 = 0: AUTO, normal processing
    run.set(M0_0=True).call()
    assert run.out("TAP_ON") and not run.out("AUTO_ON")
    run.set(I0_2=True).call(20)
    assert run.active == [2] and run.get("Q0.0") is True  # condition holds, no switch
    run.set(M0_1=True).call()
    assert run.active == [3] and run.get("Q0.1") is True
    run.set(I0_3=True).call(5)  # T_PUSH still 1: no new edge, no switch
    assert run.active == [3]


def test_exercise_2_sw_edges_select_a_mode_that_stays() -> None:
    """Ex. 2: SW_AUTO, SW_MAN, SW_TAP on M0.0, M0.1, M0.2, toggled in turn."""
    run = started("exercise_modes").wire(SW_AUTO="M0.0", SW_MAN="M0.1", SW_TAP="M0.2")

    def mode() -> list[str]:
        return [m for m in ("AUTO_ON", "MAN_ON", "TAP_ON", "TOP_ON") if run.out(m)]

    for marker, expected in (("M0_1", "MAN_ON"), ("M0_2", "TAP_ON"), ("M0_0", "AUTO_ON")):
        run.set(**{marker: True}).call()
        assert mode() == [expected]
        run.set(**{marker: False}).call(3)
        assert mode() == [expected]  # kept after the input falls
    run.set(M0_1=True).call()
    run.set(I0_1=True).call(20)
    assert mode() == ["MAN_ON"] and run.active == [1]  # MAN: conditions do not switch


def test_exercise_3_top_switches_on_condition_or_push() -> None:
    """Ex. 3: User-defined set, SW_TOP := M1.0, T_PUSH := M0.1."""
    run = started("exercise_top").wire(SW_TOP="M1.0", T_PUSH="M0.1")
    run.set(M1_0=True).call()
    assert run.out("TOP_ON")
    run.set(I0_1=True).call()
    assert run.active == [2]  # by the condition
    run.set(M0_1=True).call()
    assert run.active == [3]  # by the push, I0.2 is false
    run.set(M0_1=False).call(5)
    assert run.active == [3]


def test_exercise_3_top_is_standard_here_but_user_pins_are_refused_in_standard() -> None:
    """The guide (V5) needs the User-defined set for SW_TOP; docs/semantics.md, "FB pins" follows
    TIA, whose STANDARD set has SW_TOP/TOP_ON. Pins of the larger sets are refused by name."""
    run = started("exercise_modes").wire(SW_TOP="M1.0")
    run.set(M1_0=True).call()
    assert run.out("TOP_ON")
    with pytest.raises(PinError, match="T_PREV is not in parameter set STANDARD"):
        run.wire(T_PREV="M1.1")
    with pytest.raises(PinError, match="REG_EF is not in parameter set STANDARD; use"):
        run.set(REG_EF=True)


def test_exercise_4_reg_ef_runs_the_r1_row_of_a_disturbed_step() -> None:
    """Ex. 4: REG_EF := M0.0, interlock I0.0, ``R1 S Q0.0``."""
    run = started("exercise_registration").wire(REG_EF="M0.0")
    run.set(I0_0=True, I0_1=True).call(2)
    assert run.active == [2] and run.get("Q0.1") is True and run.get("Q0.0") is False
    run.set(M0_0=True).call()  # registration without disturbance: nothing to register
    assert run.get("Q0.0") is False
    run.set(M0_0=False, I0_0=False).call()
    assert run.out("S_STATE") & 0b10 and run.get("Q0.1") is False  # disturbed, red
    assert run.get("Q0.0") is False
    run.set(M0_0=True).call()
    assert "R1" in run.events(2) and run.get("Q0.0") is True
