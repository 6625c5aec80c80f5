"""Round trips: address text, literals, encodings, memory (hypothesis; docs/runtime.md, "The block
runtime")."""

from __future__ import annotations

from datetime import date, datetime

from hypothesis import given
from hypothesis import strategies as st

from s7graph.engine.address import Address, Area, Width, parse_address
from s7graph.engine.datatypes import decode, encode, ms_to_s5time, s5time_to_ms
from s7graph.engine.literals import format_literal, parse_literal
from s7graph.engine.memory import Memory

BYTES = st.integers(0, 65535)


@st.composite
def addresses(draw: st.DrawFn) -> Address:
    area = draw(st.sampled_from(list(Area)))
    if area in (Area.T, Area.C):
        return Address(area, Width.WORD, draw(BYTES))
    widths = [w for w in Width if not (area in (Area.PI, Area.PQ) and w is Width.BIT)]
    width = draw(st.sampled_from(widths))
    bit = draw(st.integers(0, 7)) if width is Width.BIT else 0
    db = draw(st.integers(1, 65535)) if area is Area.DB else None
    return Address(area, width, draw(BYTES), bit, db)


@given(addresses())
def test_address_text_round_trips(addr: Address) -> None:
    assert parse_address(str(addr)) == addr
    assert parse_address(str(addr).lower()) == addr


DATES = st.dates(date(1990, 1, 1), date(2168, 12, 31))
DTS = st.datetimes(datetime(1990, 1, 1), datetime(2089, 12, 31, 23, 59, 59)).map(
    lambda d: d.replace(microsecond=d.microsecond // 1000 * 1000)
)
TEXT = st.text(st.characters(min_codepoint=1, max_codepoint=255), max_size=30)
FLOAT32 = st.floats(width=32, allow_nan=False, allow_infinity=False)

TYPED_VALUES = st.one_of(
    st.tuples(st.just("BOOL"), st.booleans()),
    st.tuples(st.just("BYTE"), st.integers(0, 0xFF)),
    st.tuples(st.just("WORD"), st.integers(0, 0xFFFF)),
    st.tuples(st.just("DWORD"), st.integers(0, 0xFFFF_FFFF)),
    st.tuples(st.just("INT"), st.integers(-32768, 32767)),
    st.tuples(st.just("DINT"), st.integers(-(2**31), 2**31 - 1)),
    st.tuples(st.just("REAL"), FLOAT32),
    st.tuples(st.just("TIME"), st.integers(-(2**31), 2**31 - 1)),
    st.tuples(st.just("S5TIME"), st.integers(0, 9_990_000)),
    st.tuples(st.just("TIME_OF_DAY"), st.integers(0, 86_399_999)),
    st.tuples(st.just("DATE"), DATES),
    st.tuples(st.just("DATE_AND_TIME"), DTS),
    st.tuples(st.just("CHAR"), st.characters(min_codepoint=1, max_codepoint=255)),
    st.tuples(st.just("STRING"), TEXT),
)


@given(TYPED_VALUES)
def test_format_then_parse_literal_gives_back_type_and_value(tv: tuple[str, object]) -> None:
    type_name, value = tv
    assert parse_literal(format_literal(type_name, value)) == (type_name, value)


@given(TYPED_VALUES.filter(lambda tv: tv[0] != "S5TIME"))
def test_encode_then_decode_gives_back_the_value(tv: tuple[str, object]) -> None:
    type_name, value = tv
    name = "STRING[30]" if type_name == "STRING" else type_name
    assert decode(name, encode(name, value)) == value


@given(st.integers(0, 9_990_000))
def test_s5time_keeps_three_significant_digits_and_never_grows(ms: int) -> None:
    """El-Shahat's S7-300/400 course, timers and counters: the actual value is between TV − 1 time
    base and TV."""
    back = s5time_to_ms(ms_to_s5time(ms))
    base = (10, 100, 1000, 10000)[ms_to_s5time(ms) >> 12]
    assert back <= ms < back + base
    assert ms_to_s5time(back) == ms_to_s5time(ms)


@given(st.integers(0, 124), st.integers(0, 0xFFFF_FFFF))
def test_dword_bytes_read_back_most_significant_first(byte: int, value: int) -> None:
    """For any dword: MB n is bits 31..24 of MD n."""
    mem = Memory()
    mem.write(Address(Area.M, Width.DWORD, byte), value)
    assert mem.read(Address(Area.M, Width.BYTE, byte)) == value >> 24
    assert mem.read(Address(Area.M, Width.WORD, byte + 2)) == value & 0xFFFF
