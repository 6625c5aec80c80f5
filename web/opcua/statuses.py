"""OPC UA Part 4's status codes for node ids the face has not, where asyncua answers
others (docs/opcua.md, "Limits"): a well-formed node id of no node is
``BadNodeIdUnknown`` — asyncua's Browse, TranslateBrowsePathsToNodeIds and Call said
``BadNodeIdInvalid``, which is for a node id that is no node id at all (the null one) or,
in a call, an object that is no object; a call's method id that names no method is
``BadMethodInvalid`` (asyncua: ``BadNodeIdInvalid``, or ``BadNothingToDo`` for a
variable), a method the server has no implementation of ``BadNotImplemented``; an event
subscription of no node ``BadNodeIdUnknown`` (asyncua: ``BadServiceUnsupported``).
:class:`web.opcua.sessions.FaceSession` answers so before (or after) asyncua serves.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Final

from asyncua import ua
from asyncua.server.address_space import AddressSpace

from s7graph.web.opcua.typed import AttributeIds, ObjectIds, StatusCodes, ua_id, ua_status

__all__ = [
    "call_problem",
    "fix_browse",
    "fix_translate",
    "is_condition",
    "missing",
    "node_class",
]

_CALLABLE: Final = (ua.NodeClass.Object, ua.NodeClass.ObjectType)
"""What a Call's object may be (Part 4, "Call": anything else is ``BadNodeIdInvalid``)."""


def node_class(aspace: AddressSpace, nid: ua.NodeId) -> ua.NodeClass | None:
    """The class of node ``nid`` (None: no such node)."""
    node = aspace.get(nid)
    if node is None:
        return None
    held = node.attributes.get(AttributeIds.NodeClass)
    value = held.value.Value.Value if held is not None and held.value and held.value.Value else 0
    try:
        return ua.NodeClass(value)
    except ValueError:
        return ua.NodeClass.Unspecified


def is_condition(aspace: AddressSpace, nid: ua.NodeId) -> bool:
    """Whether ``nid`` is a condition of the face: of type ``AlarmConditionType``."""
    node = aspace.get(nid)
    if node is None:
        return False
    has_type = ua_id(ObjectIds.HasTypeDefinition)
    alarm = ua_id(ObjectIds.AlarmConditionType)
    return any(
        r.IsForward and r.ReferenceTypeId == has_type and r.NodeId == alarm for r in node.references
    )


def missing(aspace: AddressSpace, nid: object) -> int | None:
    """Why ``nid`` names no node (None: it does): ``BadNodeIdInvalid`` for the null node
    id or no node id, ``BadNodeIdUnknown`` for a well-formed one of no node."""
    if not isinstance(nid, ua.NodeId) or nid.is_null():
        return StatusCodes.BadNodeIdInvalid
    return None if nid in aspace else StatusCodes.BadNodeIdUnknown


def call_problem(aspace: AddressSpace, request: ua.CallMethodRequest) -> int | None:
    """Why a call is refused before any method runs (None: asyncua runs it)."""
    problem = missing(aspace, request.ObjectId)
    if problem is not None:
        return problem
    if node_class(aspace, request.ObjectId) not in _CALLABLE:
        return StatusCodes.BadNodeIdInvalid
    method = request.MethodId
    if not isinstance(method, ua.NodeId) or node_class(aspace, method) is not ua.NodeClass.Method:
        return StatusCodes.BadMethodInvalid
    node = aspace.get(method)
    if node is None or node.call is None:
        return StatusCodes.BadNotImplemented
    return None


def fix_browse(
    aspace: AddressSpace,
    asked: Sequence[ua.BrowseDescription],
    results: Sequence[ua.BrowseResult],
) -> None:
    """The results of a Browse, a node id of no node ``BadNodeIdUnknown``."""
    for description, result in zip(asked, results, strict=False):
        if result.StatusCode.value == StatusCodes.BadNodeIdInvalid:
            code = missing(aspace, description.NodeId) or StatusCodes.BadNodeIdInvalid
            result.StatusCode = ua_status(code)


def fix_translate(
    aspace: AddressSpace, paths: Sequence[ua.BrowsePath], results: Sequence[ua.BrowsePathResult]
) -> None:
    """The results of a TranslateBrowsePathsToNodeIds, a starting node id of no node
    ``BadNodeIdUnknown``."""
    for path, result in zip(paths, results, strict=False):
        if result.StatusCode.value == StatusCodes.BadNodeIdInvalid:
            code = missing(aspace, path.StartingNode) or StatusCodes.BadNodeIdInvalid
            result.StatusCode = ua_status(code)
