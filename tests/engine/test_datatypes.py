"""Data types: sizes, ranges, encodings, layout (docs/runtime.md, "The block runtime", Siemens'
Program Design for S7-300/400, appendix C; El-Shahat's S7-300/400 course, timers and counters)."""

from __future__ import annotations

from datetime import date, datetime

import pytest

from s7graph.engine.datatypes import (
    bcd_to_int,
    check_value,
    decode,
    encode,
    int_to_bcd,
    layout,
    ms_to_s5time,
    s5time_to_ms,
    type_of,
)
from s7graph.engine.errors import TypeMismatch


@pytest.mark.parametrize(
    ("name", "bits"),
    [
        ("BOOL", 1),
        ("BYTE", 8),
        ("CHAR", 8),
        ("WORD", 16),
        ("INT", 16),
        ("S5TIME", 16),
        ("DATE", 16),
        ("DWORD", 32),
        ("DINT", 32),
        ("REAL", 32),
        ("TIME", 32),
        ("TIME_OF_DAY", 32),
        ("TOD", 32),
        ("DATE_AND_TIME", 64),
        ("DT", 64),
    ],
)
def test_elementary_types_have_s7_sizes(name: str, bits: int) -> None:
    assert type_of(name).size_bits == bits


def test_type_names_are_case_insensitive_and_aliases_share_a_spec() -> None:
    assert type_of("tod") is type_of("TIME_OF_DAY")
    assert type_of("dt").name == "DATE_AND_TIME"


def test_unknown_type_is_a_type_mismatch() -> None:
    with pytest.raises(TypeMismatch, match="LREAL"):
        type_of("LREAL")


def test_string_n_occupies_n_plus_two_bytes_and_plain_string_is_254() -> None:
    """STRING[10] occupies 12 bytes; STRING = STRING[254] = 256 bytes."""
    assert type_of("STRING[10]").size == 12
    assert type_of("STRING").size == 256
    with pytest.raises(TypeMismatch):
        type_of("STRING[255]")


def test_string_bytes_hold_max_length_then_current_length_then_chars() -> None:
    """I_STRNG(205) = '+205' in a STRING[10]: byte 0 = 10, byte 1 = 4."""
    data = encode("STRING[10]", "+205")
    assert data == bytes([10, 4]) + b"+205" + bytes(6)
    assert decode("STRING[10]", data) == "+205"


def test_string_longer_than_its_declared_length_is_a_type_mismatch() -> None:
    with pytest.raises(TypeMismatch, match="too long"):
        encode("STRING[3]", "abcd")


@pytest.mark.parametrize(
    ("name", "value", "data"),
    [
        ("BYTE", 0xAB, b"\xab"),
        ("WORD", 0x1234, b"\x12\x34"),
        ("DWORD", 0x01020304, b"\x01\x02\x03\x04"),
        ("INT", -2, b"\xff\xfe"),
        ("DINT", -2, b"\xff\xff\xff\xfe"),
        ("REAL", 1.0, b"\x3f\x80\x00\x00"),
        ("TIME", -1000, (-1000).to_bytes(4, "big", signed=True)),
        ("TIME_OF_DAY", 43_200_500, (43_200_500).to_bytes(4, "big")),
        ("DATE", date(1990, 1, 2), b"\x00\x01"),
        ("CHAR", "A", b"A"),
        ("BOOL", True, b"\x01"),
    ],
)
def test_values_encode_big_endian_and_decode_back(name: str, value: object, data: bytes) -> None:
    """Multi-byte values are big-endian, highest byte first."""
    assert encode(name, value) == data
    assert decode(name, data) == value


@pytest.mark.parametrize(
    ("ms", "word"),
    [
        (2000, 0x0200),
        (80_000, 0x1800),
        (120_000, 0x2120),
        (9_990_000, 0x3999),
        (0, 0x0000),
        (9990, 0x0999),
        (10_000, 0x1100),
    ],
)
def test_s5time_picks_the_finest_time_base_that_fits(ms: int, word: int) -> None:
    """El-Shahat's S7-300/400 course, timers and counters: S5T#2S = W#16#0200, S5T#1M20S =
    W#16#1800, max = W#16#3999."""
    assert ms_to_s5time(ms) == word
    assert s5time_to_ms(word) == ms


def test_s5time_ignores_bits_14_and_15() -> None:
    assert s5time_to_ms(0xC200) == 2000


def test_s5time_above_2h46m30s_is_a_type_mismatch() -> None:
    with pytest.raises(TypeMismatch):
        ms_to_s5time(9_990_001 + 9999)


def test_s5time_truncates_to_its_time_base() -> None:
    assert s5time_to_ms(ms_to_s5time(12_345)) == 12_300


def test_bcd_conversions_reject_invalid_nibbles() -> None:
    assert int_to_bcd(26) == 0x26
    assert bcd_to_int(0x999) == 999
    with pytest.raises(TypeMismatch, match="BCD"):
        bcd_to_int(0x1A0)
    with pytest.raises(TypeMismatch):
        int_to_bcd(1000)


def test_date_and_time_is_eight_bcd_bytes_with_sunday_as_weekday_one() -> None:
    """DT = YY MM DD hh mm ss, ms (3 digits), weekday (1 = Sunday)."""
    sunday = datetime(2026, 11, 22, 12, 34, 56, 789_000)
    assert encode("DT", sunday) == bytes([0x26, 0x11, 0x22, 0x12, 0x34, 0x56, 0x78, 0x91])
    monday = datetime(1995, 1, 2)
    assert encode("DT", monday)[0] == 0x95
    assert encode("DT", monday)[7] & 0x0F == 2
    assert decode("DT", encode("DT", sunday)) == sunday


def test_date_and_time_years_90_to_99_are_1990s_and_00_to_89_are_2000s() -> None:
    """Year byte (Siemens' Program Design for S7-300/400, appendix C): 16#90 → 1990, 16#89 →
    2089."""
    assert decode("DT", bytes([0x90, 1, 1, 0, 0, 0, 0, 0x02])).year == 1990
    assert decode("DT", bytes([0x89, 1, 1, 0, 0, 0, 0, 0x02])).year == 2089


def test_date_and_time_with_invalid_bcd_is_a_type_mismatch() -> None:
    with pytest.raises(TypeMismatch):
        decode("DT", bytes([0x26, 0x13, 0x01, 0, 0, 0, 0, 0]))


@pytest.mark.parametrize(
    ("name", "value"),
    [
        ("BYTE", 256),
        ("BYTE", -1),
        ("WORD", 65536),
        ("INT", 32768),
        ("INT", -32769),
        ("DINT", 2**31),
        ("S5TIME", -10),
        ("TIME_OF_DAY", 86_400_000),
        ("REAL", 1e39),
        ("DATE", date(1989, 12, 31)),
        ("DT", datetime(2090, 1, 1)),
        ("CHAR", "AB"),
        ("BOOL", 2),
        ("INT", 1.5),
        ("DATE", datetime(2000, 1, 1)),
        ("STRING[2]", 5),
    ],
)
def test_out_of_range_or_wrong_kind_values_are_type_mismatches(name: str, value: object) -> None:
    with pytest.raises(TypeMismatch):
        check_value(name, value)


def test_char_accepts_a_code_and_gives_the_character() -> None:
    assert check_value("CHAR", 65) == "A"


def test_layout_of_seed_db10_puts_words_on_even_bytes() -> None:
    """Siemens' Program Design for S7-300/400, appendix C (STEP7 comprehensive guide vol. 2, ch.
    13): ARRAY[1..100] OF INT, BOOL, WORD, BYTE, S5TIME."""
    lay = layout(
        [
            ("a", "ARRAY[1..100] OF INT"),
            ("b", "BOOL"),
            ("w", "WORD"),
            ("y", "BYTE"),
            ("t", "S5TIME"),
        ]
    )
    assert [lay[n] for n in ("a", "b", "w", "y", "t")] == [
        (0, 0),
        (200, 0),
        (202, 0),
        (204, 0),
        (206, 0),
    ]
    assert lay.size == 208


def test_layout_of_seed_struct_rounds_the_total_up_to_even() -> None:
    """Siemens' Program Design for S7-300/400, appendix C: INT, BYTE, CHAR, REAL, BOOL ends at
    10.0."""
    lay = layout({"i": "INT", "b": "BYTE", "c": "CHAR", "r": "REAL", "x": "BOOL"})
    assert (lay["b"], lay["c"], lay["r"], lay["x"], lay.size) == (
        (2, 0),
        (3, 0),
        (4, 0),
        (8, 0),
        10,
    )


def test_layout_packs_consecutive_bools_into_bits_of_one_byte() -> None:
    """Siemens' Program Design for S7-300/400, appendix C: FC1 params at 0.0, 0.1, 2.0, 2.1, 4.0."""
    lay = layout(
        [("a", "BOOL"), ("b", "BOOL"), ("i", "INT"), ("c", "BOOL"), ("d", "BOOL"), ("e", "INT")]
    )
    assert [lay[n] for n in "abcd"] == [(0, 0), (0, 1), (4, 0), (4, 1)]
    assert lay["i"] == (2, 0)


def test_layout_gives_nested_struct_members_absolute_dotted_names() -> None:
    lay = layout([("x", "BOOL"), ("s", [("a", "BOOL"), ("i", "INT")]), ("z", "BYTE")])
    assert (lay["s"], lay["s.a"], lay["s.i"], lay["z"], lay.size) == (
        (2, 0),
        (2, 0),
        (4, 0),
        (6, 0),
        8,
    )


def test_layout_starts_strings_and_arrays_on_even_bytes_and_rounds_them_up() -> None:
    lay = layout(
        [
            ("b", "BYTE"),
            ("s", "STRING[3]"),
            ("c", "BYTE"),
            ("a", "ARRAY[0..2] OF BYTE"),
            ("m", "ARRAY[1..2, 1..3] OF BOOL"),
        ]
    )
    assert (lay["s"], lay["c"], lay["a"], lay["m"]) == ((2, 0), (8, 0), (10, 0), (14, 0))
    assert lay.size == 16


def test_layout_rejects_duplicate_fields_and_bad_bounds() -> None:
    with pytest.raises(TypeMismatch):
        layout([("a", "INT"), ("a", "INT")])
    with pytest.raises(TypeMismatch):
        layout([("a", "ARRAY[3..1] OF INT")])


def test_a_value_that_does_not_fit_is_named_as_a_plc_programmer_writes_it() -> None:
    """No Python repr in a refusal: dates as D#/DT#, BOOLs as TRUE/FALSE, aggregates by kind."""
    for value, type_name, says in [
        (date(2169, 6, 6), "DATE", "D#2169-06-06 is out of range for DATE"),
        (datetime(2090, 1, 1), "DATE_AND_TIME", "DT#2090-01-01-00:00:00 is out of range"),
        ("2000-01-01", "DATE", "'2000-01-01' is not a date for DATE"),
        ({"a": 1}, "STRING[4]", "a structure is not text for STRING[4]"),
        (None, "STRING[4]", "nothing is not text for STRING[4]"),
    ]:
        with pytest.raises(TypeMismatch) as caught:
            check_value(type_name, value)
        assert caught.value.message.startswith(says), caught.value.message
