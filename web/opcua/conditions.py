"""The state of a condition node, for a client that browses and reads it (docs/opcua.md,
"Alarms and conditions").

Each ``AlarmConditionType`` node of the face (``web.opcua.alarms``) has, as OPC UA Part 9
gives a condition, the children that say its state: ``EnabledState``, ``ActiveState``
and ``AckedState`` (``TwoStateVariableType`` variables, each with its ``Id``),
``Retain``, ``Severity``, ``Message`` and ``Time``. They are read only and hold what the
condition's last event said: :func:`show` writes them each time that event goes out
(before it goes, so a client reading on an event reads that event's state). A condition
that has sent no event yet is enabled, inactive and acknowledged, retains nothing and has
no ``Time``. While the CPU is off the bus the children written so far keep their last value
with ``UncertainNoCommunicationLastUsableValue``, as every value of the face; they are
written again when it is back.
"""

from __future__ import annotations

from datetime import UTC, datetime
from typing import Any, Final

from asyncua import ua

from s7graph.web.opcua.nodes import Nodes
from s7graph.web.opcua.typed import ObjectIds, child_id

__all__ = ["STATES", "add_condition", "event_values", "initial_values", "show"]

STATES: Final = ("EnabledState", "ActiveState", "AckedState")
"""The condition's ``TwoStateVariableType`` children; each has an ``Id`` property."""
_PROPERTIES: Final = {
    "Retain": ObjectIds.Boolean,
    "Severity": ObjectIds.UInt16,
    "Message": ObjectIds.LocalizedText,
    "Time": ObjectIds.UtcTime,
}
"""The condition's properties and their data types."""


def _text(text: str) -> ua.Variant:
    return ua.Variant(ua.LocalizedText(text), ua.VariantType.LocalizedText)


def _flag(on: bool) -> ua.Variant:
    return ua.Variant(bool(on), ua.VariantType.Boolean)


def initial_values(message: str, severity: int) -> dict[str, ua.Variant]:
    """A condition's children before its first event, by their path under it."""
    return {
        "EnabledState": _text("Enabled"),
        "EnabledState/Id": _flag(True),
        "ActiveState": _text("Inactive"),
        "ActiveState/Id": _flag(False),
        "AckedState": _text("Acknowledged"),
        "AckedState/Id": _flag(True),
        "Retain": _flag(False),
        "Severity": ua.Variant(severity, ua.VariantType.UInt16),
        "Message": _text(message),
        "Time": ua.Variant(None, ua.VariantType.Null),
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
    message = event.Message
    values["Retain"] = _flag(bool(event.Retain))
    values["Severity"] = ua.Variant(int(event.Severity), ua.VariantType.UInt16)
    values["Message"] = _text((message.Text or "") if isinstance(message, ua.LocalizedText) else "")
    values["Time"] = ua.Variant(event.Time, ua.VariantType.DateTime)
    return values


def add_condition(
    nodes: Nodes,
    parent: ua.NodeId,
    nid: ua.NodeId,
    name: str,
    *,
    display: str,
    description: str = "",
    severity: int,
) -> ua.NodeId:
    """Batch condition ``nid`` (browse name ``name``) under ``parent``, with its state
    children as :func:`initial_values` (its ``Message`` the description or display)."""
    nodes.obj(
        parent,
        nid,
        name,
        display=display,
        description=description,
        type_def=ObjectIds.AlarmConditionType,
    )
    values = initial_values(description or display, severity)
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
    return nid


async def show(nodes: Nodes, nid: ua.NodeId, values: dict[str, ua.Variant]) -> None:
    """Write ``values`` (by path) into the children of condition ``nid``, through ``nodes``
    (``Nodes.set``: a CPU that leaves the bus marks them, as every value written, with its
    last usable value, ``Space.set_online``)."""
    now = datetime.now(UTC)
    for path, value in values.items():
        child = nid
        for part in path.split("/"):
            child = child_id(child, part)
        await nodes.set(child, value, when=now)
