"""What a SCADA's first connection found (docs/opcua.md, "Values and their status",
"Methods", "Node ids of no node"): a read's ``IndexRange`` answers that part of an array
(OPC UA Part 4, 7.27), a write with one is refused and sends nothing, the null node id is
``BadNodeIdInvalid`` to a read and a write as to a browse, a value the CPU refuses as an
argument is ``BadInvalidArgument``, a session may refresh the conditions of its own
subscriptions only (an id of another type is a type mismatch), and a sequence's and a
chart's variables say what they are."""

from __future__ import annotations

import asyncio
from collections.abc import Iterator
from typing import TYPE_CHECKING, Any

import pytest
from asyncua import ua
from asyncua.ua.uaerrors import UaStatusCodeError

from s7graph.web.access.audit import read_audit
from tests.web.opcua.helpers import (
    CHART,
    FaceRig,
    connected,
    eventually,
    face_rig,
    node,
    run,
)

if TYPE_CHECKING:
    from tests.conftest import BusCerts

pytestmark = pytest.mark.timeout(180)

NUMBER = ua.NodeId("cpu1/DiagnosticBuffer/Number", 2)
COMMENTED = CHART.replace("T#2S;", "T#2S;  // how long the mixer runs", 1)


@pytest.fixture(scope="module")
def face(tmp_path_factory: pytest.TempPathFactory, bus_certs: BusCerts) -> Iterator[FaceRig]:
    with face_rig(tmp_path_factory.mktemp("trial"), bus_certs, chart=COMMENTED) as rig:
        yield rig


def _reads(*asked: tuple[ua.NodeId, str]) -> ua.ReadParameters:
    params = ua.ReadParameters()
    params.NodesToRead = [
        ua.ReadValueId(NodeId=nid, AttributeId=ua.AttributeIds.Value, IndexRange=rng)
        for nid, rng in asked
    ]
    return params


def test_a_read_of_an_index_range_answers_that_part_of_the_value(face: FaceRig) -> None:
    async def check() -> None:
        async with connected(face.url) as c:
            assert await eventually(lambda: _longer_than(c, 1))
            whole = await c.get_node(NUMBER).read_value()
            ranges = ["1:2", "0", "1:999", "999", "0:x", "2:1", "1,0"]
            got = await c.uaclient.read(_reads(*((NUMBER, r) for r in ranges)))
            assert [v.Value.Value for v in got[:3]] == [whole[1:3], whole[:1], whole[1:]]
            assert got[0].Value.VariantType == ua.VariantType.UInt32
            assert [v.StatusCode.name for v in got[3:]] == [
                "BadIndexRangeNoData",  # past the end
                "BadIndexRangeInvalid",  # not Part 4's syntax
                "BadIndexRangeInvalid",  # the upper bound not above the lower
                "BadIndexRangeNoData",  # two dimensions of an array of numbers
            ]
            state, cycle = ua.NodeId("cpu1/State", 2), ua.NodeId("cpu1/Cycle", 2)
            got = await c.uaclient.read(_reads((state, "0:1"), (cycle, "0"), (state, "")))
            assert got[0].Value.Value == "RU"  # a String is an array of its characters
            assert got[1].StatusCode.name == "BadIndexRangeNoData"  # a number is no array
            assert got[2].Value.Value == "RUN"
            text = ua.NodeId("cpu1/DiagnosticBuffer/Text", 2)
            lines = await c.get_node(text).read_value()
            got = await c.uaclient.read(_reads((text, "0,0:2")))
            assert got[0].Value.Value == [lines[0][:3]]  # a part of each String of an array

    run(check())


async def _longer_than(c: object, n: int) -> bool:
    value = await c.get_node(NUMBER).read_value()  # type: ignore[attr-defined]
    return isinstance(value, list) and len(value) > n


class _Changes:
    """What a subscription's data change handler was given: (node id, data value)."""

    def __init__(self) -> None:
        self.seen: list[tuple[str, ua.DataValue]] = []

    def datachange_notification(self, n: Any, value: object, data: Any) -> None:
        self.seen.append((n.nodeid.Identifier, data.monitored_item.Value))


def _item(nid: ua.NodeId, rng: str, handle: int) -> ua.MonitoredItemCreateRequest:
    item = ua.MonitoredItemCreateRequest()
    item.ItemToMonitor = ua.ReadValueId(
        NodeId=nid, AttributeId=ua.AttributeIds.Value, IndexRange=rng
    )
    item.MonitoringMode = ua.MonitoringMode.Reporting
    item.RequestedParameters = ua.MonitoringParameters(ClientHandle=handle, QueueSize=10)
    return item


def test_a_monitored_item_of_an_index_range_is_notified_of_that_part(face: FaceRig) -> None:
    async def check() -> None:
        async with connected(face.url) as c:
            assert await eventually(lambda: _longer_than(c, 1))
            whole = await c.get_node(NUMBER).read_value()
            changes = _Changes()
            sub = await c.create_subscription(50, changes)
            steps = ua.NodeId("cpu1/Seq_mix/ActiveSteps", 2)
            made = await sub.create_monitored_items(
                [_item(NUMBER, "1", 1), _item(steps, "9", 2), _item(NUMBER, "1:0", 3)]
            )
            assert made[2] == ua.StatusCode(ua.StatusCodes.BadIndexRangeInvalid)
            assert await eventually(lambda: _async(len(changes.seen) >= 2))
            first = dict(changes.seen)
            assert first[NUMBER.Identifier].Value.Value == whole[1:2]
            assert first[steps.Identifier].StatusCode.name == "BadIndexRangeNoData"

    run(check())


async def _async(value: bool) -> bool:
    return value


def test_a_write_with_an_index_range_is_refused_and_sends_nothing(face: FaceRig) -> None:
    async def check() -> None:
        async with connected(face.url, "olga") as c:
            mode = ua.NodeId("cpu1/Seq_mix/Mode", 2)
            params = ua.WriteParameters()
            params.NodesToWrite = [
                ua.WriteValue(
                    NodeId=mode,
                    AttributeId=ua.AttributeIds.Value,
                    Value=ua.DataValue(ua.Variant("MAN")),
                    IndexRange=rng,
                )
                for rng in ("0:2", "x")
            ]
            got = await c.uaclient.write(params)
            assert [s.name for s in got] == ["BadWriteNotSupported", "BadIndexRangeInvalid"]
            assert await node(c, "cpu1/Seq_mix/Mode").read_value() == "AUTO"
        rows = read_audit(face.rig.state)
        assert not [r for r in rows if r.op == "mode"]

    run(check())


def test_the_null_node_id_is_invalid_to_a_read_and_a_write_as_to_a_browse(
    face: FaceRig,
) -> None:
    async def check() -> None:
        async with connected(face.url, "olga") as c:
            null, nowhere = ua.NodeId(), ua.NodeId("cpu1/Nowhere", 2)
            got = await c.uaclient.read(_reads((null, ""), (nowhere, "")))
            assert [v.StatusCode.name for v in got] == ["BadNodeIdInvalid", "BadNodeIdUnknown"]
            params = ua.WriteParameters()
            params.NodesToWrite = [
                ua.WriteValue(NodeId=nid, AttributeId=ua.AttributeIds.Value, Value=ua.DataValue(1))
                for nid in (null, nowhere)
            ]
            got = await c.uaclient.write(params)
            assert [s.name for s in got] == ["BadNodeIdInvalid", "BadNodeIdUnknown"]

    run(check())


def test_a_value_the_cpu_refuses_as_an_argument_is_an_invalid_argument(face: FaceRig) -> None:
    async def check() -> None:
        async with connected(face.url, "eng") as c:
            cpu, fb = node(c, "cpu1"), node(c, "cpu1/Seq_mix")
            calls = [
                (cpu, "cpu1/Force", ["XYZ", True]),  # no S7 address, no symbol
                (cpu, "cpu1/Modify", ["MW20", ua.Variant(70000, ua.VariantType.Int32)]),
                (fb, "cpu1/Seq_mix/Open", ["../mix.s7g"]),  # no file of the project
                (fb, "cpu1/Seq_mix/Download", ["garbage"]),  # a chart that does not parse
            ]
            for obj, method, inputs in calls:
                with pytest.raises(UaStatusCodeError) as refused:
                    await obj.call_method(ua.NodeId(method, 2), *inputs)
                assert refused.value.code == ua.StatusCodes.BadInvalidArgument, method
        ops = [r.op for r in read_audit(face.rig.state) if r.user == "eng"]
        assert {"force", "modify", "open", "download"} <= set(ops)  # the CPU said so

    run(check())


def test_a_sequences_number_and_name_say_what_they_are(face: FaceRig) -> None:
    async def check() -> None:
        async with connected(face.url) as c:
            number = await node(c, "cpu1/Seq_mix/Sequence1/Number").read_description()
            name = await node(c, "cpu1/Seq_mix/Sequence1/Name").read_description()
            assert (number.Text, name.Text) == ("the sequence's number", "the sequence's name")

    run(check())


def test_a_chart_variable_says_its_comment_or_what_it_is(face: FaceRig) -> None:
    async def check() -> None:
        async with connected(face.url) as c:
            folder = "cpu1/Seq_mix/Variables"
            assert await eventually(lambda: _has(c, f"{folder}/dwell"))
            dwell = await node(c, f"{folder}/dwell").read_description()
            count = await node(c, f"{folder}/count").read_description()
            assert dwell.Text == "how long the mixer runs (TIME)"
            assert count.Text == "the chart's variable count of the GRAPH FB Seq_mix (INT)"

    run(check())


async def _has(c: Any, path: str) -> bool:
    try:
        await node(c, path).read_description()
    except UaStatusCodeError:
        return False
    return True


class _Events:
    def __init__(self) -> None:
        self.seen: list[Any] = []

    def event_notification(self, event: Any) -> None:
        self.seen.append(event)


def test_a_session_refreshes_the_conditions_of_its_own_subscriptions_only(
    face: FaceRig,
) -> None:
    refresh = ua.NodeId(ua.ObjectIds.ConditionType_ConditionRefresh)
    refresh2 = ua.NodeId(ua.ObjectIds.ConditionType_ConditionRefresh2)

    async def check() -> None:
        async with connected(face.url, "olga") as scada, connected(face.url) as other:
            events = _Events()
            sub = await scada.create_subscription(50, events)
            item = await sub.subscribe_events(scada.nodes.server, ua.ObjectIds.BaseEventType)
            sid = ua.Variant(sub.subscription_id, ua.VariantType.UInt32)
            mid = ua.Variant(item, ua.VariantType.UInt32)
            for method, inputs in ((refresh, [sid]), (refresh2, [sid, mid])):
                with pytest.raises(UaStatusCodeError) as refused:
                    await other.nodes.server.call_method(method, *inputs)
                assert refused.value.code == ua.StatusCodes.BadSubscriptionIdInvalid
            await scada.nodes.server.call_method(refresh, sid)  # its own: served
            start, end = ua.ObjectIds.RefreshStartEventType, ua.ObjectIds.RefreshEndEventType

            def kinds() -> list[int]:
                return [e.EventType.Identifier for e in events.seen]

            assert await eventually(lambda: _async(end in kinds()))
            await asyncio.sleep(0.3)  # anything that came later would be here by now
            assert kinds().count(start) == kinds().count(end) == 1  # the other's calls sent none

    run(check())


def test_a_condition_refresh_with_an_id_of_another_type_is_a_type_mismatch(
    face: FaceRig,
) -> None:
    """As the face's other methods answer a wrong type (OPC UA Part 4, "Call"), never
    ``BadSubscriptionIdInvalid`` for a String that looks like an id."""
    refresh = ua.NodeId(ua.ObjectIds.ConditionType_ConditionRefresh)
    refresh2 = ua.NodeId(ua.ObjectIds.ConditionType_ConditionRefresh2)

    async def check() -> None:
        async with connected(face.url, "olga") as scada:
            sub = await scada.create_subscription(50, _Events())
            sid = sub.subscription_id
            good = ua.Variant(sid, ua.VariantType.UInt32)
            text = ua.Variant(str(sid), ua.VariantType.String)
            calls = [
                (refresh, [text]),
                (refresh2, [good, ua.Variant(1.0, ua.VariantType.Double)]),
                (refresh, []),
                (refresh, [good, good]),
            ]
            asked = [
                ua.CallMethodRequest(
                    ObjectId=scada.nodes.server.nodeid, MethodId=m, InputArguments=i
                )
                for m, i in calls
            ]
            got = await scada.uaclient.call(asked)
            assert [r.StatusCode.name for r in got] == [
                "BadInvalidArgument",
                "BadInvalidArgument",
                "BadArgumentsMissing",
                "BadTooManyArguments",
            ]
            assert [c.name for c in got[0].InputArgumentResults] == ["BadTypeMismatch"]
            assert [c.name for c in got[1].InputArgumentResults] == ["Good", "BadTypeMismatch"]

    run(check())


def test_the_servers_build_info_is_s7graphs(face: FaceRig) -> None:
    async def check() -> None:
        from s7graph import __version__

        async with connected(face.url) as c:
            info = await c.get_node(ua.ObjectIds.Server_ServerStatus_BuildInfo).read_value()
            name = ua.ObjectIds.Server_ServerStatus_BuildInfo_ProductName
            assert await c.get_node(name).read_value() == "s7graph OPC UA face"
            assert (info.ManufacturerName, info.ProductUri) == ("s7graph", "urn:s7graph")
            assert info.SoftwareVersion == info.BuildNumber == __version__
            status = await c.get_node(ua.ObjectIds.Server_ServerStatus).read_value()
            assert status.BuildInfo.ProductName == "s7graph OPC UA face"

    run(check())
