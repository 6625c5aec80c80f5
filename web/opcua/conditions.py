"""The state of a condition node, for a client that browses and reads it (docs/opcua.md,
"Alarms and conditions").

Each ``AlarmConditionType`` node of the face (``web.opcua.alarms``) has, as OPC UA Part 9
gives a condition, the children that say its state: ``EnabledState``, ``ActiveState``
and ``AckedState`` (``TwoStateVariableType`` variables, each with its ``Id``),
``ConditionName``, ``Retain``, ``Severity``, ``Message`` and ``Time``, and the
``ConditionVariableType`` variables ``LastSeverity`` and ``Comment``, each with its
``SourceTimestamp`` (Part 9, "ConditionVariableType": when its value last changed, the
source timestamp a read of it returns too). They are read only and hold what the
condition's last event said: :func:`show` writes them each time that event goes out
(before it goes, so a client reading on an event reads that event's state). A condition
that has sent no event yet is enabled, inactive and acknowledged, retains nothing, has
no ``Time``, no ``Comment`` and a ``LastSeverity`` of 0 (a condition's severity is its
kind's and never changes, so 0 it stays: Part 9, "ConditionType"). While the CPU is off
the bus the children written so far keep their last value with
``UncertainNoCommunicationLastUsableValue``, as every value of the face; they are written
again when it is back.

The condition has the standard ``Acknowledge`` method (``i=9111``, Part 9,
"AcknowledgeableConditionType") as its component: a client that browses a condition finds
it there, with its ``EventId`` and ``Comment`` arguments, and calls it with the condition
as the object. The reference is forward only: the method's node would otherwise list
every condition of the face.

A face started again knows no comment of its own: :func:`acked_comments` reads the last
one of each message back from the CPU's audit rows (``audit/acked``: each message's newest
applied ``ack_msg`` with a comment, however old; from a CPU before it, ``audit/list``'s
last 50) — from whatever client, the row on the bus does not say — its text without a
locale (the row keeps none), stamped with the row's time; none when that comment emptied
it.
"""

from __future__ import annotations

import json
from collections.abc import Iterable
from datetime import UTC, datetime
from typing import Any, Final

from asyncua import ua

from s7graph.web.bus.protocol import AuditEntry
from s7graph.web.opcua.nodes import Nodes
from s7graph.web.opcua.typed import ObjectIds, child_id, ua_id

__all__ = [
    "STAMPED",
    "STATES",
    "acked_comment",
    "acked_comments",
    "add_condition",
    "event_values",
    "initial_values",
    "show",
]

STATES: Final = ("EnabledState", "ActiveState", "AckedState")
"""The condition's ``TwoStateVariableType`` children; each has an ``Id`` property."""
_PROPERTIES: Final = {
    "ConditionName": ObjectIds.String,
    "Retain": ObjectIds.Boolean,
    "Severity": ObjectIds.UInt16,
    "Message": ObjectIds.LocalizedText,
    "Time": ObjectIds.UtcTime,
}
"""The condition's properties and their data types."""
STAMPED: Final = {"LastSeverity": ObjectIds.UInt16, "Comment": ObjectIds.LocalizedText}
"""The condition's ``ConditionVariableType`` children and their data types; each has a
``SourceTimestamp`` property."""
_NO_TIME: Final = ua.Variant(None, ua.VariantType.Null)


def acked_comment(row: AuditEntry) -> tuple[str, str, datetime] | None:
    """Of an applied ``ack_msg`` row that gave a comment: its message id (as text), the
    comment ("": emptied) and when; None for any other row, or one whose arguments are
    not recognised."""
    if row.op != "ack_msg" or row.outcome != "applied":
        return None
    try:
        args = json.loads(row.args)
    except ValueError:
        return None
    comment = args.get("comment") if isinstance(args, dict) else None
    if not isinstance(comment, str) or "msg_id" not in args:
        return None
    return str(args["msg_id"]), comment, datetime.fromtimestamp(row.t_ms / 1000, UTC)


def acked_comments(rows: Iterable[AuditEntry]) -> dict[str, tuple[ua.LocalizedText, datetime]]:
    """Per message id (as text): the comment of its newest applied acknowledgement that
    gave one, and when — none when that one emptied it (``""``). ``rows`` oldest first;
    a row whose arguments are not recognised is passed over."""
    comments: dict[str, tuple[ua.LocalizedText, datetime]] = {}
    for row in rows:
        given = acked_comment(row)
        if given is None:
            continue
        key, comment, when = given
        if comment:
            comments[key] = (ua.LocalizedText(comment), when)
        else:  # emptied
            comments.pop(key, None)
    return comments


def _text(text: str) -> ua.Variant:
    return ua.Variant(ua.LocalizedText(text), ua.VariantType.LocalizedText)


def _flag(on: bool) -> ua.Variant:
    return ua.Variant(bool(on), ua.VariantType.Boolean)


def _time(when: Any) -> ua.Variant:
    return ua.Variant(when, ua.VariantType.DateTime) if when is not None else _NO_TIME


def initial_values(name: str, message: str, severity: int) -> dict[str, ua.Variant]:
    """A condition's children before its first event, by their path under it."""
    return {
        "ConditionName": ua.Variant(name, ua.VariantType.String),
        "EnabledState": _text("Enabled"),
        "EnabledState/Id": _flag(True),
        "ActiveState": _text("Inactive"),
        "ActiveState/Id": _flag(False),
        "AckedState": _text("Acknowledged"),
        "AckedState/Id": _flag(True),
        "Retain": _flag(False),
        "Severity": ua.Variant(severity, ua.VariantType.UInt16),
        "Message": _text(message),
        "Time": _NO_TIME,
        "LastSeverity": ua.Variant(0, ua.VariantType.UInt16),
        "LastSeverity/SourceTimestamp": _NO_TIME,
        "Comment": ua.Variant(None, ua.VariantType.Null),
        "Comment/SourceTimestamp": _NO_TIME,
    }


def event_values(event: Any) -> dict[str, ua.Variant]:
    """What the condition event ``event`` (asyncua's ``AlarmCondition``) says, as the
    condition's children, by their path under it."""
    values: dict[str, ua.Variant] = {}
    for state in STATES:
        shown = getattr(event, state)
        text = shown.Text if isinstance(shown, ua.LocalizedText) else str(shown or "")
        values[state] = _text(text or "")
        values[f"{state}/Id"] = _flag(bool(getattr(event, f"{state}/Id")))
    message, comment = event.Message, event.Comment
    values["ConditionName"] = ua.Variant(str(event.ConditionName or ""), ua.VariantType.String)
    values["Retain"] = _flag(bool(event.Retain))
    values["Severity"] = ua.Variant(int(event.Severity), ua.VariantType.UInt16)
    values["Message"] = _text((message.Text or "") if isinstance(message, ua.LocalizedText) else "")
    values["Time"] = ua.Variant(event.Time, ua.VariantType.DateTime)
    values["LastSeverity"] = ua.Variant(int(event.LastSeverity or 0), ua.VariantType.UInt16)
    values["LastSeverity/SourceTimestamp"] = _time(getattr(event, "LastSeverity/SourceTimestamp"))
    values["Comment"] = (
        _text_of(comment) if isinstance(comment, ua.LocalizedText) else ua.Variant(None)
    )
    values["Comment/SourceTimestamp"] = _time(getattr(event, "Comment/SourceTimestamp"))
    return values


def _text_of(text: ua.LocalizedText) -> ua.Variant:
    return ua.Variant(text, ua.VariantType.LocalizedText)


def add_condition(
    nodes: Nodes,
    parent: ua.NodeId,
    nid: ua.NodeId,
    name: str,
    *,
    display: str,
    description: str = "",
    severity: int,
    condition: str = "",
) -> ua.NodeId:
    """Batch condition ``nid`` (browse name ``name``) under ``parent``, with its state
    children as :func:`initial_values` (its ``ConditionName`` ``condition`` or ``name``,
    its ``Message`` the description or display) and the standard ``Acknowledge`` as its
    component."""
    nodes.obj(
        parent,
        nid,
        name,
        display=display,
        description=description,
        type_def=ObjectIds.AlarmConditionType,
    )
    values = initial_values(condition or name, description or display, severity)
    for state in STATES:
        node = nodes.prop(
            nid,
            state,
            values[state],
            ObjectIds.LocalizedText,
            type_def=ObjectIds.TwoStateVariableType,
        )
        nodes.prop(node, "Id", values[f"{state}/Id"], ObjectIds.Boolean)
    for prop, data_type in _PROPERTIES.items():
        nodes.prop(nid, prop, values[prop], data_type)
    for var, data_type in STAMPED.items():
        node = nodes.prop(
            nid, var, values[var], data_type, type_def=ObjectIds.ConditionVariableType
        )
        stamp = values[f"{var}/SourceTimestamp"]
        nodes.prop(node, "SourceTimestamp", stamp, ObjectIds.UtcTime)
    ack = ua_id(ObjectIds.AcknowledgeableConditionType_Acknowledge)
    nodes.reference(
        nid, ack, ObjectIds.HasComponent, target_class=ua.NodeClass.Method, inverse=False
    )
    return nid


async def show(nodes: Nodes, nid: ua.NodeId, values: dict[str, ua.Variant]) -> None:
    """Write ``values`` (by path) into the children of condition ``nid``, through ``nodes``
    (``Nodes.set``: a CPU that leaves the bus marks them, as every value written, with its
    last usable value, ``Space.set_online``); a ``ConditionVariableType`` child with the
    source timestamp its ``SourceTimestamp`` says, once it has one."""
    now = datetime.now(UTC)
    for path, value in values.items():
        child = nid
        for part in path.split("/"):
            child = child_id(child, part)
        stamp = values.get(f"{path}/SourceTimestamp") if path in STAMPED else None
        when = stamp.Value if stamp is not None and stamp.Value is not None else now
        await nodes.set(child, value, when=when)
