"""asyncua as this package uses it, typed: its id tables imported from the modules that
define them, and constructors of node ids, status codes and data values that take plain
ints and datetimes (asyncua types its integers and times as ``NewType`` s, so a plain
``int`` is not an ``Int32`` to mypy) — the casts live here and nowhere else."""

from __future__ import annotations

from datetime import datetime
from typing import Any, cast

from asyncua import ua
from asyncua.server.server import Server
from asyncua.ua.attribute_ids import AttributeIds
from asyncua.ua.object_ids import ObjectIds
from asyncua.ua.status_codes import StatusCodes

__all__ = [
    "AttributeIds",
    "ObjectIds",
    "Server",
    "StatusCodes",
    "child_id",
    "data_value",
    "ua_id",
    "ua_status",
    "ua_uint",
]


def ua_id(ident: int | str, ns: int = 0) -> ua.NodeId:
    """The node id ``ident`` (a number: one of ``ObjectIds``; a string) in namespace ``ns``."""
    return ua.NodeId(cast(Any, ident), cast(Any, ns))


def child_id(parent: ua.NodeId, name: str) -> ua.NodeId:
    """The node id of ``parent``'s child ``name``: the parent's string, then ``/name``."""
    return ua_id(f"{cast(str, parent.Identifier)}/{name}", parent.NamespaceIndex)


def ua_uint(value: int) -> ua.UInt32:
    """``value`` as asyncua's ``UInt32``."""
    return cast(ua.UInt32, value)


def ua_status(code: int) -> ua.StatusCode:
    """The status code ``code`` (one of ``StatusCodes``)."""
    return ua.StatusCode(cast(Any, code))


def data_value(
    variant: ua.Variant | None = None, code: int = StatusCodes.Good, when: datetime | None = None
) -> ua.DataValue:
    """A value with its status code and source timestamp."""
    return ua.DataValue(
        variant if variant is not None else ua.Variant(None),
        StatusCode=ua_status(code),
        SourceTimestamp=cast(Any, when),
    )
