"""Literals (docs/runtime.md, "The block runtime", Siemens' Program Design for S7-300/400, appendix
C, table C-1)."""

from __future__ import annotations

from datetime import date, datetime

import pytest

from s7graph.engine.errors import LiteralError, SourceLocation, TypeMismatch
from s7graph.engine.literals import format_literal, parse_literal


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("TRUE", ("BOOL", True)),
        ("false", ("BOOL", False)),
        ("BOOL#1", ("BOOL", True)),
        ("12", ("INT", 12)),
        ("-32768", ("INT", -32768)),
        ("70000", ("DINT", 70000)),
        ("L#1", ("DINT", 1)),
        ("L#-2147483648", ("DINT", -(2**31))),
        ("INT#16#3F_FF", ("INT", 0x3FFF)),
        ("1.5", ("REAL", 1.5)),
        ("1.0e3", ("REAL", 1000.0)),
        ("1.234567e+13", ("REAL", 12345669582848.0)),  # a REAL holds 32 bits
        ("REAL#2", ("REAL", 2.0)),
        ("16#FF", ("WORD", 255)),
        ("16#1_0000", ("DWORD", 0x10000)),
        ("B#16#FF", ("BYTE", 255)),
        ("B#2#101", ("BYTE", 5)),
        ("W#16#FFF0", ("WORD", 0xFFF0)),
        ("WORD#8#177777", ("WORD", 0xFFFF)),
        ("DW#16#00A2_1234", ("DWORD", 0x00A21234)),
        ("2#1010", ("WORD", 10)),
        ("B#(10,20)", ("WORD", 0x0A14)),
        ("B#(1,14,100,120)", ("DWORD", 0x010E6478)),
        ("C#26", ("WORD", 0x0026)),
        ("C#998", ("WORD", 0x0998)),
        ("CHAR#49", ("CHAR", "1")),
        ("S5T#2S", ("S5TIME", 2000)),
        ("S5TIME#0H_1M_0S_0MS", ("S5TIME", 60_000)),
        ("S5T#2H46M30S", ("S5TIME", 9_990_000)),
        ("T#1s200ms", ("TIME", 1200)),
        ("TIME#-5m", ("TIME", -300_000)),
        ("T#1D2H", ("TIME", 93_600_000)),
        ("T#24D_20H_31M_23S_647MS", ("TIME", 2**31 - 1)),
        ("T#1.5S", ("TIME", 1500)),
        ("D#2026-11-22", ("DATE", date(2026, 11, 22))),
        ("DATE#1994-3-15", ("DATE", date(1994, 3, 15))),
        ("TOD#12:00:00.5", ("TIME_OF_DAY", 43_200_500)),
        ("TIME_OF_DAY#1:10:3.3", ("TIME_OF_DAY", 4_203_300)),
        ("DT#2026-11-22-12:00:00", ("DATE_AND_TIME", datetime(2026, 11, 22, 12))),
        (
            "DATE_AND_TIME#1995-01-01-12:12:12.2",
            ("DATE_AND_TIME", datetime(1995, 1, 1, 12, 12, 12, 200_000)),
        ),
        ("'text'", ("STRING", "text")),
        ("'it$'s $41$$'", ("STRING", "it's A$")),
        ("''", ("STRING", "")),
    ],
)
def test_literals_parse_to_type_and_value(text: str, expected: tuple[str, object]) -> None:
    assert parse_literal(text) == expected


@pytest.mark.parametrize(
    "text",
    [
        "B#16#1FF",
        "W#16#1_0000",
        "32768000000",
        "INT#40000",
        "C#1000",
        "S5T#2H46M31S",
        "S5T#-1S",
        "T#24D20H31M23S648MS",
        "D#1989-12-31",
        "D#2169-01-01",
        "TOD#24:00:00",
        "DT#2090-01-01-00:00:00",
        "B#(256,0)",
        "3.5e39",
        "DW#16#1_0000_0000",
    ],
)
def test_out_of_range_literals_raise_literal_error_naming_the_text(text: str) -> None:
    with pytest.raises(LiteralError) as info:
        parse_literal(text)
    assert repr(text) in str(info.value)


@pytest.mark.parametrize(
    "text",
    [
        "X#1",
        "T#5S1M",
        "T#",
        "'open",
        "'a'b'",
        "1.",
        "16#XYZ",
        "D#2026-02-30",
        "P#M50.0",
        "",
        "'$Q'",
    ],
)
def test_malformed_literals_raise_literal_error(text: str) -> None:
    with pytest.raises(LiteralError):
        parse_literal(text)


@pytest.mark.parametrize(
    ("text", "said"),
    [
        ("2#102", "'2' is not a digit of base 2"),
        ("8#9", "'9' is not a digit of base 8"),
        ("D#2026-02-30", "2026-02 has no day 30"),
        ("DT#2000-13-01-00:00:00", "there is no month 13"),
    ],
)
def test_a_malformed_literal_is_said_in_s7_terms_not_pythons(text: str, said: str) -> None:
    with pytest.raises(LiteralError) as info:
        parse_literal(text)
    assert str(info.value).endswith(said) and "int()" not in str(info.value)


def test_literal_error_names_the_source_location() -> None:
    with pytest.raises(LiteralError, match=r"^chart\.s7g:3:9: .*'B#16#100'"):
        parse_literal("B#16#100", SourceLocation("chart.s7g", 3, 9))


@pytest.mark.parametrize(
    ("type_name", "value", "text"),
    [
        ("TIME", 1200, "T#1S200MS"),
        ("TIME", -300_000, "T#-5M"),
        ("TIME", 0, "T#0MS"),
        ("S5TIME", 80_000, "S5T#1M20S"),
        ("WORD", 0xFFF0, "W#16#FFF0"),
        ("BYTE", 10, "B#16#0A"),
        ("DWORD", 0xA21234, "DW#16#00A21234"),
        ("INT", -5, "-5"),
        ("DINT", 70000, "L#70000"),
        ("BOOL", True, "TRUE"),
        ("REAL", 1e20, "1.0E+20"),
        ("REAL", -0.25, "-0.25"),
        ("CHAR", "A", "CHAR#65"),
        ("DATE", date(1994, 3, 5), "D#1994-03-05"),
        ("TOD", 43_200_500, "TOD#12:00:00.500"),
        ("TIME_OF_DAY", 0, "TOD#00:00:00"),
        ("DT", datetime(2026, 11, 22, 12), "DT#2026-11-22-12:00:00"),
        ("STRING[20]", "it's\n", "'it$'s$N'"),
    ],
)
def test_format_literal_gives_canonical_upper_case_text(
    type_name: str, value: object, text: str
) -> None:
    assert format_literal(type_name, value) == text


def test_format_literal_rejects_values_outside_the_type() -> None:
    with pytest.raises(TypeMismatch):
        format_literal("BYTE", 300)
