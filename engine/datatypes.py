"""S7 data types: sizes, ranges, big-endian encodings and DB layout (docs/runtime.md, "The block
runtime").

Encodings (Siemens' Program Design for S7-300/400, appendix C; El-Shahat's S7-300/400 course, timers
and counters): integers two's complement big-endian; REAL IEEE 754 single; TIME = DINT ms; DATE =
WORD days since 1990-01-01; TIME_OF_DAY = DWORD ms since midnight; DATE_AND_TIME = 8 BCD bytes (YY
MM DD hh mm ss, 3 ms digits, weekday 1 = Sunday); S5TIME = 3 BCD digits + time base in bits 12-13;
STRING[n] = n + 2 bytes (max, current, chars). Python values follow docs/architecture.md, "Seams".
"""

from __future__ import annotations

import math
import re
import struct
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from datetime import date, datetime, timedelta
from functools import lru_cache

from s7graph.engine.errors import TypeMismatch

__all__ = [
    "DATE_EPOCH",
    "S5TIME_MAX_MS",
    "S5_BASES_MS",
    "TYPES",
    "FieldType",
    "Layout",
    "Slot",
    "TypeSpec",
    "bcd_to_int",
    "check_value",
    "decode",
    "encode",
    "int_to_bcd",
    "layout",
    "ms_to_s5time",
    "real32",
    "real_shown",
    "s5time_to_ms",
    "string_chars",
    "type_of",
]

DATE_EPOCH = date(1990, 1, 1)
DATE_MAX = date(2168, 12, 31)
DT_MIN = datetime(1990, 1, 1)
DT_MAX = datetime(2089, 12, 31, 23, 59, 59, 999000)
S5_BASES_MS = (10, 100, 1000, 10000)
"""S5TIME time bases for bits 12-13 = 00, 01, 10, 11 (El-Shahat's S7-300/400 course, timers and
counters)."""
S5TIME_MAX_MS = 999 * 10000
TOD_MAX_MS = 86_400_000 - 1
REAL_MAX = 3.4028234663852886e38


@dataclass(frozen=True)
class TypeSpec:
    """An S7 type: name, size in bits, signedness and numeric range (None when not numeric).

    TIME, S5TIME and TIME_OF_DAY ranges are in milliseconds (their Python value).
    """

    name: str
    size_bits: int
    signed: bool
    lo: int | float | None
    hi: int | float | None

    @property
    def size(self) -> int:
        """Bytes occupied (BOOL: 1)."""
        return max(1, self.size_bits // 8)


def _t(name: str, bits: int, signed: bool, lo: float | None, hi: float | None) -> TypeSpec:
    return TypeSpec(name, bits, signed, lo, hi)


TYPES: dict[str, TypeSpec] = {
    "BOOL": _t("BOOL", 1, False, 0, 1),
    "BYTE": _t("BYTE", 8, False, 0, 0xFF),
    "WORD": _t("WORD", 16, False, 0, 0xFFFF),
    "DWORD": _t("DWORD", 32, False, 0, 0xFFFF_FFFF),
    "CHAR": _t("CHAR", 8, False, 0, 0xFF),
    "INT": _t("INT", 16, True, -32768, 32767),
    "DINT": _t("DINT", 32, True, -(2**31), 2**31 - 1),
    "REAL": _t("REAL", 32, True, -REAL_MAX, REAL_MAX),
    "S5TIME": _t("S5TIME", 16, False, 0, S5TIME_MAX_MS),
    "TIME": _t("TIME", 32, True, -(2**31), 2**31 - 1),
    "DATE": _t("DATE", 16, False, None, None),
    "TIME_OF_DAY": _t("TIME_OF_DAY", 32, False, 0, TOD_MAX_MS),
    "DATE_AND_TIME": _t("DATE_AND_TIME", 64, False, None, None),
    "TIMER": _t("TIMER", 16, False, 0, 0xFFFF),
    "COUNTER": _t("COUNTER", 16, False, 0, 0xFFFF),
}
TYPES["TOD"] = TYPES["TIME_OF_DAY"]
TYPES["DT"] = TYPES["DATE_AND_TIME"]

_STRING = re.compile(r"STRING(?:\[(\d+)\])?")
_INT_TYPES = frozenset({"BYTE", "WORD", "DWORD", "INT", "DINT", "TIME", "TIMER", "COUNTER"})
_STRUCT_CODES = {"BYTE": ">B", "WORD": ">H", "DWORD": ">I", "INT": ">h", "DINT": ">i"}
_STRUCT_CODES |= {"TIME": ">i", "TIME_OF_DAY": ">I", "TIMER": ">H", "COUNTER": ">H"}


@lru_cache(maxsize=512)
def _lookup(key: str) -> TypeSpec | None:
    spec = TYPES.get(key)
    if spec is not None:
        return spec
    if len(key) <= 16 and (m := _STRING.fullmatch(key)):
        n = int(m[1]) if m[1] is not None else 254
        if n <= 254:
            return TypeSpec(f"STRING[{n}]", (n + 2) * 8, False, None, None)
    return None


def type_of(name: str) -> TypeSpec:
    """The TypeSpec for ``name`` (case-insensitive; ``STRING`` = ``STRING[254]``, n ≤ 254).

    Raises TypeMismatch for an unknown type (Siemens' Program Design for S7-300/400, appendix C).
    """
    spec = _lookup("".join(name.split()).upper())
    if spec is None:
        raise TypeMismatch(f"unknown data type {name!r}")
    return spec


def string_chars(name: str) -> int | None:
    """``n`` for a ``STRING[n]`` written with its length (case and blanks as ``type_of``
    takes them); None for any other type name, plain ``STRING`` included."""
    m = _STRING.fullmatch("".join(name.split()).upper())
    return int(m[1]) if m is not None and m[1] is not None else None


def _bad(spec: TypeSpec, value: object, why: str = "out of range") -> TypeMismatch:
    return TypeMismatch(f"{shown(value)} is {why} for {spec.name}")


def shown(value: object) -> str:
    """``value`` as a PLC programmer writes it: ``D#2169-06-06``, ``DT#…``, ``'text'``,
    ``TRUE``; a list or an object by what it is, never a Python repr."""
    if isinstance(value, bool):
        return "TRUE" if value else "FALSE"
    if isinstance(value, datetime):
        return "DT#" + value.strftime("%Y-%m-%d-%H:%M:%S")
    if isinstance(value, date):
        return "D#" + value.isoformat()
    if isinstance(value, str):
        return f"'{value}'" if len(value) <= 40 else f"'{value[:37]}...'"
    if value is None:
        return "nothing"
    if isinstance(value, list | tuple):
        return "a list"
    if isinstance(value, dict):
        return "a structure"
    if isinstance(value, int | float):
        return repr(value)
    return f"a {type(value).__name__} value"


_REAL = struct.Struct(">f")


def real32(value: float) -> float:
    """``value`` as a REAL holds it: rounded to IEEE 754 single precision (24 bits of
    mantissa), as the CPU's floating-point unit gives every REAL result; beyond the REAL
    range an infinity of its sign."""
    try:
        return float(_REAL.unpack(_REAL.pack(float(value)))[0])
    except OverflowError:
        return math.copysign(math.inf, value)


def real_shown(value: float) -> float:
    """A REAL's value as the CPU's watch table shows it: the shortest decimal that reads
    back as the same REAL (``0.1``, not ``0.10000000149011612``); a value no REAL holds
    exactly, as it is."""
    if not math.isfinite(value) or real32(value) != value:
        return value
    for digits in range(1, 10):
        near = float(f"{value:.{digits}g}")
        if real32(near) == value:
            return near
    return value


def check_value(type_name: str, value: object) -> object:
    """Check ``value`` fits ``type_name`` and return it (CHAR codes become 1-char str).

    Raises TypeMismatch for a wrong Python type or a value outside the S7 range
    (Siemens' Program Design for S7-300/400, appendix C, table C-1).
    """
    spec = type_of(type_name)
    name = spec.name
    if name == "BOOL":
        if isinstance(value, bool) or value in (0, 1):
            return bool(value)
        raise _bad(spec, value)
    if name in _INT_TYPES or name in ("S5TIME", "TIME_OF_DAY"):
        if not isinstance(value, int):
            raise _bad(spec, value, "not an integer")
        assert spec.lo is not None and spec.hi is not None
        if not spec.lo <= value <= spec.hi:
            raise _bad(spec, value)
        return value
    if name == "REAL":
        if not isinstance(value, int | float):
            raise _bad(spec, value, "not a number")
        if math.isfinite(value) and abs(value) > REAL_MAX:
            raise _bad(spec, value)
        return real32(value)
    if name == "CHAR":
        if isinstance(value, int) and not isinstance(value, bool) and 0 <= value <= 0xFF:
            return chr(value)
        if isinstance(value, str) and len(value) == 1 and ord(value) <= 0xFF:
            return value
        raise _bad(spec, value, "not a single latin-1 character")
    if name == "DATE":
        if isinstance(value, datetime) or not isinstance(value, date):
            raise _bad(spec, value, "not a date")
        if not DATE_EPOCH <= value <= DATE_MAX:
            raise _bad(spec, value)
        return value
    if name == "DATE_AND_TIME":
        if not isinstance(value, datetime):
            raise _bad(spec, value, "not a date and time")
        if not DT_MIN <= value.replace(tzinfo=None) <= DT_MAX:
            raise _bad(spec, value)
        return value
    # STRING[n]
    if not isinstance(value, str):
        raise _bad(spec, value, "not text")
    if len(value) > spec.size - 2:
        raise _bad(spec, value, "too long")
    try:
        value.encode("latin-1")
    except UnicodeEncodeError:
        raise _bad(spec, value, "not latin-1 text") from None
    return value


def int_to_bcd(value: int, digits: int = 3) -> int:
    """Binary 0..10**digits-1 → packed BCD (``C#26`` = 16#0026, El-Shahat's S7-300/400 course,
    timers and counters)."""
    if not 0 <= value < 10**digits:
        raise TypeMismatch(f"{value} does not fit {digits} BCD digits")
    out = 0
    for shift in range(digits):
        out |= (value // 10**shift % 10) << (4 * shift)
    return out


def bcd_to_int(bcd: int, digits: int = 3) -> int:
    """Packed BCD → binary; a nibble above 9 is a BCD error (TypeMismatch, El-Shahat's S7-300/400
    course, timers and counters)."""
    out = 0
    for shift in reversed(range(digits)):
        nibble = (bcd >> (4 * shift)) & 0xF
        if nibble > 9:
            raise TypeMismatch(f"W#16#{bcd:04X} is not valid BCD")
        out = out * 10 + nibble
    return out


def ms_to_s5time(ms: int) -> int:
    """Milliseconds → S5TIME word, finest base that fits (S5T#2S = W#16#0200, El-Shahat's S7-300/400
    course, timers and counters).

    The count is truncated to the chosen base; above 9990 s raises TypeMismatch.
    """
    if not 0 <= ms <= S5TIME_MAX_MS:
        raise TypeMismatch(f"{ms} ms is out of range for S5TIME (0..{S5TIME_MAX_MS})")
    for code, base in enumerate(S5_BASES_MS):
        if ms // base <= 999:
            return (code << 12) | int_to_bcd(ms // base)
    raise AssertionError("unreachable")  # pragma: no cover


def s5time_to_ms(word: int) -> int:
    """S5TIME word → milliseconds: BCD count × base (bits 12-13); bits 14-15 ignored."""
    return bcd_to_int(word & 0x0FFF) * S5_BASES_MS[(word >> 12) & 0x3]


def _bcd2(value: int) -> int:
    return ((value // 10) << 4) | (value % 10)


def _unbcd2(byte: int) -> int:
    return bcd_to_int(byte, 2)


def _encode_dt(value: datetime) -> bytes:
    ms = value.microsecond // 1000
    weekday = value.isoweekday() % 7 + 1  # 1 = Sunday (Program Design, appendix C)
    parts = (value.year % 100, value.month, value.day, value.hour, value.minute, value.second)
    return bytes([*(_bcd2(p) for p in parts), _bcd2(ms // 10), ((ms % 10) << 4) | weekday])


def _decode_dt(data: bytes) -> datetime:
    yy, mo, dd, hh, mi, ss, msh = (_unbcd2(b) for b in data[:7])
    msl = data[7] >> 4
    if msl > 9:
        raise TypeMismatch(f"DT byte 7 16#{data[7]:02X} is not valid BCD")
    year = 1900 + yy if yy >= 90 else 2000 + yy
    try:
        return datetime(year, mo, dd, hh, mi, ss, (msh * 10 + msl) * 1000)
    except ValueError as exc:
        raise TypeMismatch(f"invalid DATE_AND_TIME bytes {data.hex()}: {exc}") from None


def encode(type_name: str, value: object) -> bytes:
    """Value → big-endian bytes of the type's size (BOOL → one byte 0/1).

    Range-checked with ``check_value`` first (TypeMismatch).
    """
    spec = type_of(type_name)
    v = check_value(spec.name, value)
    name = spec.name
    code = _STRUCT_CODES.get(name)
    if code is not None:
        return struct.pack(code, v)
    if name == "BOOL":
        return b"\x01" if v else b"\x00"
    if name == "REAL":
        assert isinstance(v, float)
        return struct.pack(">f", v)
    if name == "CHAR":
        assert isinstance(v, str)
        return v.encode("latin-1")
    if name == "S5TIME":
        assert isinstance(v, int)
        return ms_to_s5time(v).to_bytes(2, "big")
    if name == "DATE":
        assert isinstance(v, date)
        return (v - DATE_EPOCH).days.to_bytes(2, "big")
    if name == "DATE_AND_TIME":
        assert isinstance(v, datetime)
        return _encode_dt(v)
    assert isinstance(v, str)
    n = spec.size - 2
    raw = v.encode("latin-1")
    return bytes([n, len(raw)]) + raw + bytes(n - len(raw))


def decode(type_name: str, data: bytes | bytearray | memoryview) -> object:
    """Big-endian bytes → Python value; ``data`` must hold at least the type's size.

    STRING reads the current length from byte 1 (clipped to the declared maximum, byte 0).
    """
    spec = type_of(type_name)
    name = spec.name
    if len(data) < spec.size:
        raise TypeMismatch(f"{len(data)} bytes are too few for {name} ({spec.size})")
    raw = bytes(data[: spec.size])
    code = _STRUCT_CODES.get(name)
    if code is not None:
        value: object = struct.unpack(code, raw)[0]
        return value
    if name == "BOOL":
        return bool(raw[0] & 1)
    if name == "REAL":
        real: float = struct.unpack(">f", raw)[0]
        return real
    if name == "CHAR":
        return raw.decode("latin-1")
    if name == "S5TIME":
        return s5time_to_ms(int.from_bytes(raw, "big"))
    if name == "DATE":
        return DATE_EPOCH + timedelta(days=int.from_bytes(raw, "big"))
    if name == "DATE_AND_TIME":
        return _decode_dt(raw)
    length = min(raw[1], raw[0], spec.size - 2)
    return raw[2 : 2 + length].decode("latin-1")


# ---- layout of STRUCT / ARRAY / DB images (Program Design for S7-300/400, appendix C) -----

FieldType = str | Sequence[tuple[str, "FieldType"]]
"""A field's type: a type name (``'INT'``, ``'STRING[10]'``, ``'ARRAY[1..5] OF INT'``) or a
nested STRUCT given as a sequence of ``(name, type)`` pairs."""

_ARRAY = re.compile(r"ARRAY\s*\[(.+?)\]\s*OF\s+(.+)", re.IGNORECASE | re.DOTALL)
_BOUND = re.compile(r"\s*(-?\d+)\s*\.\.\s*(-?\d+)\s*")


@dataclass(frozen=True)
class Slot:
    """Where one field lives: byte offset, bit (BOOL only), size in bytes (BOOL: 0)."""

    byte: int
    bit: int
    type: str
    size: int


@dataclass(frozen=True)
class Layout:
    """Offsets of named fields (nested names dotted, ``'s.x'``) and total size (even)."""

    slots: dict[str, Slot]
    size: int

    def __getitem__(self, name: str) -> tuple[int, int]:
        slot = self.slots[name]
        return slot.byte, slot.bit


class _Cursor:
    def __init__(self) -> None:
        self.byte = 0
        self.bit = 0  # > 0 while packing BOOLs into the current byte

    def close_bits(self) -> None:
        if self.bit:
            self.byte += 1
            self.bit = 0

    def even(self) -> None:
        self.close_bits()
        self.byte += self.byte & 1


def _place(cur: _Cursor, name: str, ftype: FieldType, out: dict[str, Slot]) -> None:
    """Place one field at ``cur`` following the rules of Siemens' Program Design for S7-300/400,
    appendix C."""
    if not isinstance(ftype, str):
        cur.even()
        start = cur.byte
        inner: dict[str, Slot] = {}
        size = _layout_into(ftype, inner)
        out[name] = Slot(start, 0, "STRUCT", size)
        for sub, slot in inner.items():
            out[f"{name}.{sub}"] = Slot(slot.byte + start, slot.bit, slot.type, slot.size)
        cur.byte = start + size
        return
    if m := _ARRAY.fullmatch(ftype.strip()):
        count = 1
        for dim in m[1].split(","):
            b = _BOUND.fullmatch(dim)
            if b is None or int(b[2]) < int(b[1]):
                raise TypeMismatch(f"bad array bounds in {ftype!r}")
            count *= int(b[2]) - int(b[1]) + 1
        elem = m[2].strip()
        cur.even()
        if elem.upper() == "BOOL":
            size = (count + 7) // 8
        else:
            one = _field_size(elem)
            size = count * (one + (one & 1) if one > 1 else one)
        size += size & 1
        out[name] = Slot(cur.byte, 0, ftype, size)
        cur.byte += size
        return
    spec = type_of(ftype)
    if spec.name == "BOOL":
        out[name] = Slot(cur.byte, cur.bit, "BOOL", 0)
        cur.bit += 1
        if cur.bit == 8:
            cur.close_bits()
        return
    if spec.size == 1:
        cur.close_bits()
    else:
        cur.even()
    out[name] = Slot(cur.byte, 0, spec.name, spec.size)
    cur.byte += spec.size
    if spec.size > 4:  # STRING, DT: the next field starts on an even byte
        cur.byte += cur.byte & 1


def _field_size(ftype: FieldType) -> int:
    tmp: dict[str, Slot] = {}
    cur = _Cursor()
    _place(cur, "_", ftype, tmp)
    return tmp["_"].size


def _layout_into(fields: Sequence[tuple[str, FieldType]], out: dict[str, Slot]) -> int:
    cur = _Cursor()
    for name, ftype in fields:
        if name in out:
            raise TypeMismatch(f"duplicate field {name!r}")
        _place(cur, name, ftype, out)
    cur.even()
    return cur.byte


def layout(fields: Sequence[tuple[str, FieldType]] | Mapping[str, FieldType]) -> Layout:
    """Lay out fields as S7 does in DBs and instance DBs (Siemens' Program Design for S7-300/400,
    appendix C).

    Consecutive BOOLs pack into one byte; BYTE/CHAR take the next byte; every other type,
    ARRAY, STRUCT and STRING starts on an even byte; the total is rounded up to even.
    Nested STRUCT members get absolute offsets under dotted names.
    """
    items = list(fields.items()) if isinstance(fields, Mapping) else list(fields)
    slots: dict[str, Slot] = {}
    size = _layout_into(items, slots)
    return Layout(slots, size)
