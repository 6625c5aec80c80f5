"""S7 address syntax (docs/runtime.md, "The block runtime", Siemens' Program Design for S7-300/400,
ch. 5)."""

from __future__ import annotations

import pytest

from s7graph.engine.address import Address, Area, Width, parse_address
from s7graph.engine.errors import AddressError, SourceLocation


@pytest.mark.parametrize(
    ("text", "area", "width", "byte", "bit", "db"),
    [
        ("I0.0", Area.I, Width.BIT, 0, 0, None),
        ("IB0", Area.I, Width.BYTE, 0, 0, None),
        ("IW2", Area.I, Width.WORD, 2, 0, None),
        ("ID4", Area.I, Width.DWORD, 4, 0, None),
        ("QX4.1", Area.Q, Width.BIT, 4, 1, None),
        ("MB10", Area.M, Width.BYTE, 10, 0, None),
        ("MW11", Area.M, Width.WORD, 11, 0, None),
        ("MD12", Area.M, Width.DWORD, 12, 0, None),
        ("LW4", Area.L, Width.WORD, 4, 0, None),
        ("T5", Area.T, Width.WORD, 5, 0, None),
        ("C3", Area.C, Width.WORD, 3, 0, None),
        ("DB1.DBX0.7", Area.DB, Width.BIT, 0, 7, 1),
        ("DB1.DBB2", Area.DB, Width.BYTE, 2, 0, 1),
        ("DB12.DBW2", Area.DB, Width.WORD, 2, 0, 12),
        ("DB1.DBD4", Area.DB, Width.DWORD, 4, 0, 1),
        ("PIW256", Area.PI, Width.WORD, 256, 0, None),
        ("PQB0", Area.PQ, Width.BYTE, 0, 0, None),
    ],
)
def test_english_addresses_parse_into_area_width_byte_bit(
    text: str, area: Area, width: Width, byte: int, bit: int, db: int | None
) -> None:
    assert parse_address(text) == Address(area, width, byte, bit, db)


@pytest.mark.parametrize(
    ("german", "english"),
    [
        ("E0.0", "I0.0"),
        ("EB0", "IB0"),
        ("AW4", "QW4"),
        ("A1.2", "Q1.2"),
        ("PEW256", "PIW256"),
        ("PAW8", "PQW8"),
        ("Z3", "C3"),
    ],
)
def test_german_mnemonics_are_aliases_of_the_english_ones(german: str, english: str) -> None:
    assert parse_address(german) == parse_address(english)


@pytest.mark.parametrize(
    ("text", "canonical"),
    [("I 0.0", "I0.0"), ("qx4.1", "Q4.1"), ("db1 . dbw 2", "DB1.DBW2"), ("  mw 10 ", "MW10")],
)
def test_blanks_lower_case_and_x_normalise_to_canonical_text(text: str, canonical: str) -> None:
    assert str(parse_address(text)) == canonical


@pytest.mark.parametrize(
    "text",
    [
        "I0.8",
        "MW10.3",
        "DB1.DBW2.1",
        "MB10.0",
        "I0",
        "QX4",
        "DB1.DBX0",
        "PI0.0",
        "PIX0.1",
        "X1.0",
        "DB0.DBB0",
        "M70000.0",
        "T",
        "",
        "DB1.W2",
    ],
)
def test_unknown_or_misaligned_addresses_raise_address_error_naming_the_text(text: str) -> None:
    with pytest.raises(AddressError) as info:
        parse_address(text)
    assert repr(text) in str(info.value)


@pytest.mark.parametrize(
    "text", ["M\u0661.\u0660", "Q\uff11.0", "MW\uff11\uff10", "DB\uff11.DBX0.0", "T\uff11"]
)
def test_digits_other_than_0_to_9_make_no_address(text: str) -> None:
    """Before: ``M١.٠`` (Arabic-Indic digits) and ``Q１.0`` (full-width) were M1.0 and Q1.0,
    in a chart, an S7-SCL source and a symbol file alike."""
    with pytest.raises(AddressError, match="not an S7 address"):
        parse_address(text)


def test_address_error_names_the_source_location_when_given() -> None:
    where = SourceLocation("drill.s7g", 12, 5)
    with pytest.raises(AddressError, match=r"^drill\.s7g:12:5: .*'MW10\.3'"):
        parse_address("MW10.3", where)


def test_odd_word_addresses_are_allowed_as_in_s7() -> None:
    assert parse_address("MW11").byte == 11


def test_addresses_are_hashable_and_equal_by_value() -> None:
    table = {parse_address("I 0.0"): "start"}
    assert table[parse_address("e0.0")] == "start"


def test_address_constructor_rejects_inconsistent_parts() -> None:
    with pytest.raises(AddressError):
        Address(Area.M, Width.WORD, 10, 3)
    with pytest.raises(AddressError):
        Address(Area.DB, Width.BYTE, 0)
    with pytest.raises(AddressError):
        Address(Area.T, Width.BIT, 5)


def test_address_size_counts_bytes_covered() -> None:
    assert [parse_address(t).size for t in ("M0.0", "MB0", "MW0", "MD0")] == [1, 1, 2, 4]
