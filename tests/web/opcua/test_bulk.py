"""The face's nodes added in bulk straight into the address space (``web.opcua.bulk``) are
the nodes asyncua's ``AddNodes`` makes of the same requests: the same attributes with
the same values and types, the same references both ways, variables waiting for their
first value — and a request ``AddNodes`` refuses is refused, naming the node; nodes
deleted in bulk leave what ``DeleteNodes`` leaves (docs/opcua.md, "How fast")."""

from __future__ import annotations

import asyncio
from typing import Any

import pytest
from asyncua import Server, ua

from s7graph.web.opcua.conditions import add_condition
from s7graph.web.opcua.model import MS, TEXT, UaType, node_id
from s7graph.web.opcua.nodes import Nodes
from s7graph.web.opcua.typed import ObjectIds, StatusCodes, ua_id

DURATION = UaType(ua.VariantType.Double, "float", unit=MS, node=ObjectIds.Duration)


def _batch(nodes: Nodes) -> None:
    """A CPU, a folder, a variable with its engineering units, a writable one, an array,
    a method with its arguments and a condition (with its reference to Acknowledge)."""
    root = node_id(2, "cpu1")
    nodes.obj(ua_id(ObjectIds.ObjectsFolder), root, "cpu1", ref=ObjectIds.Organizes, notifier=True)
    nodes.folder(root, node_id(2, "cpu1", "Symbols"), "Symbols", "the operands")
    nodes.var(root, node_id(2, "cpu1", "T"), "T", DURATION, description="the step time")
    nodes.var(root, node_id(2, "cpu1", "Mode"), "Mode", TEXT, writable=True)
    nodes.var(root, node_id(2, "cpu1", "Active"), "Active", TEXT, array=True)
    argument = ua.Argument(Name="step", DataType=ua_id(ObjectIds.UInt16), ValueRank=-1)

    async def call(parent: ua.NodeId, *inputs: Any) -> None:
        return None

    nodes.method(
        root,
        node_id(2, "cpu1", "StepOn"),
        "StepOn",
        call,
        description="activate a step",
        inputs=[argument],
        outputs=[],
    )
    cond = node_id(2, "cpu1", "Supervision")
    nodes.root(cond)
    add_condition(nodes, root, cond, "Supervision", display="S2 Supervision", severity=700)
    nodes.end_root()
    nodes.reference(root, cond, ObjectIds.HasCondition)


async def _space(bulk: bool, delete: bool = False) -> dict[ua.NodeId, Any]:
    server = Server()
    await server.init()
    assert await server.register_namespace("urn:s7graph:plc") == 2
    nodes = Nodes(server, 2)
    _batch(nodes)
    if not bulk:  # the same requests through asyncua's AddNodes, as the face made them
        session = server.iserver.isession
        items, nodes._items = nodes._items, []
        for result in await session.add_nodes(items):
            assert result.StatusCode.is_good()
        initial = ua.DataValue(StatusCode=ua.StatusCode(StatusCodes.BadWaitingForInitialData))
        for nid in nodes._waiting:
            await server.write_attribute_value(nid, initial)
        nodes._waiting = []
    await nodes.flush()
    aspace = server.iserver.aspace
    if delete:  # the condition, a monitored item on its Retain told it went
        told: list[object] = []
        retain = node_id(2, "cpu1", "Supervision", "Retain")
        aspace.add_datachange_callback(retain, ua.AttributeIds.Value, lambda *a: told.append(a[2]))
        cond = node_id(2, "cpu1", "Supervision")
        if bulk:
            await nodes.delete(cond)
        else:
            items = [ua.DeleteNodesItem(nid, True) for nid in reversed(nodes.under.pop(cond))]
            await server.iserver.isession.delete_nodes(ua.DeleteNodesParameters(items))
        assert cond not in aspace and retain not in aspace
        assert told == [ua.StatusCode(ua.StatusCodes.BadNodeIdUnknown)]
    nids = aspace.keys()  # asyncua's address space: no iteration of its own
    mine = [nid for nid in nids if nid.NamespaceIndex == 2]
    return {nid: _shown(aspace[nid]) for nid in [*mine, ua_id(ObjectIds.ObjectsFolder)]}


def _shown(node: Any) -> tuple[object, ...]:
    """A node as a client reads and browses it (a value's timestamps: whether it has them)."""
    attributes = {}
    for attr, held in node.attributes.items():
        dv = held.value
        stamped = (dv.SourceTimestamp is not None, dv.ServerTimestamp is not None)
        attributes[attr] = (dv.Value, dv.StatusCode, stamped)
    refs = sorted(
        (
            r.ReferenceTypeId.to_string(),
            r.IsForward,
            r.NodeId.to_string(),
            r.BrowseName.to_string(),
            r.DisplayName.Text,
            r.NodeClass,
            r.TypeDefinition.to_string(),
        )
        for r in node.references
    )
    return attributes, refs


def test_nodes_added_in_bulk_are_those_asyncuas_add_nodes_makes() -> None:
    bulk, asyncua_made = asyncio.run(_space(True)), asyncio.run(_space(False))
    assert set(bulk) == set(asyncua_made)
    assert len(bulk) > 20
    for nid, shown in asyncua_made.items():
        assert bulk[nid] == shown, nid.to_string()


def test_nodes_deleted_in_bulk_leave_what_asyncuas_delete_nodes_leaves() -> None:
    bulk, asyncua_left = asyncio.run(_space(True, True)), asyncio.run(_space(False, True))
    assert set(bulk) == set(asyncua_left)
    for nid, shown in asyncua_left.items():
        assert bulk[nid] == shown, nid.to_string()
    refs = bulk[node_id(2, "cpu1")][1]
    assert not [r for r in refs if "Supervision" in r[2]]  # no reference to it is left


def test_a_node_asyncua_would_refuse_is_refused_in_bulk_naming_it() -> None:
    async def twice() -> None:
        server = Server()
        await server.init()
        await server.register_namespace("urn:s7graph:plc")
        nodes = Nodes(server, 2)
        objects = ua_id(ObjectIds.ObjectsFolder)
        nodes.obj(objects, node_id(2, "cpu1"), "cpu1")
        await nodes.flush()
        nodes.obj(objects, node_id(2, "cpu1"), "cpu1")  # taken
        with pytest.raises(RuntimeError, match="cpu1 refused: BadNodeIdExists"):
            await nodes.flush()
        nodes.obj(node_id(2, "nowhere"), node_id(2, "lost"), "lost")
        with pytest.raises(RuntimeError, match="lost refused: BadParentNodeIdInvalid"):
            await nodes.flush()

    asyncio.run(twice())
