"""SFC20 BLKMOV and SFC21 FILL over ANY areas (STEP7 comprehensive guide vol. 2, ch. 12)."""

from __future__ import annotations

import pytest

from s7graph.engine.address import Area
from s7graph.engine.errors import AddressError
from s7graph.engine.memory import Memory
from s7graph.sfb.catalogue import as_word, br_of
from s7graph.sfb.sfc_memory import AnyPointer, blkmov, fill, parse_any


@pytest.fixture
def mem() -> Memory:
    m = Memory()
    m.create_db(1, 16)
    m.markers[0:6] = bytes([1, 2, 3, 4, 5, 6])
    return m


def test_parse_any_reads_p_hash_pointers() -> None:
    assert parse_any("P#DB1.DBX2.0 WORD 3") == AnyPointer(Area.DB, 2, 0, 1, "WORD", 3)
    assert parse_any("p#m 10.0 bool 16").bits == 16
    assert str(parse_any("P#M4.0 BYTE 2")) == "P#M4.0 BYTE 2"
    with pytest.raises(AddressError):
        parse_any("M4 BYTE 2")


def test_blkmov_copies_between_areas_and_a_shorter_destination_takes_what_fits(
    mem: Memory,
) -> None:
    assert blkmov(mem, parse_any("P#M0.0 BYTE 6"), parse_any("P#DB1.DBX0.0 WORD 2")) == 0
    assert bytes(mem.dbs[1].data[:6]) == bytes([1, 2, 3, 4, 0, 0])
    assert blkmov(mem, parse_any("P#M0.0 BOOL 16"), parse_any("P#Q0.0 BYTE 8")) == 0
    assert bytes(mem.outputs[:3]) == bytes([1, 2, 0])


def test_blkmov_with_overlap_copies_the_source_as_it_was(mem: Memory) -> None:
    assert blkmov(mem, parse_any("P#M0.0 BYTE 4"), parse_any("P#M1.0 BYTE 4")) == 0
    assert bytes(mem.markers[:5]) == bytes([1, 1, 2, 3, 4])


@pytest.mark.parametrize(
    ("src", "dst", "word"),
    [
        ("P#M0.0 BOOL 7", "P#M10.0 BYTE 1", 0x8122),  # BOOL not multiple of 8
        ("P#M0.0 BYTE 1", "P#M10.0 BOOL 12", 0x8323),
        ("P#M0.1 BYTE 1", "P#M10.0 BYTE 1", 0x8128),  # bit address not 0
        ("P#DB9.DBX0.0 BYTE 1", "P#M10.0 BYTE 1", 0x813A),  # DB not loaded
        ("P#M0.0 BYTE 4", "P#DB1.DBX14.0 BYTE 2", 0x0000),  # shorter dst: fits
        ("P#M254.0 BYTE 4", "P#M10.0 BYTE 1", 0x8122),  # beyond the M area
        ("P#M0.0 BYTE 4", "P#DB1.DBX15.0 WORD 1", 0x8323),
    ],
)
def test_blkmov_errors_are_8xyy_with_the_parameter_number(
    mem: Memory, src: str, dst: str, word: int
) -> None:
    """Error RET_VALs have bit 15 set and BR = 0."""
    ret = blkmov(mem, parse_any(src), parse_any(dst))
    assert as_word(ret) == word
    assert br_of(ret) is (word == 0)


def test_fill_repeats_the_pattern_until_the_destination_is_full(mem: Memory) -> None:
    assert fill(mem, parse_any("P#M0.0 BYTE 3"), parse_any("P#DB1.DBX0.0 BYTE 8")) == 0
    assert bytes(mem.dbs[1].data[:9]) == bytes([1, 2, 3, 1, 2, 3, 1, 2, 0])
