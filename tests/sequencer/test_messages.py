"""Interlock and supervision messages in the CPU's message list (docs/semantics.md, "Messages"; seed
STEP7 comprehensive guide vol. 2, ch. 14). Chart: scenarios/messages.s7g (FB 1, DB 1)."""

from __future__ import annotations

from s7graph.engine.clock import VirtualClock
from s7graph.engine.cpu import Cpu
from s7graph.engine.record import ScanRecord
from s7graph.sequencer.compile import compile_chart
from s7graph.sequencer.fb import GraphFB, install_all
from s7graph.sequencer.messages import PROGRAM_USER, message_id, remote_acks, sync_messages
from s7graph.sequencer.state import GraphState
from s7graph.sequencer.text.parse import parse_chart
from s7graph.sfb.alarms import MessageList, MessageState, message_list
from tests.sequencer.helpers import Run, chart_text

SV1 = message_id("Msg_plant", 1, 1, "SV")
IL1 = message_id("Msg_plant", 1, 1, "IL")


def plant(**options: str) -> Run:
    source, text = chart_text("messages")
    for name, value in options.items():
        source = source.replace("MESSAGES := TRUE;", f"MESSAGES := TRUE; {name} := {value};")
    run = Run(source, file=text)
    run.wire(OFF_SQ="M10.0", INIT_SQ="M10.1", ACK_EF="M10.2")
    run.set(I1_0=True).call()
    assert run.active == [1] and run.messages.entries() == ()
    return run


def test_supervision_fault_raises_the_templated_message_with_step_text_and_time() -> None:
    run = plant()
    run.call(9)
    run.set(M3_1=True).call()
    (msg,) = run.messages.entries()
    assert msg.msg_id == SV1 and msg.state is MessageState.INCOMING
    assert msg.text == "S7GRAPH Supervision Error: FB1, DB1, S001 material is missing"
    assert msg.came_ns == 100_000_000 and msg.ack_required and msg.source == "S7-Graph"
    run.call(5)
    assert len(run.messages.entries()) == 1  # raised once, not every call


def test_message_goes_with_the_cause_but_the_step_waits_for_ack_ef() -> None:
    run = plant()
    run.set(M3_1=True).call()
    run.set(M3_1=False, I0_1=True).call(3)
    (msg,) = run.messages.entries()
    assert msg.state is MessageState.OUTGOING and not msg.acked
    assert run.active == [1]  # no transition until acknowledged (guide ch. 14)
    run.set(M10_2=True).call()
    assert run.active == [2] and run.messages.entries() == ()
    kinds = [(e.kind, e.user) for e in run.messages.log()]
    assert kinds == [("incoming", ""), ("outgoing", ""), ("acknowledged", PROGRAM_USER)]
    assert run.messages.log()[-1].t_ns == run.clock.now_ns() - 10_000_000


def test_interlock_error_message_comes_goes_and_is_acknowledged_by_ack_ef() -> None:
    run = plant()
    run.set(I1_0=False).call()
    (msg,) = run.messages.entries()
    assert msg.msg_id == IL1
    assert msg.text == "S7GRAPH Interlock Error: FB1, DB1, S001 material is missing"
    run.set(I1_0=True).call()
    assert run.messages.get(IL1).state is MessageState.OUTGOING  # type: ignore[union-attr]
    assert not run.out("ERR_FLT")  # the error cleared itself (semantics.md, "Interlock")
    run.set(M10_2=True).call()
    assert run.messages.entries() == ()
    assert run.messages.log()[-1].user == PROGRAM_USER


def test_ack_ef_while_the_cause_persists_leaves_the_fault_and_its_message() -> None:
    run = plant()
    run.set(M3_1=True).call()
    run.set(M10_2=True).call()
    (msg,) = run.messages.entries()
    assert not msg.acked and msg.state is MessageState.INCOMING and run.out("ERR_FLT")


def test_init_sq_clears_the_fault_and_acknowledges_its_message_as_program() -> None:
    run = plant()
    run.set(M3_1=True).call()
    run.set(M3_1=False, M10_1=True).call()
    assert run.messages.entries() == () and not run.out("ERR_FLT")


def test_message_acknowledged_by_a_user_in_the_list_is_reported_for_the_step() -> None:
    run = plant()
    run.set(M3_1=True).call()
    run.set(M3_1=False, I0_1=True).call()
    assert run.remote_acks == []
    assert run.messages.acknowledge(SV1, "alice", run.clock.now_ns()) is not None
    assert run.messages.entries() == ()  # gone and acknowledged: off the list
    assert remote_acks(run.cc, run.st, run.messages, "Msg_plant", 1) == [run.idx(1)]
    assert run.messages.log()[-1].user == "alice"


def test_remote_acknowledgement_releases_the_step_like_ack_s() -> None:
    run = plant()
    run.set(M3_1=True).call()
    run.set(M3_1=False, I0_1=True).call()
    run.messages.acknowledge(SV1, "alice", run.clock.now_ns())
    run.call(2)
    assert run.active == [2]


def test_no_messages_without_the_messages_option() -> None:
    source, _ = chart_text("messages")
    quiet = Run(source.replace("MESSAGES := TRUE;", "MESSAGES := FALSE;"))
    quiet.set(I1_0=False, M3_1=True).call(3)
    assert quiet.out("ERR_FLT") and quiet.messages.entries() == ()
    assert sync_messages(quiet.cc, quiet.st, quiet.messages, "x", 1, 0) == []


def test_without_acknowledgement_required_messages_leave_when_the_cause_goes() -> None:
    run = plant(ACK_REQUIRED="FALSE")
    run.set(M3_1=True).call()
    (msg,) = run.messages.entries()
    assert not msg.ack_required
    run.set(M3_1=False, I0_1=True).call(2)  # V0 in 4d, switching in the next call
    assert run.messages.entries() == () and run.active == [2]
    assert [e.kind for e in run.messages.log()] == ["incoming", "outgoing"]


def test_message_state_survives_snapshot_and_restore_without_raising_twice() -> None:
    run = plant()
    run.set(M3_1=True).call()
    saved_list = run.messages.snapshot()
    saved_state = run.st.to_state()
    restored = MessageList()
    restored.restore(saved_list)
    state = GraphState.from_state(saved_state)
    sync_messages(run.cc, state, restored, "Msg_plant", 1, 999)
    (msg,) = restored.entries()
    assert msg.event_id == 1 and msg.came_ns == run.messages.entries()[0].came_ns


# ---------------------------------------------------------------- the GraphFB in a CPU


def cpu_plant() -> tuple[Cpu, VirtualClock, GraphFB]:
    source, text = chart_text("messages")
    clock = VirtualClock()
    cpu = Cpu(clock)
    g = GraphFB(compile_chart(parse_chart(source, text)))
    install_all(cpu, [g])
    cpu.mem.periph_in[1] = 0b1  # I1.0: S1's interlock holds
    cpu.start("warm")
    return cpu, clock, g


def scan(cpu: Cpu, clock: VirtualClock) -> ScanRecord:
    clock.advance(10)
    return cpu.scan()


def test_graph_fb_raises_its_messages_in_the_cpus_list_and_a_user_ack_releases_the_step() -> None:
    cpu, clock, g = cpu_plant()
    messages = message_list(cpu)
    cpu.mem.set("M3.1", True)
    rec = scan(cpu, clock)
    msg = messages.get(SV1)
    assert msg is not None and msg.state is MessageState.INCOMING
    assert (SV1, "incoming") in [(e.msg_id, e.kind) for e in rec.alarms]  # in the record
    cpu.mem.set("M3.1", False)
    cpu.mem.periph_in[0] = 0b10  # I0.1: T1 holds
    scan(cpu, clock)
    assert g.state.active == [0]  # latched: waits for an acknowledgement
    t_ack = clock.now_ns()
    messages.acknowledge(SV1, "alice", t_ack)
    scan(cpu, clock)  # sync sees the user's acknowledgement: queued for the next call
    rec = scan(cpu, clock)
    assert g.state.active == [1]
    assert any(getattr(e, "event", "") == "A1" for e in rec.events)
    (acked,) = [e for e in messages.log() if e.kind == "acknowledged" and e.msg_id == SV1]
    assert (acked.user, acked.t_ns) == ("alice", t_ack)


def test_graph_fb_ack_ef_acknowledges_its_message_as_program() -> None:
    cpu, clock, g = cpu_plant()
    messages = message_list(cpu)
    cpu.mem.set("M3.1", True)
    scan(cpu, clock)
    cpu.mem.set("M3.1", False)
    scan(cpu, clock)
    g.idb.values["ACK_EF"] = True  # type: ignore[union-attr]
    scan(cpu, clock)
    assert messages.entries() == () and not g.outputs["ERR_FLT"]
    assert messages.log()[-1].kind == "acknowledged"
    assert (messages.log()[-1].user, messages.log()[-1].t_ns) == (PROGRAM_USER, clock.now_ns())


def test_a_message_of_a_step_a_download_removes_goes_outgoing_saying_why() -> None:
    """A step that is gone raises and clears nothing: its incoming message goes outgoing at
    the first call after the download, the download as its reason, and stays listed until
    acknowledged (as after a restart)."""
    from s7graph.sequencer.change.online import swap

    cpu, clock, g = cpu_plant()
    messages = message_list(cpu)
    cpu.mem.set("M3.1", True)
    scan(cpu, clock)
    assert messages.get(SV1).state is MessageState.INCOMING  # type: ignore[union-attr]
    source, text = chart_text("messages")
    renumbered = (
        source.replace("INITIAL_STEP S1", "INITIAL_STEP S9")
        .replace("FROM S1 ", "FROM S9 ")
        .replace("TO S1 :=", "TO S9 :=")
    )
    swap(g, compile_chart(parse_chart(renumbered, text)), cpu, removed="keep")
    rec = scan(cpu, clock)
    msg = messages.get(SV1)
    assert msg is not None and msg.state is MessageState.OUTGOING
    gone = [e for e in rec.alarms if e.msg_id == SV1]
    assert [(e.kind, e.reason) for e in gone] == [("outgoing", "a download removed its step")]
