"""web/bus/live.py: a real compiled chart on the virtual clock, seen live and commanded."""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import pytest

from s7graph.engine.clock import VirtualClock
from s7graph.engine.errors import S7Error
from s7graph.engine.persistence import StateStore
from s7graph.web.bus.live import LiveGraph, watch_names
from s7graph.web.bus.protocol import Command, StepStateUpdate, refusal_kind
from s7graph.web.harness.session import ChartSession
from tests.web.helpers import chart_session

# A MINIMUM parameter set has no ACK_EF, SW_MAN, S_ON ... pins: the Control Sequencer's
# commands act all the same.
CHART = """\
FUNCTION_BLOCK "Live" FB 1 DB 1
  PARAMETERS := MINIMUM;
  ACK_REQUIRED := TRUE;
SYMBOLS
  "Start" : I0.0 : BOOL;
  "Full" : I0.1 : BOOL;
  "Door" : I0.2 : BOOL;
  "Pump" : Q0.0 : BOOL;
END_SYMBOLS
SEQUENCE 1 "Main"
  INITIAL_STEP S1 "Idle":
  END_STEP
  STEP S2 "Fill":
    INTERLOCK := "Door";
    SUPERVISION := S2.U > T#1S;
    N C "Pump";
  END_STEP
  STEP S3 "Done":
  END_STEP
  TRANSITION T1 "Go" FROM S1 TO S2 := "Start";
  TRANSITION T2 "Full" FROM S2 TO S3 := "Full";
  TRANSITION T3 "Back" FROM S3 TO S1 := NOT "Start";
END_SEQUENCE
END_FUNCTION_BLOCK
"""


@dataclass
class Rig:
    session: ChartSession
    clock: VirtualClock
    live: LiveGraph
    store: StateStore

    def scan(self, ms: float = 10.0) -> StepStateUpdate:
        self.clock.advance(ms)
        return self.live.update(self.session.scan())

    def scans(self, n: int, ms: float = 10.0) -> list[StepStateUpdate]:
        return [self.scan(ms) for _ in range(n)]

    def cmd(self, op: str, user: str = "alice", **args: Any) -> tuple[bool, str]:
        applied, reason, _ = self.live.apply(Command(op=op, fb="Live", user=user, args=args))  # type: ignore[arg-type]
        return applied, reason


@pytest.fixture
def rig(tmp_path: Path) -> Iterator[Rig]:
    session, table, clock, store = chart_session(tmp_path, "live.s7g", CHART)
    live = LiveGraph(
        session.graph,
        read=session.get,
        reader=session.reader,
        watch=[*watch_names(table), "no_such_operand"],
        wall_ns=lambda: 1_700_000_000_000_000_000,
    )
    session.start()
    r = Rig(session, clock, live, store)
    r.scan()
    try:
        yield r
    finally:
        store.close()


def events(updates: list[StepStateUpdate]) -> list[tuple[str, int]]:
    return [e for u in updates for e in u.events]


def test_first_scan_shows_the_initial_step_active_in_auto(rig: Rig) -> None:
    update = rig.scan()
    assert (update.active, update.mode, update.disturbed, update.latched) == ([1], "AUTO", [], [])


def test_supervision_fault_is_disturbed_and_latched_until_acknowledged(rig: Rig) -> None:
    rig.session.set("Start", True)
    rig.session.set("Door", True)
    seen = rig.scans(3)
    assert ("S1", 2) in events(seen) and seen[-1].active == [2]
    seen = rig.scans(110)  # S2.U passes 1 s
    assert ("V1", 2) in events(seen)
    assert (seen[-1].disturbed, seen[-1].latched) == ([2], [2])
    rig.session.set("Full", True)
    assert rig.scans(5)[-1].active == [2]  # the fault holds the transition

    assert rig.cmd("ack", user="alice") == (True, "")
    after = rig.scan()
    assert ("A1", 2) in after.events
    assert (after.active, after.disturbed, after.latched) == ([3], [], [])


def test_interlock_error_is_disturbed_but_not_latched(rig: Rig) -> None:
    rig.session.set("Start", True)
    update = rig.scans(3)[-1]  # "Door" open: S2's interlock does not hold
    assert (update.active, update.disturbed, update.latched) == ([2], [2], [])
    assert update.values["Pump"] is False


def test_ack_without_a_fault_is_refused(rig: Rig) -> None:
    applied, reason = rig.cmd("ack")
    assert not applied and "no supervision fault" in reason


def test_step_on_and_off_need_man_mode_and_a_known_step(rig: Rig) -> None:
    applied, reason = rig.cmd("step_on", step=3)
    assert not applied
    assert reason == "step_on needs mode MAN (S7-GRAPH Control Sequencer)"
    assert rig.cmd("mode", mode="MAN") == (True, "")
    assert rig.scan().mode == "MAN"
    assert rig.cmd("step_on", step=3) == (True, "")
    update = rig.scan()
    assert update.active == [1, 3] and ("S1", 3) in update.events
    assert rig.cmd("step_on", step=3) == (False, "S3 is already active")
    assert rig.cmd("step_on", step=9) == (False, "no step S9 in Live")
    kinds = [refusal_kind(rig.cmd("step_on", step=n)[1]) for n in (3, 9)]
    assert kinds == ["state", "not_found"]  # said where refused: the reply's kind
    assert rig.cmd("step_off", step=1) == (True, "")
    assert rig.scan().active == [3]
    assert rig.cmd("step_off", step=1) == (False, "S1 is not active")


def test_set_steps_moves_the_sequence_in_one_call_in_man(rig: Rig) -> None:
    applied, reason = rig.cmd("set_steps", steps=[3])
    assert (applied, reason) == (False, "set_steps needs mode MAN (S7-GRAPH Control Sequencer)")
    assert rig.cmd("mode", mode="MAN") == (True, "")
    rig.scan()
    assert rig.cmd("set_steps", steps=[3, 9]) == (False, "no step S9 in Live")
    assert rig.cmd("set_steps", steps=[1]) == (
        False,
        "nothing to change: S1 already active, no other step active in their sequences",
    )
    applied, reason, detail = rig.live.apply(
        Command(op="set_steps", fb="Live", user="alice", args={"steps": [3, 3]})  # type: ignore[arg-type]
    )
    assert (applied, detail) == (True, "FB Live: S3 (off: S1; on: S3)")  # the audit's words
    assert not rig.cmd("step_on", step=2)[0]  # one step command a boundary
    update = rig.scan()
    assert update.active == [3] and {("S0", 1), ("S1", 3)} <= set(update.events)


def test_mode_then_step_on_at_one_boundary_act_in_order(rig: Rig) -> None:
    assert rig.cmd("mode", mode="MAN") == (True, "")
    assert rig.cmd("step_on", step=2) == (True, "")
    update = rig.scan()
    assert (update.mode, update.active) == ("MAN", [1, 2])


def test_second_mode_or_step_command_at_one_boundary_is_refused(rig: Rig) -> None:
    assert rig.cmd("mode", mode="MAN") == (True, "")
    applied, reason = rig.cmd("mode", mode="AUTO")
    assert not applied and "conflicts with mode AUTO -> MAN" in reason
    assert rig.cmd("step_on", step=2) == (True, "")
    assert not rig.cmd("step_on", step=3)[0]
    assert rig.scan().active == [1, 2]
    assert rig.cmd("mode", mode="AUTO") == (True, "")  # a new scan, a new boundary


def test_man_mode_holds_the_sequence_and_auto_releases_it(rig: Rig) -> None:
    rig.cmd("mode", mode="MAN")
    rig.session.set("Start", True)
    assert rig.scans(3)[-1].active == [1]  # no switching in MAN
    rig.cmd("mode", mode="AUTO")
    assert rig.scans(2)[-1].active == [2]


def test_t_push_needs_tap_or_top_and_switches_in_tap(rig: Rig) -> None:
    applied, reason = rig.cmd("t_push")
    assert not applied and "TAP or TOP" in reason
    rig.cmd("mode", mode="TAP")
    rig.scan()
    assert rig.cmd("t_push") == (  # said, not silently lost
        True,
        "no transition of the active steps was satisfied in the last call: in TAP the push "
        "switches only one satisfied in the next",
    )
    assert rig.scan().active == [1]
    rig.session.set("Start", True)
    assert rig.scans(3)[-1].active == [1]  # TAP: condition AND push
    assert rig.cmd("t_push") == (True, "")
    assert rig.scan().active == [2]


def test_off_deactivates_every_step_and_init_restores_the_initial_step(rig: Rig) -> None:
    assert rig.cmd("off") == (True, "")
    update = rig.scan()
    assert update.active == [] and ("S0", 1) in update.events
    assert rig.scans(3)[-1].active == []  # OFF acts for one call; the sequencer stays off
    assert rig.cmd("init") == (True, "")
    assert rig.scan().active == [1]


def test_values_hold_the_fb_outputs_and_the_watched_operands(rig: Rig) -> None:
    values = rig.scan().values
    assert {"Start", "Full", "Door", "Pump"} <= set(values)
    assert "no_such_operand" not in values  # an unreadable watch is left out, not raised
    assert set(rig.session.graph.out_pins) <= set(values)


def test_a_reader_gives_what_get_gives_with_the_name_resolved_once(rig: Rig) -> None:
    session = rig.session
    names = ["Start", "Pump", "I0.2", "MW10", "T3", "S1.X", "S2.T", "T1.TT", "INIT_SQ"]
    readers = {name: session.reader(name) for name in names}
    session.set("Start", True)
    session.set("MW10", 1234)
    rig.scans(3)
    assert {n: r() for n, r in readers.items()} == {n: session.get(n) for n in names}
    assert readers["Start"]() is True and readers["MW10"]() == 1234
    with pytest.raises(S7Error, match="unknown name no_such_operand"):
        session.reader("no_such_operand")


def test_watched_operands_are_resolved_once_and_again_after_an_online_change(
    rig: Rig,
) -> None:
    session = rig.session
    resolved: list[str] = []

    def reader(name: str) -> Any:
        resolved.append(name)
        return session.reader(name)

    live = LiveGraph(session.graph, reader=reader, watch=["Start", "Pump"])
    for _ in range(3):
        live.update(rig.session.scan())
    assert resolved == ["Start", "Pump"]  # once, not per scan
    live.switch(live.prepare(session.cc, version=2))  # an online change: symbols may differ
    assert live.update(rig.session.scan()).values["Start"] is False
    assert resolved == ["Start", "Pump"] * 2


def test_commands_are_refused_while_the_cpu_is_not_in_run(rig: Rig) -> None:
    rig.session.cpu.stop("test")
    rig.scan()
    applied, reason = rig.cmd("init")
    assert not applied and "STOP" in reason


@pytest.mark.parametrize(
    "hostile",
    [
        None,
        object(),
        SimpleNamespace(op="step_on", step="S3", mode=None, user="x", args={}),
        SimpleNamespace(op="step_on", step=True, mode=None, user="x", args={}),
        SimpleNamespace(op="mode", step=None, mode="FAST", user="x", args={}),
        SimpleNamespace(op="ack", step=None, mode=None, user=None, args={}),
        SimpleNamespace(op="reboot", step=None, mode=None, user="x", args={}),
    ],
)
def test_hostile_command_is_refused_and_the_scan_loop_goes_on(rig: Rig, hostile: object) -> None:
    rig.cmd("mode", mode="MAN")
    rig.scan()
    applied, reason, _ = rig.live.apply(hostile)  # type: ignore[arg-type]
    assert applied is False and reason
    update = rig.scan()
    assert update.active == [1]


def test_a_failing_fb_hook_refuses_the_command_instead_of_raising(
    rig: Rig, monkeypatch: pytest.MonkeyPatch
) -> None:
    def boom(*args: object, **kwargs: object) -> None:
        raise RuntimeError("hook broke")

    monkeypatch.setattr(rig.session.graph, "command", boom)
    assert rig.cmd("init") == (
        False,
        "command refused: an internal error in the CPU while applying init to "
        f"{rig.live.fb}: hook broke (please report it)",
    )
    assert rig.scan().active == [1]


def test_halt_holds_the_sequencer_until_released_whatever_the_parameter_set(rig: Rig) -> None:
    """HALT_SQ from the Control Sequencer: no switching while held, the pin again after."""
    assert rig.cmd("halt", on=True) == (True, "")
    rig.session.set("Start", True)
    held = rig.scans(5)[-1]
    assert held.active == [1] and held.halted
    assert rig.cmd("halt", on=False) == (True, "")
    after = rig.scans(3)[-1]
    assert after.active == [2] and not after.halted


def test_en_sv_off_disables_supervision_and_ack_step_acknowledges_one_step(rig: Rig) -> None:
    rig.session.set("Start", True)
    rig.session.set("Door", True)
    rig.scans(3)
    assert rig.cmd("ack_step", step=2) == (False, "S2 waits for no acknowledgement")
    assert rig.cmd("en_sv", on=False) == (True, "")
    quiet = rig.scans(120)[-1]  # S2.U passes 1 s: no supervision fault while disabled
    assert quiet.latched == [] and not quiet.sv_enabled
    assert rig.cmd("en_sv", on=True) == (True, "")
    latched = rig.scans(3)[-1]
    assert latched.latched == [2] and latched.sv_enabled
    assert rig.cmd("ack_step", step=9) == (False, "no step S9 in Live")
    rig.session.set("Full", True)  # the cause persists, but T2 may switch once released
    rig.scan()
    assert rig.cmd("ack_step", step=2) == (True, "")
    assert ("A1", 2) in rig.scan().events  # released as ACK_S would


def test_an_ack_whose_cause_persists_is_refused_saying_why_and_changes_nothing(
    rig: Rig,
) -> None:
    """S2.U stays over 1 s and T2 is not satisfied: acknowledged, the fault would latch
    again in the same call and its message stay unacknowledged, so the command says so."""
    rig.session.set("Start", True)
    rig.session.set("Door", True)
    assert rig.scans(115)[-1].latched == [2]
    persists = (
        "the cause of S2's supervision fault persists (its condition still holds): "
        "acknowledged now the fault would latch again at once and its message stay "
        "unacknowledged; remove the cause, then acknowledge"
    )
    assert rig.cmd("ack") == (False, persists)
    assert rig.cmd("ack_step", step=2) == (False, persists)
    after = rig.scans(3)
    assert ("A1", 2) not in events(after) and after[-1].latched == [2]
    rig.session.set("Full", True)  # T2 satisfied: the acknowledgement lets S2 switch on
    rig.scan()
    assert rig.cmd("ack") == (True, "")
    assert rig.scan().active == [3]


def test_a_chart_swapped_under_the_live_view_is_followed_with_its_own_steps(rig: Rig) -> None:
    """The live view reads the chart from the GraphFB: a swap it was not told of (no
    ``switch``) still gives the new chart's steps, details and a newer layout version."""
    from s7graph.sequencer.change.online import swap
    from s7graph.web.harness.session import compile_text

    rig.session.set("Start", True)
    rig.session.set("Door", True)
    assert rig.scans(2)[-1].active == [2]
    inserted = CHART.replace(
        '  STEP S3 "Done":', '  STEP S8 "Check":\n  END_STEP\n  STEP S3 "Done":'
    ).replace(
        'FROM S2 TO S3 := "Full";',
        'FROM S2 TO S8 := "Full";\n  TRANSITION T4 "Checked" FROM S8 TO S3 := "Full";',
    )
    version = rig.live.layout.version
    cc, _ = compile_text(inserted, "live.s7g")
    swap(rig.session.graph, cc, rig.session.cpu)
    rig.session.set("Full", True)
    seen = rig.scans(2)
    assert events(seen)[:4] == [("S0", 2), ("S1", 8), ("S0", 8), ("S1", 3)]
    assert rig.live.cc is cc and rig.live.layout.version == version + 1
    assert [s.number for s in rig.live.layout.steps] == [1, 2, 8, 3]


def test_the_operands_the_permanent_instructions_write_go_out_every_scan(
    tmp_path: Path,
) -> None:
    """What the permanent pre- and post-instructions write is among an update's values in
    every scan, whatever step is active; a change of one alone is a change of the FB."""
    from tests.web.bus.test_chart_text import PERMANENT

    chart = PERMANENT.replace("  CALL FC 3;\n", "")  # no FC 3 in this CPU
    session, _, clock, store = chart_session(tmp_path, "perm.s7g", chart)
    try:
        live = LiveGraph(session.graph, read=session.get, reader=session.reader)
        session.start()

        def scan() -> StepStateUpdate | None:
            clock.advance(10)
            return live.changed(session.scan())

        first = scan()
        assert first is not None and first.active == [1]
        assert {k: first.values[k] for k in ("Ready", "Lamp", "Motor")} == {
            "Ready": False,
            "Lamp": False,
            "Motor": True,  # S1's N row, after which R "Motor" := "Trip" resets nothing
        }
        runs = first.values["runs"]
        later = scan()  # runs := runs + 1 in every call: a change every scan
        assert later is not None and later.values["runs"] == runs + 1
        session.set("Trip", True)
        faulted = scan()
        assert faulted is not None and faulted.active == [1]  # no step switched
        assert (faulted.values["Lamp"], faulted.values["Motor"]) == (True, False)
    finally:
        store.close()
