"""What the OPC UA face's address space is made of, without a server: the namespace and
the node ids (stable across restarts: made from the CPU's, the FB's and the operands'
names and the step numbers), S7 types as OPC UA types, bus values as variants and back,
and engineering units (docs/opcua.md, "The address space").

A node id is a string in the face's one namespace (``NAMESPACE_URI``, index 2 on every
start): the path of names from the CPU down, joined by ``/`` — ``cpu1``,
``cpu1/Seq_drill/S3/Active``, ``cpu1/Symbols/Start_button``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from datetime import UTC, datetime
from typing import Final

from asyncua import ua

from s7graph.web.opcua.typed import ua_id

__all__ = [
    "FLOAT_VARIANTS",
    "INT_VARIANTS",
    "MS",
    "NAMESPACE_URI",
    "PERCENT",
    "Kind",
    "UaType",
    "eu_information",
    "from_variant",
    "node_id",
    "to_variant",
    "ua_type",
]

NAMESPACE_URI: Final = "urn:s7graph:plc"
"""The namespace of every node the face adds (the same on every start)."""
UNITS_URI: Final = "http://www.opcfoundation.org/UA/units/un/cefact"
MS: Final = ("C26", "ms", "millisecond")
"""The engineering unit of times: UNECE code, display name, description."""
PERCENT: Final = ("P1", "%", "percent")


def node_id(ns: int, *parts: str) -> ua.NodeId:
    """The node id of the path ``parts`` (``"cpu1", "Seq_drill", "S3"``) in namespace
    ``ns``."""
    return ua_id("/".join(parts), ns)


def eu_information(unit: tuple[str, str, str]) -> ua.EUInformation:
    """An ``EngineeringUnits`` value of a UNECE unit (OPC UA Part 8, ``EUInformation``:
    the unit id is the code's characters, each a byte)."""
    code, shown, description = unit
    unit_id = 0
    for char in code:
        unit_id = (unit_id << 8) | ord(char)
    return ua.EUInformation(
        NamespaceUri=UNITS_URI,
        UnitId=unit_id,
        DisplayName=ua.LocalizedText(shown),
        Description=ua.LocalizedText(description),
    )


Kind = str
"""How a value converts: ``bool``, ``int``, ``float``, ``text``, ``time`` (a date and time)."""


@dataclass(frozen=True, slots=True)
class UaType:
    """An S7 type as OPC UA sees it: the variant, its data type node, how a bus value
    converts (``kind``), the range of an integer, the unit (None: none); ``node``: a data
    type more precise than the variant's (Duration, a Double of ms), 0: the variant's."""

    variant: ua.VariantType
    kind: Kind
    lo: int = 0
    hi: int = 0
    unit: tuple[str, str, str] | None = None
    node: int = 0

    @property
    def data_type(self) -> ua.NodeId:
        return ua_id(self.node or self.variant.value)


def _int(
    variant: ua.VariantType, lo: int, hi: int, unit: tuple[str, str, str] | None = None
) -> UaType:
    return UaType(variant, "int", lo, hi, unit)


BOOLEAN: Final = UaType(ua.VariantType.Boolean, "bool")
TEXT: Final = UaType(ua.VariantType.String, "text")
DOUBLE: Final = UaType(ua.VariantType.Double, "float")
_TYPES: Final[dict[str, UaType]] = {
    "BOOL": BOOLEAN,
    "TIMER": BOOLEAN,  # a timer or counter reads as its Q bit
    "COUNTER": BOOLEAN,
    "BYTE": _int(ua.VariantType.Byte, 0, 0xFF),
    "WORD": _int(ua.VariantType.UInt16, 0, 0xFFFF),
    "DWORD": _int(ua.VariantType.UInt32, 0, 0xFFFF_FFFF),
    "INT": _int(ua.VariantType.Int16, -(2**15), 2**15 - 1),
    "DINT": _int(ua.VariantType.Int32, -(2**31), 2**31 - 1),
    "TIME": _int(ua.VariantType.Int32, -(2**31), 2**31 - 1, MS),
    "S5TIME": _int(ua.VariantType.UInt32, 0, 0xFFFF_FFFF, MS),
    "TIME_OF_DAY": _int(ua.VariantType.UInt32, 0, 0xFFFF_FFFF, MS),
    "TOD": _int(ua.VariantType.UInt32, 0, 0xFFFF_FFFF, MS),
    "REAL": UaType(ua.VariantType.Float, "float"),
    "LREAL": DOUBLE,
    "CHAR": TEXT,
    "DATE": TEXT,  # ISO text: 2026-11-22
    "DATE_AND_TIME": UaType(ua.VariantType.DateTime, "time"),
    "DT": UaType(ua.VariantType.DateTime, "time"),
}
INT_VARIANTS: Final = frozenset(  # the integer variants a value may arrive in
    {
        ua.VariantType.SByte,
        ua.VariantType.Byte,
        ua.VariantType.Int16,
        ua.VariantType.UInt16,
        ua.VariantType.Int32,
        ua.VariantType.UInt32,
        ua.VariantType.Int64,
        ua.VariantType.UInt64,
    }
)
FLOAT_VARIANTS: Final = frozenset({ua.VariantType.Float, ua.VariantType.Double})


def ua_type(s7_type: str) -> UaType:
    """The OPC UA type of an S7 type name (``INT``, ``STRING[20]``, ``TIME``); an
    unknown one (a STRUCT, an ARRAY) as text."""
    name = "".join(s7_type.split()).upper()
    return _TYPES.get(name, TEXT)


def to_variant(value: object, t: UaType) -> ua.Variant:
    """A bus value (JSON: bool, int, float, text) as a variant of ``t``; ``ValueError``
    when it does not fit (the node gets a bad status instead)."""
    if value is None:
        raise ValueError("no value")
    kind = t.kind
    if kind == "bool":
        if not isinstance(value, bool | int) or isinstance(value, float):
            raise ValueError(f"not a BOOL: {value!r}")
        return ua.Variant(bool(value), t.variant)
    if kind == "int":
        if isinstance(value, bool) or not isinstance(value, int) or not t.lo <= value <= t.hi:
            raise ValueError(f"out of range: {value!r}")
        return ua.Variant(value, t.variant)
    if kind == "float":
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise ValueError(f"not a number: {value!r}")
        return ua.Variant(float(value), t.variant)
    if kind == "time":
        when = datetime.fromisoformat(str(value))
        return ua.Variant(when if when.tzinfo else when.replace(tzinfo=UTC), t.variant)
    return ua.Variant(str(value), ua.VariantType.String)


def from_variant(variant: ua.Variant, t: UaType) -> bool | int | float | str:
    """A value written by an OPC UA client, as the bus takes it (a force job's value);
    ``TypeError`` when its type is not the node's (integers of any width for an integer,
    a Float or Double for a real), ``ValueError`` when it is out of range."""
    value, vt, kind = variant.Value, variant.VariantType, t.kind
    if kind == "bool" and vt is ua.VariantType.Boolean and isinstance(value, bool):
        return value
    if kind == "int" and vt in INT_VARIANTS and isinstance(value, int):
        if not t.lo <= value <= t.hi:
            raise ValueError(f"{value} is out of range {t.lo}..{t.hi}")
        return value
    if kind == "float" and vt in FLOAT_VARIANTS and isinstance(value, float):
        if not math.isfinite(value):
            raise ValueError("not a finite number")
        return value
    if kind == "text" and vt is ua.VariantType.String and isinstance(value, str):
        return value
    raise TypeError(f"a {vt.name} does not fit a {t.variant.name}")
