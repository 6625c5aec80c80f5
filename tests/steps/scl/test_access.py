"""A DB variable by name (``steps/scl/access.py``): the name's parts, the member's type and
place — keys into an instance, byte and bit in a global DB laid out as S7 lays it out — and
values as JSON holds them."""

from __future__ import annotations

from datetime import date

import pytest

from s7graph.steps.scl import types as ty
from s7graph.steps.scl.access import MAX_STEPS, member, parse_name, plain, read_bytes
from tests.steps.scl.helpers import build

DB = """
DATA_BLOCK DB20
STRUCT
  on : BOOL; ready : BOOL; avg : REAL;
  flags : ARRAY[0..9] OF BOOL;
  grid : ARRAY[1..2, 1..3] OF INT;
  motor : ARRAY[1..3] OF STRUCT run : BOOL; speed : INT; END_STRUCT;
END_STRUCT
BEGIN avg := 2.5; grid[2, 3] := -4; motor[3].speed := 9; flags[9] := TRUE;
END_DATA_BLOCK
"""


@pytest.mark.parametrize(
    ("text", "parsed"),
    [
        ("DB20.avg", (20, ("avg",))),
        ("db3.motor[2].on", (3, ("motor", (2,), "on"))),
        ('"Oven".temp', ("Oven", ("temp",))),
        ("DB20.grid[2, 3]", (20, ("grid", (2, 3)))),
        ("DB20.DBW2x", (20, ("DBW2x",))),
        ("MW0", None),
        ("Start", None),
    ],
)
def test_a_name_splits_into_its_db_and_its_path(text: str, parsed: object) -> None:
    assert parse_name(text) == parsed


@pytest.mark.parametrize(
    "text",
    ["DB20.", "DB20.1x", "DB20.a[", "DB20.a[1", "DB20.a]", "DB20.a..b", "DB20.a[1e3]"],
)
def test_a_name_that_does_not_parse_is_a_value_error_naming_it(text: str) -> None:
    with pytest.raises(ValueError, match="DB20"):
        parse_name(text)


def test_a_name_deeper_than_the_limit_is_refused_not_walked() -> None:
    assert parse_name("DB1.a" + ".b" * (MAX_STEPS - 1)) is not None
    with pytest.raises(ValueError, match="too deep"):
        parse_name("DB1.a" + ".b" * MAX_STEPS)
    with pytest.raises(ValueError):
        parse_name("DB1.a" + "[1]" * 100_000)


def test_members_of_a_global_db_read_where_s7_lays_them_out() -> None:
    program = build(DB)
    t = program.types["DB20"]
    block = program.block("DB20")
    buf = bytearray(block.init or b"")  # type: ignore[union-attr]

    def at(name: str) -> object:
        parsed = parse_name(name)
        assert parsed is not None
        m = member(t, parsed[1], {}, name)
        return m.byte, m.bit, read_bytes(buf, m)

    assert at("DB20.ready") == (0, 1, False)
    assert at("DB20.avg") == (2, 0, 2.5)
    assert at("DB20.flags[9]") == (7, 1, True)  # bits from byte 6
    assert at("DB20.grid[2, 3]") == (8 + 5 * 2, 0, -4)
    assert at("DB20.motor[3]") == (20 + 2 * 4, 0, {"run": False, "speed": 9})


def test_an_instance_member_is_keyed_by_its_declared_name_and_flat_index() -> None:
    grid = ty.SclType("ARRAY", dims=((1, 2), (1, 3)), element=ty.INT)
    t = ty.SclType("STRUCT", fields=(("Grid", grid),))
    m = member(t, ("grid", (2, 1)), {}, "DB1.grid[2,1]")
    assert m.keys == ("Grid", 3) and m.type == ty.INT
    with pytest.raises(ValueError, match="takes 2 index"):
        member(t, ("grid", (2,)), {}, "DB1.grid[2]")


def test_values_as_json_holds_them() -> None:
    assert plain([1, {"a": date(2026, 1, 2)}, (True, 2.5)]) == [
        1,
        {"a": "2026-01-02"},
        [True, 2.5],
    ]
