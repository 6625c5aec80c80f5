"""What the address space is made of (``web.opcua.model``): node ids made of names, S7
types as OPC UA types with their units, bus values as variants and a client's values
back, refused when they do not fit."""

from __future__ import annotations

from datetime import UTC, datetime

import pytest
from asyncua import ua

from s7graph.web.opcua.model import eu_information, from_variant, node_id, to_variant, ua_type


def test_node_ids_are_the_path_of_names() -> None:
    assert node_id(2, "cpu1", "Seq_drill", "S3", "Active") == ua.NodeId(
        "cpu1/Seq_drill/S3/Active", 2
    )


@pytest.mark.parametrize(
    ("s7", "variant", "unit"),
    [
        ("BOOL", ua.VariantType.Boolean, None),
        ("BYTE", ua.VariantType.Byte, None),
        ("WORD", ua.VariantType.UInt16, None),
        ("DWORD", ua.VariantType.UInt32, None),
        ("INT", ua.VariantType.Int16, None),
        ("DINT", ua.VariantType.Int32, None),
        ("REAL", ua.VariantType.Float, None),
        ("TIME", ua.VariantType.Int32, "ms"),
        ("S5TIME", ua.VariantType.UInt32, "ms"),
        ("TIME_OF_DAY", ua.VariantType.UInt32, "ms"),
        ("DATE_AND_TIME", ua.VariantType.DateTime, None),
        ("STRING[20]", ua.VariantType.String, None),
        ("TIMER", ua.VariantType.Boolean, None),
        ("ARRAY[1..3] OF INT", ua.VariantType.String, None),
    ],
)
def test_s7_types_are_opcua_types(s7: str, variant: ua.VariantType, unit: str | None) -> None:
    t = ua_type(s7)
    assert t.variant == variant and t.data_type == ua.NodeId(variant.value)
    assert (t.unit[1] if t.unit else None) == unit


def test_the_unit_of_a_millisecond_is_uneces() -> None:
    eu = eu_information(("C26", "ms", "millisecond"))
    assert eu.UnitId == (ord("C") << 16) | (ord("2") << 8) | ord("6")
    assert eu.NamespaceUri == "http://www.opcfoundation.org/UA/units/un/cefact"


def test_bus_values_become_variants_or_are_refused() -> None:
    assert to_variant(True, ua_type("BOOL")) == ua.Variant(True, ua.VariantType.Boolean)
    assert to_variant(-5, ua_type("INT")) == ua.Variant(-5, ua.VariantType.Int16)
    assert to_variant(2, ua_type("REAL")) == ua.Variant(2.0, ua.VariantType.Float)
    when = to_variant("2026-11-22T08:30:00", ua_type("DT")).Value
    assert when == datetime(2026, 11, 22, 8, 30, tzinfo=UTC)
    for value, s7 in ((70000, "INT"), (None, "INT"), ("x", "INT"), (True, "INT"), ("x", "REAL")):
        with pytest.raises(ValueError):
            to_variant(value, ua_type(s7))


def test_a_clients_value_must_fit_the_node() -> None:
    assert from_variant(ua.Variant(5, ua.VariantType.Int32), ua_type("INT")) == 5
    assert from_variant(ua.Variant(True), ua_type("BOOL")) is True
    assert from_variant(ua.Variant(1.5, ua.VariantType.Double), ua_type("REAL")) == 1.5
    with pytest.raises(TypeError):
        from_variant(ua.Variant(1.5), ua_type("INT"))
    with pytest.raises(TypeError):
        from_variant(ua.Variant(1), ua_type("BOOL"))
    with pytest.raises(ValueError):
        from_variant(ua.Variant(40000, ua.VariantType.Int32), ua_type("INT"))
    with pytest.raises(ValueError):
        from_variant(ua.Variant(float("nan")), ua_type("REAL"))
