"""Adding and deleting the face's nodes in the address space in bulk (docs/opcua.md,
"How fast").

asyncua's ``AddNodes`` (``NodeManagementService._add_node``) checks every attribute of
the request's attribute mask by name, looks the parent's references through twice (a
property's browse name taken, a reference already there) and reads its parent's and its
type's attributes anew for each node: a chart's 1,000 supervised steps (a condition is
16 nodes) took seconds, the longer the more children a parent has.
:func:`insert` makes the same nodes — the same attributes, typed as asyncua types them,
the same references: from the parent and back, to the type definition — straight into
the address space, for nodes the face makes: new node ids under parents that exist
(anything else is refused as asyncua refuses it: :class:`Refused`); :func:`remove`
deletes them as ``DeleteNodes`` does. It mirrors asyncua 2.1.0 (pinned);
``tests/web/opcua/test_bulk.py`` holds it to what ``AddNodes`` and ``DeleteNodes`` do.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import dataclass
from datetime import UTC, datetime
from typing import Any, Final

from asyncua import ua
from asyncua.server.address_space import AddressSpace, AttributeValue, NodeData

from s7graph.web.opcua.typed import AttributeIds, ObjectIds, StatusCodes, ua_id

__all__ = ["Refused", "insert", "remove"]

_log = logging.getLogger("s7graph.web.opcua")

_ATTRIBUTES: Final = (
    ("AccessLevel", ua.VariantType.Byte, False),
    ("ArrayDimensions", ua.VariantType.UInt32, True),
    ("DataType", ua.VariantType.NodeId, False),
    ("Description", ua.VariantType.LocalizedText, False),
    ("DisplayName", ua.VariantType.LocalizedText, False),
    ("EventNotifier", ua.VariantType.Byte, False),
    ("Executable", ua.VariantType.Boolean, False),
    ("Historizing", ua.VariantType.Boolean, False),
    ("MinimumSamplingInterval", ua.VariantType.Double, False),
    ("UserAccessLevel", ua.VariantType.Byte, False),
    ("UserExecutable", ua.VariantType.Boolean, False),
    ("ValueRank", ua.VariantType.Int32, False),
    ("WriteMask", ua.VariantType.UInt32, False),
    ("UserWriteMask", ua.VariantType.UInt32, False),
)
"""The attributes of an object, a variable or a method that asyncua keeps when its mask
names them, with the variant type it gives each (``Value`` apart)."""
_CLASSES: Final = (ua.ObjectAttributes, ua.VariableAttributes, ua.MethodAttributes)
_HAS_TYPE: Final = ua_id(ObjectIds.HasTypeDefinition)


def _named(kind: type) -> tuple[tuple[AttributeIds, str, ua.VariantType, bool], ...]:
    mask = kind().SpecifiedAttributes
    return tuple(
        (getattr(AttributeIds, name), name, vtype, array)
        for name, vtype, array in _ATTRIBUTES
        if mask & getattr(ua.NodeAttributesMask, name)
    )


_KEPT: Final = {kind: _named(kind) for kind in _CLASSES}
"""Per attribute class, what asyncua keeps of it (its default mask: every one it has)."""


class Refused(Exception):
    """A node the address space cannot take as asked; ``status`` says why, as ``AddNodes``
    would."""

    def __init__(self, nid: ua.NodeId, status: int) -> None:
        self.status = status
        name = ua.StatusCode(status).name  # type: ignore[arg-type]
        super().__init__(f"node {nid.to_string()} refused: {name}")


@dataclass
class _Seen:
    """What the reference back to a node says of it: its class, names, type."""

    node_class: ua.NodeClass
    browse: ua.QualifiedName
    display: ua.LocalizedText
    type_def: ua.NodeId


def _seen(aspace: AddressSpace, nid: ua.NodeId) -> _Seen:
    node = aspace[nid]

    def value(attr: AttributeIds) -> Any:
        held = node.attributes.get(attr)
        dv = held.value if held is not None else None
        return dv.Value.Value if dv is not None and dv.Value is not None else None

    kind = ua.NodeClass(value(AttributeIds.NodeClass) or 0)
    type_def = ua.NodeId()
    if kind in (ua.NodeClass.Object, ua.NodeClass.Variable):
        type_def = next(
            (r.NodeId for r in node.references if r.IsForward and r.ReferenceTypeId == _HAS_TYPE),
            type_def,
        )
    return _Seen(
        kind,
        value(AttributeIds.BrowseName) or ua.QualifiedName(),
        value(AttributeIds.DisplayName) or ua.LocalizedText(),
        type_def,
    )


def _ref(
    ref: ua.NodeId, forward: bool, target: ua.NodeId, seen: _Seen, type_def: ua.NodeId
) -> ua.ReferenceDescription:
    return ua.ReferenceDescription(
        ReferenceTypeId=ref,
        IsForward=forward,
        NodeId=target,
        BrowseName=seen.browse,
        DisplayName=seen.display,
        NodeClass=seen.node_class,
        TypeDefinition=type_def,
    )


def insert(
    aspace: AddressSpace, items: Sequence[ua.AddNodesItem], waiting: frozenset[ua.NodeId]
) -> None:
    """Add ``items`` (in order: a parent before its children) to ``aspace`` as
    ``AddNodes`` would; a variable of ``waiting`` holds no value yet
    (``BadWaitingForInitialData``). :class:`Refused` at the first that cannot be added:
    its node id taken, its parent or type not there — those before it stay added."""
    values = _Values(datetime.now(UTC), aspace.force_server_timestamp)
    seen: dict[ua.NodeId, _Seen] = {}

    def known(nid: ua.NodeId) -> _Seen:
        found = seen.get(nid)
        if found is None:
            found = seen[nid] = _seen(aspace, nid)
        return found

    for item in items:
        nid: ua.NodeId = item.RequestedNewNodeId
        if nid.is_null() or nid in aspace:
            raise Refused(nid, StatusCodes.BadNodeIdExists)
        parent = aspace.get(item.ParentNodeId)
        if parent is None:
            raise Refused(nid, StatusCodes.BadParentNodeIdInvalid)
        type_def: ua.NodeId = item.TypeDefinition
        if not type_def.is_null() and type_def not in aspace:
            raise Refused(nid, StatusCodes.BadTypeDefinitionInvalid)
        node = NodeData(nid)
        _attributes(node, item, nid in waiting, values)
        aspace[nid] = node
        attrs = item.NodeAttributes
        mine = _Seen(item.NodeClass, item.BrowseName, attrs.DisplayName, type_def)
        seen[nid] = mine
        parent.references.append(_ref(item.ReferenceTypeId, True, nid, mine, type_def))
        up = known(item.ParentNodeId)
        node.references.append(
            _ref(item.ReferenceTypeId, False, item.ParentNodeId, up, up.type_def)
        )
        if not type_def.is_null():
            kind = known(type_def)
            node.references.append(_ref(_HAS_TYPE, True, type_def, kind, ua.NodeId()))


class _Values:
    """The attribute values of one :func:`insert`: one ``DataValue`` for each constant
    the nodes share (a write mask, an access level, a data type — asyncua replaces a
    value written, never changes it), a new one for each name."""

    def __init__(self, now: datetime, server_time: bool) -> None:
        self.now = now
        self.server_time = now if server_time else None
        self._shared: dict[tuple[object, ...], ua.DataValue] = {}
        waiting = ua.StatusCode(StatusCodes.BadWaitingForInitialData)  # type: ignore[arg-type]
        self.waiting = ua.DataValue(ua.Variant(None, ua.VariantType.Null), StatusCode=waiting)
        """A variable waiting for its first value, as writing that status leaves it: no
        value, no timestamps."""

    def of(self, value: object, vtype: ua.VariantType, array: bool = False) -> ua.DataValue:
        if array:
            if value:
                return ua.DataValue(ua.Variant(value, vtype, is_array=True))
            value = None if value is None else ()
        elif isinstance(value, ua.LocalizedText | ua.QualifiedName):
            return ua.DataValue(ua.Variant(value, vtype))
        key = (vtype, array, value)
        dv = self._shared.get(key)
        if dv is None:
            held = None if value is None else [] if array else value
            dv = self._shared[key] = ua.DataValue(ua.Variant(held, vtype, is_array=array))
        return dv

    def value(self, attrs: ua.VariableAttributes, waiting: bool) -> ua.DataValue:
        if waiting:
            return self.waiting
        return ua.DataValue(
            ua.Variant(attrs.Value),
            SourceTimestamp=self.now,  # type: ignore[arg-type]
            ServerTimestamp=self.server_time,  # type: ignore[arg-type]
        )


def _attributes(node: NodeData, item: ua.AddNodesItem, waiting: bool, values: _Values) -> None:
    held = node.attributes
    nid = ua.Variant(node.nodeid, ua.VariantType.NodeId)
    held[AttributeIds.NodeId] = AttributeValue(ua.DataValue(nid))
    held[AttributeIds.BrowseName] = AttributeValue(
        values.of(item.BrowseName, ua.VariantType.QualifiedName)
    )
    held[AttributeIds.NodeClass] = AttributeValue(values.of(item.NodeClass, ua.VariantType.Int32))
    attrs = item.NodeAttributes
    for attr, name, vtype, array in _KEPT[type(attrs)]:
        held[attr] = AttributeValue(values.of(getattr(attrs, name), vtype, array))
    if isinstance(attrs, ua.VariableAttributes):
        held[AttributeIds.Value] = AttributeValue(values.value(attrs, waiting))


def remove(aspace: AddressSpace, nids: Sequence[ua.NodeId]) -> None:
    """Delete ``nids`` from ``aspace`` as ``DeleteNodes`` with ``deleteTargetReferences``
    would — a monitored item of a value told ``BadNodeIdUnknown``, every reference to
    them gone — looking only at the nodes they refer to: every reference the face makes
    comes with its inverse but those to a type and to ``Acknowledge``, which hold none
    back. asyncua looked through every node of the address space for each node deleted
    (an online change of 10 steps of a 1,000-step chart: 21 s)."""
    gone = {nid for nid in nids if nid in aspace}
    around: set[ua.NodeId] = set()
    for nid in gone:
        around.update(ref.NodeId for ref in aspace[nid].references)
    for nid in around - gone:
        node = aspace.get(nid)
        if node is not None and any(ref.NodeId in gone for ref in node.references):
            node.references[:] = [ref for ref in node.references if ref.NodeId not in gone]
    unknown = ua.StatusCode(StatusCodes.BadNodeIdUnknown)  # type: ignore[arg-type]
    for nid in nids:
        if nid not in gone:
            continue
        value = aspace[nid].attributes.get(AttributeIds.Value)
        for handle, callback in list(value.datachange_callbacks.items()) if value else []:
            try:
                callback(handle, None, unknown)
                aspace.delete_datachange_callback(handle)
            except Exception as exc:  # one item's callback must not keep the node
                _log.warning("opcua: a monitored item of %s: %s", nid.to_string(), exc)
        del aspace[nid]
        gone.discard(nid)
