"""Malformed and hostile OPC UA requests get a bad status code, never a crash of the face
and never a command to the CPU: requests with too many operations, a request larger than
the server takes, floods of subscriptions and monitored items, a publishing interval of
nothing, wrong argument types and counts, garbage on the socket (docs/opcua.md,
"Limits")."""

from __future__ import annotations

import asyncio
import socket
import struct
import time
from collections.abc import Iterator
from typing import TYPE_CHECKING
from urllib.parse import urlparse

import pytest
from asyncua import ua
from asyncua.ua.uaerrors import UaStatusCodeError

from s7graph.web.access.audit import read_audit
from s7graph.web.opcua.sessions import Limits
from tests.web.opcua.helpers import FaceRig, connected, face_rig, node, run

if TYPE_CHECKING:
    from tests.conftest import BusCerts

pytestmark = pytest.mark.timeout(180)

LIMITS = Limits()
STEP_ON = ua.NodeId("cpu1/Seq_mix/StepOn", 2)
SET_MODE = ua.NodeId("cpu1/Seq_mix/SetMode", 2)


@pytest.fixture(scope="module")
def face(tmp_path_factory: pytest.TempPathFactory, bus_certs: BusCerts) -> Iterator[FaceRig]:
    with face_rig(tmp_path_factory.mktemp("hostile"), bus_certs) as rig:
        yield rig


def _code(exc: BaseException) -> int:
    assert isinstance(exc, UaStatusCodeError), repr(exc)
    return int(exc.code)


def test_a_request_of_too_many_operations_is_refused(face: FaceRig) -> None:
    async def check() -> None:
        async with connected(face.url) as c:
            many = LIMITS.operations + 1
            browse = ua.BrowseParameters()
            browse.NodesToBrowse = [
                ua.BrowseDescription(NodeId=ua.NodeId("cpu1", 2), ResultMask=63)
                for _ in range(many)
            ]
            with pytest.raises(UaStatusCodeError) as refused:
                await c.uaclient.browse(browse)
            assert _code(refused.value) == ua.StatusCodes.BadTooManyOperations
            read = ua.ReadParameters()
            read.NodesToRead = [
                ua.ReadValueId(NodeId=ua.NodeId("cpu1/State", 2), AttributeId=13)
                for _ in range(many)
            ]
            with pytest.raises(UaStatusCodeError) as refused:
                await c.uaclient.read(read)
            assert _code(refused.value) == ua.StatusCodes.BadTooManyOperations
            # at the limit it is served
            browse.NodesToBrowse = browse.NodesToBrowse[: LIMITS.operations]
            assert len(await c.uaclient.browse(browse)) == LIMITS.operations

    run(check())


def test_a_request_larger_than_the_server_takes_closes_only_that_connection(
    face: FaceRig,
) -> None:
    async def check() -> None:
        with pytest.raises((UaStatusCodeError, ConnectionError, asyncio.TimeoutError)):
            async with connected(face.url, "olga") as c:
                huge = "x" * (9 << 20)  # over the 8 MiB a request may be
                await node(c, "cpu1/Seq_mix/Mode").write_value(ua.Variant(huge))
        async with connected(face.url) as c:  # the face goes on serving
            assert await node(c, "cpu1/State").read_value() == "RUN"

    run(check())


def test_floods_of_subscriptions_and_monitored_items_are_refused(face: FaceRig) -> None:
    async def check() -> None:
        async with connected(face.url) as c:
            subs = []
            for _ in range(LIMITS.subscriptions):
                subs.append(await c.create_subscription(100, None))
            with pytest.raises(UaStatusCodeError) as refused:
                await c.create_subscription(100, None)
            assert _code(refused.value) == ua.StatusCodes.BadTooManySubscriptions
            for sub in subs[1:]:
                await sub.delete()
            sub = subs[0]
            state = node(c, "cpu1/State")
            with pytest.raises(UaStatusCodeError) as refused:  # one call of too many
                await sub.subscribe_data_change([state] * (LIMITS.operations + 1))
            assert _code(refused.value) == ua.StatusCodes.BadTooManyOperations
            for _ in range(LIMITS.monitored_items // LIMITS.operations):
                await sub.subscribe_data_change([state] * LIMITS.operations)
            results = await sub.subscribe_data_change([state, state])
            assert all(isinstance(r, ua.StatusCode) for r in results), results
            assert {r.value for r in results} == {ua.StatusCodes.BadTooManyMonitoredItems}
            await sub.delete()

    run(check())


def test_a_filter_that_does_not_go_with_its_attribute_is_refused_per_item(
    face: FaceRig,
) -> None:
    """An EventFilter on a value (or a DataChangeFilter on events) is that item's
    ``BadFilterNotAllowed``; the other items of the request are made (asyncua alone
    answered the whole request with ``BadInternalError``)."""

    async def check() -> None:
        async with connected(face.url) as c:
            result = await c.uaclient.create_subscription(
                ua.CreateSubscriptionParameters(
                    RequestedPublishingInterval=100,
                    RequestedLifetimeCount=100,
                    RequestedMaxKeepAliveCount=10,
                    PublishingEnabled=True,
                ),
                lambda *_: None,
            )

            def item(
                attribute: int, filter_: object, handle: int, node: object = None
            ) -> ua.MonitoredItemCreateRequest:
                made = ua.MonitoredItemCreateRequest()
                made.ItemToMonitor = ua.ReadValueId(
                    NodeId=node or ua.NodeId("cpu1/State", 2), AttributeId=attribute
                )
                made.MonitoringMode = ua.MonitoringMode.Reporting
                made.RequestedParameters = ua.MonitoringParameters(
                    ClientHandle=handle, SamplingInterval=100, QueueSize=1, Filter=filter_
                )
                return made

            value, events = ua.AttributeIds.Value, ua.AttributeIds.EventNotifier
            server = ua.NodeId(ua.ObjectIds.Server)
            params = ua.CreateMonitoredItemsParameters(
                SubscriptionId=result.SubscriptionId,
                TimestampsToReturn=ua.TimestampsToReturn.Both,
                ItemsToCreate=[
                    item(value, ua.EventFilter(), 1),
                    item(value, None, 2),
                    item(value, ua.AggregateFilter(), 3),
                    item(value, ua.DataChangeFilter(), 4),
                    item(events, ua.DataChangeFilter(), 5, server),  # events, not values
                ],
            )
            made = await c.uaclient.create_monitored_items(params)
            codes = [r.StatusCode.name for r in made]
            refused = "BadFilterNotAllowed"
            assert codes == [refused, "Good", refused, "Good", refused]
            await c.uaclient.delete_subscriptions([result.SubscriptionId])

    run(check())


def test_a_publishing_interval_of_nothing_is_revised_to_the_minimum(face: FaceRig) -> None:
    async def check() -> None:
        async with connected(face.url) as c:
            params = ua.CreateSubscriptionParameters()
            params.RequestedPublishingInterval = 0.0
            params.RequestedLifetimeCount = 100
            params.RequestedMaxKeepAliveCount = 10
            params.PublishingEnabled = True
            result = await c.uaclient.create_subscription(params, lambda *_: None)
            assert result.RevisedPublishingInterval == LIMITS.min_publishing_ms
            await c.uaclient.delete_subscriptions([result.SubscriptionId])

    run(check())


def test_wrong_arguments_are_refused_by_status_code(face: FaceRig) -> None:
    before = [r for r in read_audit(face.rig.state) if r.op not in ("login", "logout")]

    async def call(c: object, method: ua.NodeId, *args: object) -> ua.CallMethodResult:
        request = ua.CallMethodRequest()
        request.ObjectId = ua.NodeId("cpu1/Seq_mix", 2)
        request.MethodId = method
        request.InputArguments = list(args)
        (result,) = await c.uaclient.call([request])  # type: ignore[attr-defined]
        return result

    async def check() -> None:
        async with connected(face.url, "olga") as c:
            bad = await call(c, STEP_ON, ua.Variant("three"))
            assert bad.StatusCode.value == ua.StatusCodes.BadInvalidArgument
            assert [r.value for r in bad.InputArgumentResults] == [ua.StatusCodes.BadTypeMismatch]
            bad = await call(c, STEP_ON, ua.Variant(0, ua.VariantType.UInt16))  # steps from 1
            assert bad.StatusCode.value == ua.StatusCodes.BadInvalidArgument
            bad = await call(c, STEP_ON, ua.Variant([1, 2], ua.VariantType.UInt16))
            assert bad.StatusCode.value == ua.StatusCodes.BadInvalidArgument
            bad = await call(c, SET_MODE)
            assert bad.StatusCode.value == ua.StatusCodes.BadArgumentsMissing
            bad = await call(c, SET_MODE, ua.Variant("MAN"), ua.Variant("AUTO"))
            assert bad.StatusCode.value == ua.StatusCodes.BadTooManyArguments
            bad = await call(c, SET_MODE, ua.Variant("FAST"))
            assert bad.StatusCode.value == ua.StatusCodes.BadInvalidArgument
            bad = await call(c, ua.NodeId("cpu1/Seq_mix/NoSuchOp", 2))
            assert bad.StatusCode.value == ua.StatusCodes.BadMethodInvalid
            with pytest.raises(UaStatusCodeError) as refused:
                await node(c, "cpu1/NoSuchNode").read_value()
            assert _code(refused.value) == ua.StatusCodes.BadNodeIdUnknown

    run(check())
    after = [r for r in read_audit(face.rig.state) if r.op not in ("login", "logout")]
    assert after == before  # no command went to the CPU


def test_a_node_id_of_no_node_is_unknown_and_a_call_of_no_method_is_method_invalid(
    face: FaceRig,
) -> None:
    """OPC UA Part 4: a well-formed node id of no node is ``BadNodeIdUnknown`` (Browse,
    TranslateBrowsePathsToNodeIds, Call's object, an event item), the null node id or a
    call's object that is no object ``BadNodeIdInvalid``, a call's method that is no
    method ``BadMethodInvalid``, one not implemented ``BadNotImplemented``; Part 9:
    ``Acknowledge`` on an object that is no condition ``BadMethodInvalid``, on the
    condition type ``BadNodeIdInvalid``. Nothing reaches the CPU."""
    before = len(read_audit(face.rig.state))
    nowhere = ua.NodeId("cpu1/NoSuchNode", 2)
    ack = ua.NodeId(ua.ObjectIds.AcknowledgeableConditionType_Acknowledge)
    supervision = ua.NodeId("cpu1/Seq_mix/S2/Supervision", 2)

    def call(obj: ua.NodeId, method: ua.NodeId, *args: object) -> ua.CallMethodRequest:
        return ua.CallMethodRequest(ObjectId=obj, MethodId=method, InputArguments=list(args))

    async def check() -> None:
        async with connected(face.url, "olga") as c:
            browsed = await c.uaclient.browse(
                ua.BrowseParameters(
                    NodesToBrowse=[
                        ua.BrowseDescription(NodeId=nowhere),
                        ua.BrowseDescription(NodeId=ua.NodeId()),
                        ua.BrowseDescription(NodeId=ua.NodeId("cpu1", 2)),
                    ]
                )
            )
            assert [r.StatusCode.name for r in browsed] == [
                "BadNodeIdUnknown",
                "BadNodeIdInvalid",
                "Good",
            ]
            path = ua.BrowsePath(StartingNode=nowhere)
            path.RelativePath.Elements = [ua.RelativePathElement(TargetName=ua.QualifiedName("X"))]
            (found,) = await c.uaclient.translate_browsepaths_to_nodeids([path])
            assert found.StatusCode.name == "BadNodeIdUnknown"
            words = ua.Variant(b"x"), ua.Variant(ua.LocalizedText("x"))
            called = await c.uaclient.call(
                [
                    call(nowhere, ua.NodeId("cpu1/Seq_mix/Init", 2)),
                    call(ua.NodeId("cpu1/State", 2), ua.NodeId("cpu1/Seq_mix/Init", 2)),
                    call(ua.NodeId("cpu1/Seq_mix", 2), ua.NodeId("cpu1/Seq_mix/NoSuchOp", 2)),
                    call(ua.NodeId("cpu1/Seq_mix", 2), ua.NodeId("cpu1/Seq_mix/Mode", 2)),
                    call(supervision, ua.NodeId(ua.ObjectIds.ConditionType_Disable)),
                    call(ua.NodeId("cpu1/Symbols", 2), ack, *words),
                    call(ua.NodeId(ua.ObjectIds.AcknowledgeableConditionType), ack, *words),
                    call(supervision, ack, *words),
                ]
            )
            assert [r.StatusCode.name for r in called] == [
                "BadNodeIdUnknown",
                "BadNodeIdInvalid",
                "BadMethodInvalid",
                "BadMethodInvalid",
                "BadNotImplemented",
                "BadMethodInvalid",
                "BadNodeIdInvalid",
                "BadEventIdUnknown",  # a condition: an event it never sent
            ]
            sub = await c.create_subscription(100, None)
            with pytest.raises(UaStatusCodeError) as refused:
                await sub.subscribe_events(nowhere)
            assert _code(refused.value) == ua.StatusCodes.BadNodeIdUnknown
            await sub.delete()

    run(check())
    rows = read_audit(face.rig.state)[before:]
    assert [r for r in rows if r.op not in ("login", "logout")] == []


def test_no_client_registers_a_server_with_the_face(face: FaceRig) -> None:
    async def check() -> None:
        async with connected(face.url) as c:
            server = ua.RegisteredServer()
            server.ServerUri = "urn:someone:else"
            server.ServerNames = [ua.LocalizedText("someone")]
            server.IsOnline = True
            with pytest.raises(UaStatusCodeError) as refused:
                await c.uaclient.register_server(server)
            assert _code(refused.value) == ua.StatusCodes.BadServiceUnsupported
            assert [s.ApplicationUri for s in await c.find_servers()] == ["urn:s7graph:opcua:cpu1"]

    run(check())


def test_garbage_on_the_socket_costs_that_connection_only(face: FaceRig) -> None:
    where = urlparse(face.url)
    for garbage in (b"\x00" * 64, b"HEL" + b"\xff" * 5000, b"MSGF" + b"\x10\x00\x00\x00" * 64):
        with socket.create_connection((where.hostname, where.port), timeout=5) as s:
            s.sendall(garbage)
            s.settimeout(5)
            try:
                while s.recv(65536):
                    pass
            except OSError:
                pass

    async def check() -> None:
        async with connected(face.url) as c:
            assert await node(c, "cpu1/State").read_value() == "RUN"

    run(check())


def test_a_chunk_larger_than_the_server_receives_ends_its_connection_at_its_header(
    face: FaceRig,
) -> None:
    """A header claiming a chunk of 4 GiB ends that connection with
    ``BadTcpMessageTooLarge`` before its body: asyncua buffered all a client sent behind
    it, copying the buffer on every read — other clients waited, memory grew."""
    where = urlparse(face.url)
    for header in (
        b"MSGF" + struct.pack("<II", 0xFFFF_FFF0, 1),
        b"HELF" + struct.pack("<I", 0xFFFF_FFF0),
    ):
        with socket.create_connection((where.hostname, where.port), timeout=5) as s:
            s.sendall(header + b"\0" * 100_000)  # the body a chunk that large would have
            s.settimeout(5)
            got, start = b"", time.monotonic()
            try:
                while chunk := s.recv(65536):
                    got += chunk
            except OSError:
                pass
            assert time.monotonic() - start < 4, "the connection was kept open"
            assert got[:4] == b"ERRF", got[:40]
            (code,) = struct.unpack_from("<I", got, 8)
            assert code == ua.StatusCodes.BadTcpMessageTooLarge

    async def check() -> None:
        async with connected(face.url) as c:
            assert await node(c, "cpu1/State").read_value() == "RUN"

    run(check())
