"""What a GRAPH FB is to do in its next call outlives a restart (sequencer/fb.py,
sequencer/state.py): an online change's new sequencer, whose initial step is active from the
swap on but whose S1 rows are the next call's (``GraphFB.enter``), a placement queued for
the next call (``GraphFB.place``), the operator commands and level holds queued for it
(``GraphFB.command``, ``set_level``) and the steps users released by acknowledging their
messages are part of the instance DB. A CPU "killed" after the
state file took the swap (or the placement) and before the FB was called again carries
them out once, in the first call after its restart — on the virtual clock, the state file
as ``s7graph run`` keeps it, and once as a real ``s7graph run`` killed with SIGKILL."""

from __future__ import annotations

import threading
from pathlib import Path
from typing import Any

import pytest

from s7graph.engine.clock import VirtualClock
from s7graph.engine.persistence import StateStore, unpack_instance
from s7graph.sequencer.change.online import swap
from s7graph.sequencer.state import GraphState
from s7graph.sfb.alarms import message_list
from s7graph.web.access.audit import read_audit
from s7graph.web.bus.protocol import Command
from s7graph.web.cli import main
from s7graph.web.harness.persist import open_state
from s7graph.web.harness.session import ChartSession, compile_text
from tests.real_process import kill_run, query_store, wait_for
from tests.web.helpers import cpu_process

CHART = """FUNCTION_BLOCK "Seq_fill" FB 1 DB 1
VAR
  go : BOOL;
  full : BOOL;
  pieces : INT := 0;
  starts : INT := 0;
END_VAR
SEQUENCE 1 "Fill"
  INITIAL_STEP S1 "Idle":
  END_STEP
  STEP S2 "Fill":
    S1 N pieces := pieces + 1;
  END_STEP
  STEP S3 "Drain":
  END_STEP
  TRANSITION T1 "Go" FROM S1 TO S2 := go;
  TRANSITION T2 "Full" FROM S2 TO S3 := full;
  TRANSITION T3 "Empty" FROM S3 TO S1 := FALSE;
END_SEQUENCE
END_FUNCTION_BLOCK
"""
SECOND = """SEQUENCE 2 "Count"
  INITIAL_STEP S20 "Ready":
    S1 N starts := starts + 1;
  END_STEP
  STEP S21 "Counted":
  END_STEP
  TRANSITION T20 FROM S20 TO S21 := full;
  TRANSITION T21 FROM S21 TO S20 := FALSE;
END_SEQUENCE
"""
WITH_SECOND = CHART.replace("END_SEQUENCE\n", "END_SEQUENCE\n" + SECOND)


class Run:
    """``s7graph run`` of ``text`` on the virtual clock with its state file at ``state``,
    started by ``restart``; ``kill`` ends it after its last commit."""

    def __init__(self, text: str, state: Path, restart: str = "warm") -> None:
        cc, table = compile_text(text, "fill.s7g")
        self.session = ChartSession(cc, table, VirtualClock(10**12))
        self.cpu = self.session.cpu
        self.store: StateStore = open_state(state, self.cpu, restart=restart).store
        self.cpu.start(restart)
        self.store.save(self.cpu, clean=False)

    def scan(self, n: int = 1) -> None:
        """``n`` scans, each committed as the runner commits it (after its boundary)."""
        for _ in range(n):
            self.session.clock.advance(10)  # type: ignore[attr-defined]
            self.session.scan()
            self.commit()

    def commit(self) -> None:
        batch = self.store.stage(self.cpu)
        if batch is not None:
            self.store.write(batch)

    def kill(self) -> None:
        self.store.close()

    def active(self) -> list[int]:
        g = self.session.graph
        return sorted(g.cc.step_numbers[i] for i in g.state.active)

    def get(self, name: str) -> object:
        return self.session.get(name)


def _swapped_and_killed(state: Path) -> None:
    """S2 active, then a download adds sequencer 2; the swap's state committed at its scan
    boundary, the run killed before the FB's next call."""
    run = Run(CHART, state, restart="hot")
    run.session.set("go", True)
    run.scan(5)
    assert run.active() == [2] and run.get("pieces") == 1
    new, _ = compile_text(WITH_SECOND, "fill.s7g")
    swap(run.session.graph, new, run.cpu)
    run.commit()
    run.kill()


def test_a_hot_restart_between_a_swap_and_the_next_call_runs_the_new_sequencers_s1_once(
    tmp_path: Path,
) -> None:
    state = tmp_path / "state.sqlite"
    _swapped_and_killed(state)
    again = Run(WITH_SECOND, state, restart="hot")
    assert again.active() == [2, 20] and again.get("starts") == 0
    again.scan()  # the first call after the restart: S20's S1 rows
    assert again.active() == [2, 20] and again.get("starts") == 1
    assert again.get("pieces") == 1  # S2 went on where it was, its S1 not again
    again.scan(5)
    assert again.get("starts") == 1
    again.kill()
    third = Run(WITH_SECOND, state, restart="hot")  # and once more: nothing left to do
    third.scan(5)
    assert third.get("starts") == 1 and third.active() == [2, 20]


def test_a_warm_restart_between_a_swap_and_the_next_call_enters_the_new_sequencer_once(
    tmp_path: Path,
) -> None:
    """The warm restart initializes the sequencer (INIT_SQ in OB100): S20 enters with it,
    and the entry still pending does not run its S1 rows a second time."""
    state = tmp_path / "state.sqlite"
    _swapped_and_killed(state)
    again = Run(WITH_SECOND, state, restart="warm")
    assert again.active() == [1, 20] and again.get("starts") == 1
    again.scan(5)
    assert again.get("starts") == 1 and not again.session.graph.state.to_enter


def test_a_placement_queued_before_the_kill_is_carried_out_once_after_a_hot_restart(
    tmp_path: Path,
) -> None:
    state = tmp_path / "state.sqlite"
    run = Run(CHART, state, restart="hot")
    run.session.graph.command("SW_MAN")
    run.scan()
    run.session.graph.place([2])  # applied at a scan boundary: committed with it
    run.commit()
    run.kill()
    again = Run(CHART, state, restart="hot")
    assert again.active() == [1] and again.session.graph.state.to_place == [2]
    again.scan()
    assert again.active() == [2] and again.get("pieces") == 1
    again.scan(3)
    assert again.get("pieces") == 1 and not again.session.graph.state.to_place


def test_an_entry_pending_at_a_second_download_stays_pending_in_the_new_chart(
    tmp_path: Path,
) -> None:
    """Two swaps at one boundary: the first's new sequencer still gets its S1 rows."""
    run = Run(CHART, tmp_path / "state.sqlite")
    run.scan()
    swap(run.session.graph, compile_text(WITH_SECOND, "fill.s7g")[0], run.cpu)
    renamed = WITH_SECOND.replace('STEP S3 "Drain"', 'STEP S3 "Drain it"')
    swap(run.session.graph, compile_text(renamed, "fill.s7g")[0], run.cpu)
    assert run.session.graph.state.to_enter == [20]
    run.scan()
    assert run.get("starts") == 1


def test_a_sequencer_state_saved_before_pending_steps_were_kept_still_loads() -> None:
    saved = GraphState(3, 2).to_state()
    del saved["to_enter"], saved["to_place"]
    st = GraphState.from_state(saved)
    assert st.to_enter == [] and st.to_place == []


@pytest.mark.parametrize("value", ["S20", [20.0], [True], {"20": 1}])
def test_a_pending_step_list_that_is_not_step_numbers_is_refused(value: object) -> None:
    saved = GraphState(3, 2).to_state()
    saved["to_enter"] = value
    with pytest.raises(ValueError, match="'to_enter' is"):
        GraphState.from_state(saved)


def _sequencer(path: Path) -> dict[str, Any] | None:
    """The sequencer state the state file at ``path`` holds (a reader beside the run)."""
    row = query_store(path, lambda con: con.execute("SELECT data FROM instances").fetchone())
    return None if row is None else unpack_instance(row[0])["G7_STATE"]  # type: ignore[no-any-return]


@pytest.mark.timeout(180)
def test_a_run_killed_between_a_download_and_the_next_call_runs_the_entry_once_hot(
    tmp_path: Path,
) -> None:
    """``s7graph run --restart hot`` at a 2 s cycle: a download adds sequencer 2; the state
    file takes the swap at its scan boundary, and the run is killed (SIGKILL) as soon as the
    file holds the entry still to run — before the next call. The hot restart runs S20's
    S1 rows in its first call, once; a second restart does not run them again."""
    chart, state = tmp_path / "fill.s7g", tmp_path / "fill.sqlite"
    chart.write_text(CHART, encoding="utf-8")
    args = [str(chart), "--state", str(state), "--restart", "hot", "--rt-priority", "0"]
    with cpu_process(tmp_path, [*args, "--cycle-ms", "2000"], fb="Seq_fill", user="tess") as (
        proc,
        client,
        token,
    ):
        download = Command(
            op="download", fb="Seq_fill", user="tess", token=token, args={"source": WITH_SECOND}
        )
        sender = threading.Thread(target=_send, args=(client, download), daemon=True)
        sender.start()
        wait_for(_sequencer, state, lambda st: st.get("to_enter") == [20], proc)  # type: ignore[arg-type]
        kill_run(proc)
    on_disk = _sequencer(state)
    assert on_disk is not None and on_disk["to_enter"] == [20]
    assert on_disk["vars"]["starts"] == 0  # S20 active, its S1 rows not run yet
    for _ in range(2):  # the restart runs them; the next one finds nothing left to run
        assert main(["run", *args, "--duration-s", "0.5"]) == 0
        again = _sequencer(state)
        assert again is not None and again["vars"]["starts"] == 1 and again["to_enter"] == []


def _send(client: Any, command: Command) -> None:
    """Send ``command``; its reply may never come (the run is killed first)."""
    try:
        client.send(command, timeout=30)
    except Exception:  # the session closed under it
        return


# ---- operator commands queued for the next call (GraphFB.command, set_level)

ALARMED = (
    CHART.replace(
        'FUNCTION_BLOCK "Seq_fill" FB 1 DB 1\n',
        'FUNCTION_BLOCK "Seq_fill" FB 1 DB 1\n  ACK_REQUIRED := TRUE; MESSAGES := TRUE;\n',
    )
    .replace("  full : BOOL;\n", "  full : BOOL;\n  late : BOOL;\n")
    .replace(
        "    S1 N pieces := pieces + 1;\n",
        "    S1 N pieces := pieces + 1;\n    SUPERVISION := late;\n",
    )
)
SV = "Seq_fill/DB1/S2/SV"


def _queued_and_killed(state: Path, text: str, queue: Any, before: Any = None) -> None:
    """A hot run in S2; ``before(run)`` at one boundary, then ``queue(graph)`` at the next,
    committed with it (as the runner stages after the boundary's commands), and the run
    killed before the FB's next call."""
    run = Run(text, state, restart="hot")
    run.session.set("go", True)
    run.scan(3)
    if before is not None:
        before(run)
    queue(run.session.graph)
    run.commit()
    run.kill()


@pytest.mark.parametrize("restart", ["warm", "hot"])
def test_a_mode_selection_queued_before_the_kill_is_carried_out_once_after_the_restart(
    tmp_path: Path, restart: str
) -> None:
    """The mode survives a warm restart (manual 14-8), so the selection the audit calls
    applied does too: no restart of ours sets a mode it would undo."""
    state = tmp_path / "state.sqlite"
    _queued_and_killed(state, CHART, lambda g: g.command("SW_MAN"))
    again = Run(CHART, state, restart=restart)
    graph = again.session.graph
    if restart == "hot":  # nothing called yet: the selection waits for OB1's first call
        assert graph.state.to_command == [("SW_MAN", None, None)] and graph.state.mode == "AUTO"
        again.scan()
    assert graph.state.mode == "MAN" and graph.state.to_command == []
    again.scan()
    again.kill()
    third = Run(CHART, state, restart=restart)  # once: nothing left to select
    assert third.session.graph.state.to_command == []
    third.scan()
    assert third.session.graph.state.mode == "MAN"


def test_a_halt_queued_before_the_kill_holds_the_sequencer_after_a_hot_restart(
    tmp_path: Path,
) -> None:
    state = tmp_path / "state.sqlite"
    _queued_and_killed(state, CHART, lambda g: g.set_level("HALT_SQ", True))
    again = Run(CHART, state, restart="hot")
    assert again.session.graph.state.to_level == {"HALT_SQ": True}
    again.session.set("full", True)
    again.scan(3)
    graph = again.session.graph
    assert again.active() == [2] and graph.levels == {"HALT_SQ": True}
    assert graph.state.halted and graph.state.to_level == {}


def _fault(run: Run) -> None:
    """S2's supervision fault latched, its cause gone: it waits for an acknowledgement."""
    run.session.set("late", True)
    run.scan()
    run.session.set("late", False)
    run.scan()
    assert run.session.graph.state.sv_err[run.session.graph.cc.step_index[2]]


def test_an_acknowledgement_queued_before_the_kill_acknowledges_as_its_user_after_a_hot_restart(
    tmp_path: Path,
) -> None:
    state = tmp_path / "state.sqlite"
    _queued_and_killed(state, ALARMED, lambda g: g.command("ACK_EF", user="tess"), _fault)
    again = Run(ALARMED, state, restart="hot")
    assert again.session.graph.state.to_command == [("ACK_EF", None, "tess")]
    again.scan()
    graph = again.session.graph
    assert not graph.state.sv_err[graph.cc.step_index[2]]
    msg = message_list(again.cpu).get(SV)
    assert msg is None or (msg.acked and msg.ack_user == "tess")
    rows = [(r.kind, r.user) for r in message_list(again.cpu).log() if r.msg_id == SV]
    assert ("acknowledged", "tess") in rows and ("acknowledged", "program") not in rows


def test_an_acknowledgement_queued_before_the_kill_acknowledges_nothing_after_a_warm_restart(
    tmp_path: Path,
) -> None:
    """Decided: the warm restart's first call is OB100's, whose INIT_SQ clears the fault
    before the acknowledgement sees it, and a restart never acknowledges a message: the
    message goes outgoing with the restart as its reason and waits for someone, as it
    would without the command — never acknowledged in a user's name for a fault the user
    never saw released."""
    state = tmp_path / "state.sqlite"
    _queued_and_killed(state, ALARMED, lambda g: g.command("ACK_EF", user="tess"), _fault)
    again = Run(ALARMED, state, restart="warm")
    graph = again.session.graph
    assert again.active() == [1] and graph.state.to_command == []
    msg = message_list(again.cpu).get(SV)
    assert msg is not None and not msg.acked
    assert all(e.kind != "acknowledged" for e in message_list(again.cpu).log())


def test_a_cold_restart_clears_the_commands_queued_before_the_kill(tmp_path: Path) -> None:
    state = tmp_path / "state.sqlite"
    _queued_and_killed(state, CHART, lambda g: (g.command("SW_MAN"), g.set_level("HALT_SQ", True)))
    again = Run(CHART, state, restart="cold")
    graph = again.session.graph
    assert graph.state.to_command == [] and graph.state.to_level == {}
    again.scan(3)
    assert graph.state.mode == "AUTO" and graph.levels == {}


def test_commands_queued_at_a_download_stay_queued_in_the_new_chart(tmp_path: Path) -> None:
    run = Run(CHART, tmp_path / "state.sqlite")
    run.scan()
    run.session.graph.command("SW_MAN", user="tess")
    run.session.graph.set_level("HALT_SQ", True)
    swap(run.session.graph, compile_text(WITH_SECOND, "fill.s7g")[0], run.cpu)
    assert run.session.graph.state.to_command == [("SW_MAN", None, "tess")]
    run.scan()
    graph = run.session.graph
    assert graph.state.mode == "MAN" and graph.levels == {"HALT_SQ": True}


def test_a_sequencer_state_saved_before_commands_were_kept_still_loads() -> None:
    saved = GraphState(3, 2).to_state()
    del saved["to_command"], saved["to_level"], saved["to_release"]
    st = GraphState.from_state(saved)
    assert st.to_command == [] and st.to_level == {} and st.to_release == []


def test_queued_commands_restore_as_they_were_saved() -> None:
    st = GraphState(3, 2)
    st.to_command = [("S_ON", 2, None), ("ACK_S", 3, "tess")]
    st.to_level = {"HALT_SQ": True, "EN_IL": None}
    st.to_release = [2]
    again = GraphState.from_state(st.to_state())
    assert again.to_command == st.to_command and again.to_level == st.to_level
    assert again.to_release == [2]


@pytest.mark.parametrize(
    ("name", "value"),
    [
        ("to_command", "SW_MAN"),
        ("to_command", [["SW_MANUAL", None, None]]),
        ("to_command", [["SW_MAN", None]]),
        ("to_command", [["S_ON", 2.0, None]]),
        ("to_command", [["S_ON", True, None]]),
        ("to_command", [["ACK_EF", None, 7]]),
        ("to_level", {"HALT_SQ": 1}),
        ("to_level", {"HALT": True}),
        ("to_level", [["HALT_SQ", True]]),
        ("to_release", ["S2"]),
    ],
)
def test_a_queued_command_that_is_not_one_is_refused(name: str, value: object) -> None:
    saved = GraphState(3, 2).to_state()
    saved[name] = value
    with pytest.raises(ValueError, match=f"'{name}' (is|has an entry)"):
        GraphState.from_state(saved)


def test_a_command_on_a_pin_no_command_acts_as_is_refused_naming_the_fb(tmp_path: Path) -> None:
    """Else it would be saved in the instance DB and the state file refused at restart."""
    run = Run(CHART, tmp_path / "state.sqlite")
    with pytest.raises(ValueError, match="Seq_fill: 'SW_MANUAL' is not an edge pin"):
        run.session.graph.command("SW_MANUAL")
    with pytest.raises(ValueError, match="Seq_fill: 'HALT' is not a level pin"):
        run.session.graph.set_level("HALT", True)
    assert run.session.graph.state.to_command == [] and run.session.graph.state.to_level == {}


@pytest.mark.timeout(180)
def test_a_run_killed_between_a_commands_boundary_and_the_next_call_carries_it_out_hot(
    tmp_path: Path,
) -> None:
    """``s7graph run --restart hot`` at a 2 s cycle: a mode selection from the bus is taken
    at a scan boundary, whose commit holds both its audit row (*applied*) and the command
    queued in the instance DB; the run is killed (SIGKILL) as soon as the file holds it,
    before the FB's next call. The hot restart selects MAN in its first call, as the user
    asked; a second restart finds nothing left to do."""
    chart, state = tmp_path / "fill.s7g", tmp_path / "fill.sqlite"
    chart.write_text(CHART, encoding="utf-8")
    args = [str(chart), "--state", str(state), "--restart", "hot", "--rt-priority", "0"]
    slow = [*args, "--cycle-ms", "2000", "--max-cycle-ms", "5000"]
    with cpu_process(tmp_path, slow, fb="Seq_fill", user="tess") as (proc, client, token):
        mode = Command(op="mode", fb="Seq_fill", user="tess", token=token, args={"mode": "MAN"})
        sender = threading.Thread(target=_send, args=(client, mode), daemon=True)
        sender.start()
        queued = [["SW_MAN", None, None]]
        wait_for(_sequencer, state, lambda st: st.get("to_command") == queued, proc)  # type: ignore[arg-type]
        kill_run(proc)
    on_disk = _sequencer(state)
    assert on_disk is not None and on_disk["mode"] == "AUTO"
    assert [(r.op, r.outcome) for r in read_audit(state) if r.op == "mode"] == [("mode", "applied")]
    for _ in range(2):
        assert main(["run", *args, "--duration-s", "0.5"]) == 0
        again = _sequencer(state)
        assert again is not None and again["mode"] == "MAN" and again["to_command"] == []


def test_a_message_a_user_acknowledged_before_the_kill_releases_its_step_after_a_hot_restart(
    tmp_path: Path,
) -> None:
    """The call after the acknowledgement hands the release to the next one (``ack_msg``'s
    reply waits for that call's commit); before, it lived in the process: a kill between
    them brought the step back latched, its fault a new unacknowledged message."""
    state = tmp_path / "state.sqlite"
    run = Run(ALARMED, state, restart="hot")
    run.session.set("go", True)
    run.scan(3)
    _fault(run)
    assert message_list(run.cpu).acknowledge(SV, "tess", 0) is not None
    run.scan()  # the call that sees it: the release is the next call's
    graph = run.session.graph
    assert graph.state.to_release == [2] and graph.state.sv_err[graph.cc.step_index[2]]
    run.kill()
    again = Run(ALARMED, state, restart="hot")
    again.scan(3)
    graph = again.session.graph
    assert not graph.state.sv_err[graph.cc.step_index[2]] and graph.state.to_release == []
    assert message_list(again.cpu).get(SV) is None  # gone, never raised again
