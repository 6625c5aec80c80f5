"""The message list as OPC UA Alarms & Conditions, against a CPU on a real zenoh bus: an
interlock and a supervision message are AlarmConditionType events of their step's
conditions with their state; ``Acknowledge`` from an OPC UA client releases the step as
``ack_msg`` does and is audited under the OPC UA user; ``ConditionRefresh`` replays what
is retained; an anonymous session cannot acknowledge; a client that browses and reads a
condition node reads the state of its last event (docs/opcua.md, "Alarms and
conditions")."""

from __future__ import annotations

import asyncio
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pytest
from asyncua import ua
from asyncua.ua.uaerrors import UaStatusCodeError

from s7graph.web.access.audit import read_audit
from tests.web.helpers import wait_until
from tests.web.opcua.helpers import FACE_CN, FaceRig, connected, eventually, face_rig, node, run

if TYPE_CHECKING:
    from tests.conftest import BusCerts

pytestmark = pytest.mark.timeout(120)

ACK = ua.NodeId(ua.ObjectIds.AcknowledgeableConditionType_Acknowledge)
REFRESH = ua.NodeId(ua.ObjectIds.ConditionType_ConditionRefresh)


class Events:
    def __init__(self) -> None:
        self.seen: list[dict[str, Any]] = []

    def event_notification(self, event: Any) -> None:
        self.seen.append(event.get_event_props_as_fields_dict())

    def of(self, condition: str) -> list[dict[str, Any]]:
        return [e for e in self.seen if _value(e, "NodeId") == ua.NodeId(condition, 2)]


def _value(event: dict[str, Any], name: str) -> Any:
    field = event.get(name)
    return None if field is None else field.Value


def test_messages_are_conditions_and_an_opcua_acknowledge_releases_the_step(
    tmp_path: Path, bus_certs: BusCerts
) -> None:
    with face_rig(tmp_path, bus_certs) as face:
        run(_alarms(face))
    rows = [r for r in read_audit(face.rig.state) if r.op == "ack_msg"]
    assert [(r.user, r.outcome, r.role) for r in rows] == [("olga", "applied", "operator")]
    assert rows[0].origin.startswith(f"{FACE_CN}@tls/127.0.0.1:")  # the face's link
    assert "claimed origin: opcua 127.0.0.1:" in rows[0].detail  # the OPC UA client's
    assert "Seq_mix/DB1/S2/SV" in rows[0].args


async def _alarms(face: FaceRig) -> None:
    supervision = "cpu1/Seq_mix/S2/Supervision"
    interlock = "cpu1/Seq_mix/S2/Interlock"
    async with connected(face.url, "olga") as c, connected(face.url) as anonymous:
        events = Events()
        sub = await c.create_subscription(20, events)
        await sub.subscribe_alarms_and_conditions(c.nodes.server, ua.ObjectIds.AlarmConditionType)
        with pytest.raises(UaStatusCodeError) as refused:  # there, with no event yet
            await node(c, interlock).call_method(ACK, b"none yet", ua.LocalizedText("x"))
        assert refused.value.code == ua.StatusCodes.BadEventIdUnknown
        face.set("Guard", False)  # the interlock does not hold: S2 is disturbed, U stands
        face.set("Start", True)
        assert wait_until(lambda: face.active() == [2])
        assert await eventually(lambda: _holds(events.of(interlock), "ActiveState/Id", True))
        last = events.of(interlock)[-1]
        assert _value(last, "Severity") == 500 and _value(last, "ConditionName") == "Interlock"
        face.set("Guard", True)  # the interlock error goes; its message waits for an ack
        assert await eventually(lambda: _holds(events.of(interlock), "ActiveState/Id", False))
        last = events.of(interlock)[-1]
        assert _value(last, "Retain") is True and _value(last, "AckedState/Id") is False

        async def latched() -> bool:  # U runs now: past 400 ms the supervision latches
            got = events.of(supervision)
            return bool(got) and _value(got[-1], "ActiveState/Id") is True

        assert await eventually(latched), events.seen
        last = events.of(supervision)[-1]
        assert _value(last, "AckedState/Id") is False and _value(last, "Retain") is True
        assert _value(last, "Severity") == 700
        assert _value(last, "SourceNode") == ua.NodeId("cpu1/Seq_mix/S2", 2)
        assert "S2" in _value(last, "SourceName")
        assert _value(last, "EventType") == ua.NodeId(ua.ObjectIds.AlarmConditionType)

        face.set("Level", 200)  # T2 would switch, but the latched fault holds the step
        await asyncio.sleep(0.5)
        assert face.active() == [2]

        refreshed = Events()
        sub2 = await c.create_subscription(20, refreshed)
        await sub2.subscribe_alarms_and_conditions(c.nodes.server, ua.ObjectIds.AlarmConditionType)
        await c.nodes.server.call_method(
            REFRESH, ua.Variant(sub2.subscription_id, ua.VariantType.UInt32)
        )
        assert await eventually(lambda: _holds(refreshed.of(supervision), "Retain", True))

        event_id = _value(events.of(supervision)[-1], "EventId")
        condition = node(anonymous, supervision)
        for asked in (event_id, b"not one of ours"):  # refused first: nothing to learn
            with pytest.raises(UaStatusCodeError) as refused:
                await condition.call_method(ACK, asked, ua.LocalizedText("anon"))
            assert refused.value.code == ua.StatusCodes.BadUserAccessDenied
        for where, asked, comment, code in (
            (supervision, b"not one of ours", ua.LocalizedText("x"), "BadEventIdUnknown"),
            (supervision, event_id, "a String, not a LocalizedText", "BadTypeMismatch"),
        ):
            with pytest.raises(UaStatusCodeError) as refused:
                await node(c, where).call_method(ACK, asked, comment)
            assert refused.value.code == getattr(ua.StatusCodes, code), (where, comment)

        await node(c, supervision).call_method(ACK, event_id, ua.LocalizedText("seen it"))
        assert wait_until(lambda: face.active() == [3])  # released: T2 switched
        assert await eventually(lambda: _holds(events.of(supervision), "Retain", False))
        with pytest.raises(UaStatusCodeError) as refused:
            await node(c, supervision).call_method(ACK, event_id, ua.LocalizedText("again"))
        assert refused.value.code == ua.StatusCodes.BadConditionBranchAlreadyAcked
        face.set("Start", False)
        await sub.delete()
        await sub2.delete()


async def _holds(events: list[dict[str, Any]], name: str, value: object) -> bool:
    return bool(events) and _value(events[-1], name) == value


STATE = ("ActiveState/Id", "AckedState/Id", "EnabledState/Id", "Retain")


async def _state(c: Any, condition: str) -> dict[str, Any]:
    """The condition's state children as a client reads them."""
    return {name: await node(c, f"{condition}/{name}").read_value() for name in STATE}


def test_a_condition_node_holds_its_last_events_state_for_a_client_that_reads(
    tmp_path: Path, bus_certs: BusCerts
) -> None:
    with face_rig(tmp_path, bus_certs) as face:
        run(_read_state(face))


async def _read_state(face: FaceRig) -> None:
    supervision = "cpu1/Seq_mix/S2/Supervision"
    async with connected(face.url, "olga") as c:
        children = {
            (await k.read_browse_name()).Name: k for k in await node(c, supervision).get_children()
        }
        assert {"ActiveState", "AckedState", "EnabledState", "Retain", "Severity"} <= set(children)
        assert {"Message", "Time"} <= set(children)
        for state in ("ActiveState", "AckedState", "EnabledState"):
            kids = [(await k.read_browse_name()).Name for k in await children[state].get_children()]
            assert "Id" in kids, state
        before = {"ActiveState/Id": False, "AckedState/Id": True, "EnabledState/Id": True}
        assert await _state(c, supervision) == {**before, "Retain": False}  # no message yet
        assert await node(c, f"{supervision}/Severity").read_value() == 700
        events = Events()
        sub = await c.create_subscription(20, events)
        await sub.subscribe_alarms_and_conditions(c.nodes.server, ua.ObjectIds.AlarmConditionType)
        face.set("Guard", True)
        face.set("Start", True)  # S2: past 400 ms its supervision latches

        async def reads(active: bool, acked: bool) -> bool:
            got = events.of(supervision)
            state = await _state(c, supervision)
            told = {name: _value(got[-1], name) for name in STATE} if got else None
            return (
                state["ActiveState/Id"] is active
                and state["AckedState/Id"] is acked
                and (
                    state == told  # what its last event said
                )
            )

        assert await eventually(lambda: reads(active=True, acked=False)), events.seen
        came = await _state(c, supervision)
        assert came["Retain"] is True and came["EnabledState/Id"] is True
        assert await node(c, f"{supervision}/ActiveState").read_value() == ua.LocalizedText(
            "Active"
        )
        assert await node(c, f"{supervision}/Time").read_value() is not None
        text = await node(c, f"{supervision}/Message").read_value()
        assert text == _value(events.of(supervision)[-1], "Message")
        with pytest.raises(UaStatusCodeError) as refused:  # read only, for everyone
            await node(c, f"{supervision}/ActiveState/Id").write_value(False)
        assert refused.value.code == ua.StatusCodes.BadNotWritable

        face.set("Level", 200)  # T2 goes once the fault is acknowledged
        event_id = _value(events.of(supervision)[-1], "EventId")
        await node(c, supervision).call_method(ACK, event_id, ua.LocalizedText("seen"))
        assert await eventually(lambda: reads(active=False, acked=True)), events.seen
        assert wait_until(lambda: face.active() == [3])
        face.set("Start", False)
        await sub.delete()
