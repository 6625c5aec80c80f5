"""S7 absolute addresses: parsing and canonical text (docs/runtime.md, "The block runtime", Siemens'
Program Design for S7-300/400, ch. 5).

An address is area + width + first byte (+ bit 0..7 for BIT). Multi-byte operands start at their
lowest byte (``MD100`` = MB100..MB103, Siemens' Program Design for S7-300/400, ch. 5). ``T5``/``C3``
name a timer/counter cell: area T/C, width WORD, ``byte`` = the cell number. German mnemonics
(E/A/PE/PA/Z) and blanks are accepted; ``str()`` always gives canonical English text.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from enum import IntEnum, StrEnum
from functools import lru_cache

from s7graph.engine.errors import AddressError, SourceLocation

__all__ = ["Address", "Area", "Width", "parse_address"]


class Area(StrEnum):
    """Operand areas (Siemens' Program Design for S7-300/400, ch. 5, table 5-2)."""

    I = "I"  # noqa: E741 - the S7 mnemonic
    Q = "Q"
    M = "M"
    T = "T"
    C = "C"
    DB = "DB"
    L = "L"
    PI = "PI"
    PQ = "PQ"


class Width(IntEnum):
    """Operand width in bits."""

    BIT = 1
    BYTE = 8
    WORD = 16
    DWORD = 32


_SIZE_LETTER = {Width.BYTE: "B", Width.WORD: "W", Width.DWORD: "D"}
_LETTER_WIDTH = {"X": Width.BIT, "B": Width.BYTE, "W": Width.WORD, "D": Width.DWORD}
_AREA_ALIAS = {
    "I": Area.I,
    "E": Area.I,
    "Q": Area.Q,
    "A": Area.Q,
    "M": Area.M,
    "L": Area.L,
    "PI": Area.PI,
    "PE": Area.PI,
    "PQ": Area.PQ,
    "PA": Area.PQ,
}
MAX_BYTE = 65535
"""Highest byte (and timer/counter/DB) number an address may name."""

# re.ASCII: digits are 0-9 only (``M١.٠`` and ``M１.0`` are no S7 addresses)
_PLAIN = re.compile(r"(PI|PQ|PE|PA|I|Q|E|A|M|L)([XBWD]?)(\d+)(?:\.(\d+))?", re.ASCII)
_CELL = re.compile(r"([TCZ])(\d+)", re.ASCII)
_DB = re.compile(r"DB(\d+)\.DB([XBWD])(\d+)(?:\.(\d+))?", re.ASCII)


@dataclass(frozen=True, slots=True)
class Address:
    """One S7 operand; frozen and hashable so compiled code can key tables by it."""

    area: Area
    width: Width
    byte: int
    bit: int = 0
    db: int | None = None

    def __post_init__(self) -> None:
        problem = _check(self.area, self.width, self.byte, self.bit, self.db)
        if problem:
            raise AddressError(f"invalid address {self.area}/{self.width.name}: {problem}")

    @property
    def size(self) -> int:
        """Bytes covered (a BIT covers its one byte)."""
        return max(1, self.width // 8)

    def __str__(self) -> str:
        if self.area in (Area.T, Area.C):
            return f"{self.area}{self.byte}"
        if self.area is Area.DB:
            letter = "X" if self.width is Width.BIT else _SIZE_LETTER[self.width]
            tail = f".{self.bit}" if self.width is Width.BIT else ""
            return f"DB{self.db}.DB{letter}{self.byte}{tail}"
        if self.width is Width.BIT:
            return f"{self.area}{self.byte}.{self.bit}"
        return f"{self.area}{_SIZE_LETTER[self.width]}{self.byte}"

    def __repr__(self) -> str:
        return f"Address({str(self)!r})"


def _check(area: Area, width: Width, byte: int, bit: int, db: int | None) -> str:
    """Return why the parts do not form a valid address, or '' (docs/runtime.md, "The block
    runtime")."""
    if not 0 <= byte <= MAX_BYTE:
        return f"byte/number {byte} outside 0..{MAX_BYTE}"
    if not 0 <= bit <= 7:
        return f"bit {bit} outside 0..7"
    if width is not Width.BIT and bit:
        return "only bit addresses carry a bit number"
    if (area is Area.DB) != (db is not None):
        return "a DB number belongs to DB addresses only"
    if db is not None and not 1 <= db <= MAX_BYTE:
        return f"DB number {db} outside 1..{MAX_BYTE}"
    if area in (Area.T, Area.C) and width is not Width.WORD:
        return "timer and counter cells are words"
    if area in (Area.PI, Area.PQ) and width is Width.BIT:
        return "peripheral areas have no bit access (PIB/PIW/PID only)"
    return ""


@lru_cache(maxsize=4096)
def _parse(norm: str) -> Address | str:
    """Parse normalized (upper-case, blank-free) text; a str result is the error reason."""
    if len(norm) > 32:  # the longest, DB65535.DBX65535.7, has 18 characters
        return f"not an S7 address ({len(norm)} characters)"
    if m := _CELL.fullmatch(norm):
        area = Area.T if m[1] == "T" else Area.C
        return _build(area, Width.WORD, int(m[2]), 0, None)
    if m := _DB.fullmatch(norm):
        return _sized(Area.DB, m[2], m[3], m[4], int(m[1]))
    if m := _PLAIN.fullmatch(norm):
        return _sized(_AREA_ALIAS[m[1]], m[2], m[3], m[4], None)
    return "not an S7 address"


def _sized(area: Area, letter: str, byte: str, bit: str | None, db: int | None) -> Address | str:
    width = _LETTER_WIDTH.get(letter, Width.BIT)
    if width is Width.BIT and bit is None:
        return "a bit address needs '.bit' (0..7)"
    if width is not Width.BIT and bit is not None:
        return f"misaligned: a {width.name} address has no bit number"
    return _build(area, width, int(byte), int(bit or 0), db)


def _build(area: Area, width: Width, byte: int, bit: int, db: int | None) -> Address | str:
    return _check(area, width, byte, bit, db) or Address(area, width, byte, bit, db)


def parse_address(text: str, where: SourceLocation | None = None) -> Address:
    """Parse S7 address text (``I 0.0``, ``QX4.1``, ``EW2``, ``DB1.DBW2``, ``Z3`` …).

    Raises AddressError naming ``text`` (and ``where``) for unknown syntax, a bit outside
    0..7, a bit number on a byte/word/dword (``MW10.3``) or a bit on PI/PQ (docs/runtime.md, "The
    block runtime").
    """
    result = _parse("".join(text.split()).upper())
    if isinstance(result, str):
        raise AddressError(f"bad address {text!r}: {result}", where)
    return result
