"""SFC20 BLKMOV and SFC21 FILL over ANY-like areas (docs/runtime.md, "The block runtime"; STEP7
comprehensive guide vol. 2, ch. 12).

An ``AnyPointer`` is ``P#<address> <type> <count>`` (``P#DB1.DBX0.0 BYTE 10``): a start
address plus a length in elements. Rules (STEP7 comprehensive guide vol. 2, ch. 12):

* areas I, Q, M, PI, PQ, L and DBs are allowed; T/C are area errors (8x24 read / 8x25 write);
* a BOOL ANY must start at bit 0 and count a multiple of 8 bits (8x22 / 8x23), any other
  type must start on a byte boundary (8x28 / 8x29);
* a missing DB is 8x3A, an area overrun an area-length error (8x22 / 8x23);
* BLKMOV copies ``min(source, destination)`` bytes (a shorter destination takes only what
  fits, ``[K]``); the source is read whole before writing, so overlap cannot corrupt it;
* FILL repeats the BVAL pattern until BLK is full.

``x`` in ``8xyy`` is the parameter number from the catalogue (SRCBLK 1, DSTBLK 3).
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import TYPE_CHECKING

from s7graph.engine import blocks
from s7graph.engine.address import Area, Width, parse_address
from s7graph.engine.datatypes import type_of
from s7graph.engine.errors import AddressError, TypeMismatch
from s7graph.engine.memory import Memory
from s7graph.sfb.catalogue import (
    AREA_LENGTH_READ,
    AREA_LENGTH_WRITE,
    AREA_READ,
    AREA_WRITE,
    DB_NOT_LOADED,
    OK,
    engine_sections,
    general_error,
    lookup,
)

if TYPE_CHECKING:
    from s7graph.engine.context import CallContext

ALIGN_READ = 0x28
ALIGN_WRITE = 0x29
_ANY = re.compile(r"\s*P#\s*(.+?)\s+([A-Z_]+)\s+(\d+)\s*$", re.IGNORECASE)
_BYTE_AREAS = frozenset({Area.I, Area.Q, Area.M, Area.L, Area.PI, Area.PQ, Area.DB})


@dataclass(frozen=True, slots=True)
class AnyPointer:
    """An ANY parameter: area, start byte/bit (DB number), element type and count."""

    area: Area
    byte: int
    bit: int = 0
    db: int | None = None
    type: str = "BYTE"
    count: int = 1

    def __str__(self) -> str:
        where = (
            f"DB{self.db}.DBX{self.byte}.{self.bit}"
            if self.db is not None
            else (f"{self.area}{self.byte}.{self.bit}")
        )
        return f"P#{where} {self.type} {self.count}"

    @property
    def bits(self) -> int:
        """Length in bits."""
        if self.type == "BOOL":
            return self.count
        return self.count * type_of(self.type).size_bits


def parse_any(text: str) -> AnyPointer:
    """``P#M10.0 BYTE 4`` / ``P#DB1.DBX0.0 WORD 2`` / ``P#I 0.0 BOOL 16`` -> AnyPointer."""
    m = _ANY.match(text)
    if m is None:
        raise AddressError(f"{text!r} is not an ANY pointer (P#<address> <type> <count>)")
    addr = parse_address(m.group(1))
    type_name = m.group(2).upper()
    if type_name != "BOOL":
        try:
            type_of(type_name)
        except TypeMismatch as exc:
            raise AddressError(f"{text!r}: {exc.message}") from None
    bit = addr.bit if addr.width is Width.BIT else 0
    return AnyPointer(addr.area, addr.byte, bit, addr.db, type_name, int(m.group(3)))


def _span(mem: Memory, ptr: AnyPointer, param: int, write: bool) -> bytearray | int:
    """The live bytes behind ``ptr`` or a RET_VAL error (general code, parameter ``param``)."""
    if ptr.area not in _BYTE_AREAS:
        return general_error(param, AREA_WRITE if write else AREA_READ)
    if ptr.type == "BOOL" and ptr.bits % 8:
        return general_error(param, AREA_LENGTH_WRITE if write else AREA_LENGTH_READ)
    if ptr.bit:
        return general_error(param, ALIGN_WRITE if write else ALIGN_READ)
    if ptr.area is Area.DB and (ptr.db is None or ptr.db not in mem.dbs):
        return general_error(param, DB_NOT_LOADED)
    buf = mem.area_bytes(ptr.area, ptr.db)
    end = ptr.byte + ptr.bits // 8
    if ptr.count < 0 or end > len(buf):
        return general_error(param, AREA_LENGTH_WRITE if write else AREA_LENGTH_READ)
    return buf


def blkmov(mem: Memory, src: AnyPointer, dst: AnyPointer) -> int:
    """SFC20 BLKMOV(SRCBLK, DSTBLK): copy min(len) bytes; RET_VAL 0 or ``8xyy``."""
    entry = lookup("BLKMOV")
    sbuf = _span(mem, src, entry.param_number("SRCBLK"), write=False)
    if isinstance(sbuf, int):
        return sbuf
    dbuf = _span(mem, dst, entry.param_number("DSTBLK"), write=True)
    if isinstance(dbuf, int):
        return dbuf
    n = min(src.bits, dst.bits) // 8
    data = bytes(sbuf[src.byte : src.byte + n])
    _store(mem, dst, dbuf, data)
    return OK


def fill(mem: Memory, bval: AnyPointer, blk: AnyPointer) -> int:
    """SFC21 FILL(BVAL, BLK): repeat the BVAL bytes until BLK is full; RET_VAL."""
    entry = lookup("FILL")
    sbuf = _span(mem, bval, entry.param_number("BVAL"), write=False)
    if isinstance(sbuf, int):
        return sbuf
    dbuf = _span(mem, blk, entry.param_number("BLK"), write=True)
    if isinstance(dbuf, int):
        return dbuf
    pattern = bytes(sbuf[bval.byte : bval.byte + bval.bits // 8])
    n = blk.bits // 8
    if pattern:
        data = (pattern * (n // len(pattern) + 1))[:n]
        _store(mem, blk, dbuf, data)
    return OK


def _store(mem: Memory, dst: AnyPointer, buf: bytearray, data: bytes) -> None:
    buf[dst.byte : dst.byte + len(data)] = data
    end = dst.byte + len(data)
    if dst.area is Area.PQ and mem.pq_updates_q and end <= len(mem.outputs):
        mem.outputs[dst.byte : end] = data  # writing PQ also updates the Q image


# --- Engine adapters ----------------------------------------------------------------------

ANY_SYNTAX = 0x01  # 8x01: illegal syntax id in an ANY parameter


def _pointer(params: dict[str, object], name: str, entry_name: str) -> AnyPointer | int:
    try:
        return parse_any(str(params[name]))
    except AddressError:
        return general_error(lookup(entry_name).param_number(name), ANY_SYNTAX)


def _blkmov(ctx: CallContext, params: dict[str, object]) -> int:
    src, dst = _pointer(params, "SRCBLK", "BLKMOV"), _pointer(params, "DSTBLK", "BLKMOV")
    if isinstance(src, int):
        return src
    if isinstance(dst, int):
        return dst
    return blkmov(ctx.mem, src, dst)


def _fill(ctx: CallContext, params: dict[str, object]) -> int:
    bval, blk = _pointer(params, "BVAL", "FILL"), _pointer(params, "BLK", "FILL")
    if isinstance(bval, int):
        return bval
    if isinstance(blk, int):
        return blk
    return fill(ctx.mem, bval, blk)


def _declare(name: str, body: blocks.FCBody) -> blocks.FC:
    entry = lookup(name)
    sections, ret = engine_sections(entry)
    return blocks.sfc(entry.number, entry.name, RET=ret, **sections)(body)


SFC20 = _declare("BLKMOV", _blkmov)
SFC21 = _declare("FILL", _fill)
BLOCKS = (SFC20, SFC21)
