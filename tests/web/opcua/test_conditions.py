"""A condition node as a generic OPC UA client (UaExpert-like) meets it, against a CPU on a
real zenoh bus: it browses the condition to its ``Acknowledge`` method, reads its
``ConditionName``, ``LastSeverity`` and ``Comment``, and acknowledges through the method
it found; the comment becomes the condition's, stamped as OPC UA Part 9 says, and lands
in the audit row; a viewer is refused and audited, an anonymous session refused
(docs/opcua.md, "Alarms and conditions")."""

from __future__ import annotations

import time
from datetime import UTC, datetime
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import pytest
from asyncua import ua
from asyncua.ua.uaerrors import UaStatusCodeError

from s7graph.web.access.audit import Facts, read_audit
from s7graph.web.bus.client import BusClient
from s7graph.web.bus.protocol import AuditEntry, Command
from s7graph.web.bus.session import open_session
from s7graph.web.opcua.conditions import acked_comments
from s7graph.web.opcua.server import OpcuaOptions, OpcuaServer
from tests.web.helpers import wait_until
from tests.web.opcua.helpers import (
    PASSWORD,
    FaceRig,
    connected,
    eventually,
    face_rig,
    free_port,
    node,
    run,
)
from tests.web.opcua.test_alarms import Events, _value

if TYPE_CHECKING:
    from tests.conftest import BusCerts

pytestmark = pytest.mark.timeout(120)

SUPERVISION = "cpu1/Seq_mix/S2/Supervision"
COMMENT = ua.LocalizedText("valve checked", "en")


async def _acknowledge_method(c: Any) -> ua.NodeId:
    """The method named Acknowledge among the condition's components, as a client that
    browses finds it (with its two input arguments)."""
    refs = await node(c, SUPERVISION).get_references(
        ua.ObjectIds.HasComponent, ua.BrowseDirection.Forward
    )
    methods = [r for r in refs if r.NodeClass == ua.NodeClass.Method]
    assert [r.BrowseName.Name for r in methods] == ["Acknowledge"]
    found = c.get_node(methods[0].NodeId)
    arguments = await (await found.get_child("0:InputArguments")).read_value()
    assert [a.Name for a in arguments] == ["EventId", "Comment"]
    return methods[0].NodeId


async def _latched(face: FaceRig, events: Events) -> bytes:
    """Run S2 until its supervision latches; the EventId of the event that says so."""
    face.set("Guard", True)
    face.set("Start", True)  # S2: past 400 ms its supervision latches

    async def latched() -> bool:
        got = [e for e in events.seen if _value(e, "NodeId") == ua.NodeId(SUPERVISION, 2)]
        return bool(got) and _value(got[-1], "ActiveState/Id") is True

    assert await eventually(latched), events.seen
    face.set("Level", 200)  # T2 switches once the fault is acknowledged
    event_id: bytes = _value(events.of(SUPERVISION)[-1], "EventId")
    return event_id


def test_a_client_that_browses_a_condition_acknowledges_it_with_a_comment_kept_and_audited(
    tmp_path: Path, bus_certs: BusCerts
) -> None:
    with face_rig(tmp_path, bus_certs) as face:
        run(_browse_and_acknowledge(face))
    rows = [r for r in read_audit(face.rig.state) if r.op == "ack_msg"]
    assert [(r.user, r.outcome) for r in rows] == [("olga", "applied")]
    assert '"comment": "valve checked"' in rows[0].args


async def _browse_and_acknowledge(face: FaceRig) -> None:
    async with connected(face.url, "olga") as c:
        method = await _acknowledge_method(c)
        assert method == ua.NodeId(ua.ObjectIds.AcknowledgeableConditionType_Acknowledge)
        assert await node(c, f"{SUPERVISION}/ConditionName").read_value() == "Supervision"
        assert await node(c, f"{SUPERVISION}/LastSeverity").read_value() == 0
        assert await node(c, f"{SUPERVISION}/Comment").read_value() is None  # none given yet
        assert await node(c, f"{SUPERVISION}/Comment/SourceTimestamp").read_value() is None
        events = Events()
        sub = await c.create_subscription(20, events)
        await sub.subscribe_alarms_and_conditions(c.nodes.server, ua.ObjectIds.AlarmConditionType)
        event_id = await _latched(face, events)
        assert _value(events.of(SUPERVISION)[-1], "Comment") is None

        with pytest.raises(UaStatusCodeError) as refused:  # longer than an audit row keeps
            await node(c, SUPERVISION).call_method(method, event_id, ua.LocalizedText("x" * 257))
        assert refused.value.code == ua.StatusCodes.BadInvalidArgument
        await node(c, SUPERVISION).call_method(method, event_id, COMMENT)
        assert wait_until(lambda: face.active() == [3])  # released: T2 switched
        comment = node(c, f"{SUPERVISION}/Comment")
        assert await eventually(lambda: _reads(comment, COMMENT)), events.seen
        stamped = await node(c, f"{SUPERVISION}/Comment/SourceTimestamp").read_value()
        assert (await comment.read_data_value()).SourceTimestamp == stamped
        assert await eventually(lambda: _told(events, COMMENT)), events.seen
        told = [e for e in events.of(SUPERVISION) if _value(e, "Comment") == COMMENT]
        assert _value(told[-1], "AckedState/Id") is True
        assert _value(told[-1], "Comment/SourceTimestamp") == stamped
        assert await node(c, f"{SUPERVISION}/LastSeverity").read_value() == 0
        face.set("Start", False)
        await sub.delete()


def test_a_face_started_again_shows_the_comment_however_many_rows_came_after_an_emptying_audited(
    tmp_path: Path, bus_certs: BusCerts
) -> None:
    """The comment comes back from the message's newest acknowledgement with one, not from
    a window of the last rows: 60 rows after it (more than ``audit/list``'s 50) lose
    nothing."""
    with face_rig(tmp_path, bus_certs) as face:
        run(_browse_and_acknowledge(face))  # "valve checked" (en) given to the first face
        face.server.stop()
        audit = face.rig.online.gate.audit
        assert audit is not None
        for i in range(60):
            audit.record(
                time.time_ns(), Facts("eng", "engineer", "shell", "force", "", {"i": i}, True)
            )
        assert wait_until(lambda: len(read_audit(face.rig.state)) >= 61)
        server = face.server
        again = OpcuaServer(
            server.session, server.status, OpcuaOptions(url=f"opc.tcp://127.0.0.1:{free_port()}")
        )
        again.start()
        try:
            stamped = run(_comes_again(face, again.url))
        finally:
            again.stop()
    first, second = [r for r in read_audit(face.rig.state) if r.op == "ack_msg"]
    assert stamped == datetime.fromtimestamp(first.t_ns // 1_000_000 / 1000, UTC)
    assert '"comment": ""' in second.args


def test_a_running_face_shows_the_comment_another_client_acknowledged_with(
    tmp_path: Path, bus_certs: BusCerts
) -> None:
    """An ``ack_msg`` with a comment from a shell on the bus (the live audit feed): the
    condition's ``Comment`` becomes it, without a locale, stamped with the row's time, and
    an event carries it."""
    with (
        face_rig(tmp_path, bus_certs) as face,
        open_session(connect=[face.rig.endpoint], tls=face.rig.tls) as session,
        BusClient(session, "cpu1") as shell,
    ):
        run(_acknowledged_from_the_shell(face, shell))
    row = [r for r in read_audit(face.rig.state) if r.op == "ack_msg"][-1]
    assert (row.user, row.outcome) == ("eng", "applied")


async def _acknowledged_from_the_shell(face: FaceRig, shell: BusClient) -> None:
    async with connected(face.url, "olga") as c:
        events = Events()
        sub = await c.create_subscription(20, events)
        await sub.subscribe_alarms_and_conditions(c.nodes.server, ua.ObjectIds.AlarmConditionType)
        await _latched(face, events)
        login = shell.login("eng", PASSWORD)
        listed = shell.alarms()
        assert login.ok and listed is not None, login.reason
        (entry,) = [e for e in listed.entries if e.kind == "SV"]
        args = {"msg_id": entry.msg_id, "comment": "valve replaced"}
        reply = shell.send(
            Command(op="ack_msg", fb=entry.fb, user="eng", token=login.token, args=args)
        )
        assert reply.applied, reply.reason
        given = ua.LocalizedText("valve replaced")
        comment = node(c, f"{SUPERVISION}/Comment")
        assert await eventually(lambda: _reads(comment, given)), events.seen
        assert await eventually(lambda: _told(events, given)), events.seen
        told = [e for e in events.of(SUPERVISION) if _value(e, "Comment") == given]
        assert _value(told[-1], "AckedState/Id") is True
        row = [r for r in read_audit(face.rig.state) if r.op == "ack_msg"][-1]
        stamped = await node(c, f"{SUPERVISION}/Comment/SourceTimestamp").read_value()
        assert stamped.replace(tzinfo=UTC) == datetime.fromtimestamp(
            row.t_ns // 1_000_000 / 1000, UTC
        )
        face.set("Start", False)
        await sub.delete()


def test_the_comment_restored_is_the_newest_applied_acknowledgements_emptied_or_none() -> None:
    def row(t_ms: int, args: str, refused: bool = False, op: str = "ack_msg") -> AuditEntry:
        outcome: Literal["applied", "refused"] = "refused" if refused else "applied"
        return AuditEntry(id=t_ms, t_ms=t_ms, user="olga", op=op, args=args, outcome=outcome)

    rows = [
        row(1000, '{"comment": "first", "msg_id": "A"}'),
        row(2000, '{"comment": "second", "msg_id": "A"}'),
        row(3000, '{"msg_id": "A"}'),  # a Null comment leaves it
        row(4000, '{"comment": "not mine", "msg_id": "A"}', refused=True),
        row(5000, '{"comment": "a mode", "msg_id": "A"}', op="set_mode"),
        row(6000, "{not json"),
        row(1000, '{"comment": "kept", "msg_id": 7}'),
        row(2000, '{"comment": "", "msg_id": 7}'),  # emptied
        row(3000, '{"comment": "once", "msg_id": "B"}'),
    ]
    got = acked_comments(rows)
    assert {k: (v[0].Text, v[0].Locale, v[1].timestamp()) for k, v in got.items()} == {
        "A": ("second", None, 2.0),
        "B": ("once", None, 3.0),
    }


async def _comes_again(face: FaceRig, url: str) -> datetime:
    """The supervision latched again under a face that never saw the acknowledgement: its
    condition's event and node carry the comment, without a locale; when it was given."""
    async with connected(url, "olga") as c:
        assert await node(c, f"{SUPERVISION}/Comment").read_value() is None  # no message
        events = Events()
        sub = await c.create_subscription(20, events)
        await sub.subscribe_alarms_and_conditions(c.nodes.server, ua.ObjectIds.AlarmConditionType)
        assert wait_until(lambda: face.active() == [1])
        face.set("Level", 0)
        event_id = await _latched(face, events)
        restored = ua.LocalizedText("valve checked")
        assert _value(events.of(SUPERVISION)[-1], "Comment") == restored
        comment = node(c, f"{SUPERVISION}/Comment")
        assert await comment.read_value() == restored
        stamped: datetime = await node(c, f"{SUPERVISION}/Comment/SourceTimestamp").read_value()
        emptied = ua.LocalizedText("", "en")  # audited as "", so a face after it shows none
        method = ua.NodeId(ua.ObjectIds.AcknowledgeableConditionType_Acknowledge)
        await node(c, SUPERVISION).call_method(method, event_id, emptied)
        assert await eventually(lambda: _reads(comment, emptied))
        face.set("Start", False)
        await sub.delete()
        return stamped.replace(tzinfo=stamped.tzinfo or UTC)


async def _reads(variable: Any, value: object) -> bool:
    return bool(await variable.read_value() == value)


async def _told(events: Events, comment: ua.LocalizedText) -> bool:
    return any(_value(e, "Comment") == comment for e in events.of(SUPERVISION))


def test_a_viewer_acknowledging_a_condition_is_refused_and_audited_an_anonymous_one_refused(
    tmp_path: Path, bus_certs: BusCerts
) -> None:
    with face_rig(tmp_path, bus_certs) as face:
        run(_refused(face))
    rows = [r for r in read_audit(face.rig.state) if r.op == "ack_msg"]
    assert [(r.user, r.role, r.outcome) for r in rows] == [("vic", "viewer", "refused")]
    assert '"comment": "let me"' in rows[0].args


async def _refused(face: FaceRig) -> None:
    async with connected(face.url, "vic") as viewer, connected(face.url) as anonymous:
        events = Events()
        sub = await viewer.create_subscription(20, events)
        await sub.subscribe_alarms_and_conditions(
            viewer.nodes.server, ua.ObjectIds.AlarmConditionType
        )
        event_id = await _latched(face, events)
        for c, text in ((viewer, "let me"), (anonymous, "me too")):
            method = await _acknowledge_method(c)
            with pytest.raises(UaStatusCodeError) as refused:
                await node(c, SUPERVISION).call_method(method, event_id, ua.LocalizedText(text))
            assert refused.value.code == ua.StatusCodes.BadUserAccessDenied, text
        assert face.active() == [2]  # still held by the latched fault
        assert await node(viewer, f"{SUPERVISION}/Comment").read_value() is None
        face.set("Start", False)
        await sub.delete()
