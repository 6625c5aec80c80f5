"""The drill with clamping-pressure supervision: fault, acknowledgement, completion
(docs/semantics.md, "Supervision" and "Messages"; STEP7 comprehensive guide vol. 2, ch. 14).
Chart: scenarios/drill_supervised.s7g; the plant is played by setting the inputs."""

from __future__ import annotations

from s7graph.sequencer.display import criteria_by_name
from s7graph.sequencer.messages import PROGRAM_USER
from s7graph.sfb.alarms import MessageState
from tests.sequencer.helpers import Run


def ready() -> Run:
    run = Run.scenario("drill_supervised")
    run.set(Drill_up=True, Dr_mot_stopped=True).call()
    assert run.active == [1]
    return run


def test_late_clamp_pressure_faults_waits_for_ack_ef_then_the_piece_is_drilled() -> None:
    run = ready()
    run.set(Start_button=True).call()
    run.set(Start_button=False).call()
    assert run.active == [2] and run.get("Clamp_workp") is True and run.get("Dr_mot_on")
    run.set(Dr_mot_stopped=False, Dr_mot_running=True).wait_ms(600)  # no pressure

    assert run.out("ERR_FLT") and run.get("Fault_lamp") is True and run.active == [2]
    (msg,) = run.messages.entries()
    assert msg.text == "S7GRAPH Supervision Error: FB1, DB1, S002 Work piece not clamped"
    assert criteria_by_name(run.cc, run.st, "S2.SV") == [
        ("S2.U > T#500MS", True),
        ('"Cl_press_ok"', False),  # the contact's own state, under the NOT
    ]

    run.set(Cl_press_ok=True).call(10)  # pressure comes late: T2 holds, the step waits
    assert run.active == [2] and run.out("ERR_FLT")
    assert run.messages.entries()[0].state is MessageState.OUTGOING

    run.pulse("ACK_EF")
    assert run.active == [3] and not run.out("ERR_FLT") and run.get("Fault_lamp") is False
    assert run.messages.entries() == () and run.messages.log()[-1].user == PROGRAM_USER

    run.set(Drill_up=False, Drill_down=True).call()
    assert run.active == [4]
    run.wait_ms(500)
    assert run.active == [5] and run.get("Raise_drill") is True
    run.set(Drill_down=False, Drill_up=True).call()
    assert run.active == [6] and run.get("Dr_mot_on") is False
    run.set(Cl_press_ok=False, Dr_mot_running=False, Dr_mot_stopped=True).call()
    assert run.active == [1] and run.st.vars["pieces"] == 1 and not run.out("ERR_FLT")


def test_pressure_in_time_drills_without_a_fault() -> None:
    run = ready()
    run.set(Start_button=True).call()
    run.set(Start_button=False, Dr_mot_stopped=False, Dr_mot_running=True).wait_ms(300)
    run.set(Cl_press_ok=True).call()
    assert run.active == [3] and run.messages.log() == () and not run.out("ERR_FLT")
