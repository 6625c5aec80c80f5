"""Operands of conditions and actions, resolved once at compile time into code snippets.

A ``Ref`` says what a name means (docs/semantics.md, "Conditions"): an S7 address (I Q M DB PI PQ,
T/C cells), an FB static variable, an FB pin, a step attribute ``Sn.X/T/U`` or ``Tn.TT``.
``CodeGen`` turns a ``Ref`` into a Python expression over names bound once per FB instance
(``bind``): memory areas are bound as ``bytearray`` objects (``_m0`` ``_m1`` ...), so a bit read is
one index and one shift, never a dict lookup or an Address parse.

Inside generated functions these locals exist: ``st`` (GraphState), ``V`` (``st.vars``), ``X``
(``st.x``). Values follow docs/architecture.md, "Seams": BOOL → bool/int 0/1, INT/DINT signed int,
WORD/DWORD unsigned int, REAL float, TIME ms.
"""

from __future__ import annotations

import math
import struct
from dataclasses import dataclass, field
from types import FunctionType
from typing import Any

from s7graph.engine.datatypes import ms_to_s5time, real32
from s7graph.engine.errors import SourceLocation, SymbolError

# S5 timer and counter cells (``T n``, ``C n``): a contact reads the status bit, a number
# (a comparison, arithmetic, an assignment to a number) reads the value as an INT — the
# count, or the remaining time in units of the time base, as ``L C n`` / ``L T n`` load it
# (El-Shahat's S7-300/400 course: "used at the same address as a BOOL state or as the current
# value").
CELLS = frozenset({"timer", "counter"})
CELL_VALUE_TYPE = "INT"
# The default type of an absolute address by width, when no symbol says otherwise.
WIDTH_TYPE = {1: "BOOL", 8: "BYTE", 16: "INT", 32: "DINT"}
# Bytes of each value type in memory.
TYPE_BYTES = {
    "BOOL": 0,
    "BYTE": 1,
    "CHAR": 1,
    "WORD": 2,
    "INT": 2,
    "S5TIME": 2,
    "DATE": 2,
    "DWORD": 4,
    "DINT": 4,
    "REAL": 4,
    "TIME": 4,
    "TIME_OF_DAY": 4,
    "TOD": 4,
}


@dataclass(frozen=True, slots=True)
class Ref:
    """A resolved operand. ``kind``: ``mem`` (address), ``var`` (FB static variable),
    ``pin`` (FB pin, ``name``), ``step`` (``index``, ``attr`` X/T/U), ``trans`` (``index``),
    ``timer``/``counter`` (``number``: an S5 cell; ``type`` BOOL, its status bit — ``CELLS``),
    ``idb`` (variable ``name`` of instance DB ``db``, read by name: ``DB10.Q``)."""

    kind: str
    type: str
    name: str = ""
    area: str = ""
    db: int | None = None
    byte: int = 0
    bit: int = 0
    index: int = 0
    attr: str = ""
    number: int = 0
    flex: bool = False
    """An absolute address without a declared type (``MD20``): its width gives ``type``,
    and a value beside it may settle another of that width (``expressions.settled``)."""


_WIDTH_LETTER = {1: "B", 2: "W", 4: "D"}


def address_text(ref: Ref) -> str | None:
    """The S7 address of a memory operand, as ``engine.address`` reads it: ``M0.1``,
    ``MW10``, ``PID4``, ``DB2.DBX0.0``, ``DB2.DBW4`` (its width from its type); None for
    a type no bit, byte, word or double word holds."""
    size = TYPE_BYTES.get(ref.type, 0)
    if ref.type != "BOOL" and size not in _WIDTH_LETTER:
        return None
    if ref.db is not None:
        if ref.type == "BOOL":
            return f"DB{ref.db}.DBX{ref.byte}.{ref.bit}"
        return f"DB{ref.db}.DB{_WIDTH_LETTER[size]}{ref.byte}"
    if ref.type == "BOOL":
        return f"{ref.area}{ref.byte}.{ref.bit}"
    return f"{ref.area}{_WIDTH_LETTER[size]}{ref.byte}"


@dataclass
class CodeGen:
    """Collects the memory buffers a generated module needs and renders operand code."""

    buffers: list[tuple[str, int | None]] = field(default_factory=list)
    consts: dict[str, Any] = field(default_factory=dict)
    idbs: list[int] = field(default_factory=list)
    """The instance DBs whose variables the module reads by name (``DB10.Q``): ``_d<k>`` is
    the ``values`` of ``idbs[k]``, bound once per FB instance."""

    def idb(self, db: int) -> str:
        if db not in self.idbs:
            self.idbs.append(db)
        return f"_d{self.idbs.index(db)}"

    def buf(self, area: str, db: int | None) -> str:
        key = (area, db)
        if key not in self.buffers:
            self.buffers.append(key)
        return f"_m{self.buffers.index(key)}"

    def const(self, value: Any, hint: str = "k") -> str:
        name = f"_{hint}{len(self.consts)}"
        self.consts[name] = value
        return name

    # ------------------------------------------------------------ reading

    def read(self, ref: Ref) -> str:
        """A Python expression reading ``ref``."""
        k = ref.kind
        if k == "step":
            if ref.attr == "X":
                return f"X[{ref.index}]"
            arr = "t_ns" if ref.attr == "T" else "u_ns"
            return f"(st.{arr}[{ref.index}] // 1000000)"
        if k == "trans":
            return f"st.tt[{ref.index}]"
        if k == "var":
            return f"V[{ref.name!r}]"
        if k == "pin":
            return f"_pin(st, {ref.name!r})"
        if k == "idb":
            assert ref.db is not None
            return f"{self.idb(ref.db)}[{ref.name!r}]"
        if k in ("timer", "counter"):
            return f"_cell_q(_mem, {k!r}, {ref.number})"
        b = self.buf(ref.area, ref.db)
        n = ref.byte
        t = ref.type
        if t == "BOOL":
            return f"({b}[{n}] >> {ref.bit} & 1)"
        if t in ("BYTE", "CHAR"):
            return f"{b}[{n}]"
        if t in ("WORD", "S5TIME", "DATE"):
            return f"({b}[{n}] << 8 | {b}[{n + 1}])"
        if t == "INT":
            return f"_signed_word({b}[{n}] << 8 | {b}[{n + 1}])"
        if t == "DWORD":
            return f"int.from_bytes({b}[{n}:{n + 4}], 'big')"
        if t in ("DINT", "TIME", "TIME_OF_DAY", "TOD"):
            return f"int.from_bytes({b}[{n}:{n + 4}], 'big', signed=True)"
        if t == "REAL":
            return f"_unpack_f({b}, {n})[0]"
        raise SymbolError(f"cannot read an operand of type {t}")

    def read_number(self, ref: Ref) -> str:
        """A Python expression reading ``ref`` where a number is expected: a timer or counter
        cell gives its value (``CELLS``), any other operand what ``read`` gives."""
        if ref.kind in CELLS:
            return f"_cell_v(_mem, {ref.kind!r}, {ref.number})"
        return self.read(ref)

    # ------------------------------------------------------------ writing

    def write(self, ref: Ref, value_src: str) -> str:
        """One Python statement writing ``value_src`` to ``ref``."""
        k = ref.kind
        if k == "var":
            if ref.type == "REAL":  # a REAL variable holds 32 bits, as in the instance DB
                value_src = f"_single({value_src})"
            return f"V[{ref.name!r}] = {value_src}"
        if k == "pin":  # an input pin (an output pin is read-only, E045)
            if ref.type == "BOOL":
                value_src = f"bool({value_src})"
            return f"_put_pin(st, {ref.name!r}, {value_src})"
        if k != "mem":
            raise SymbolError(f"{ref.name or k} cannot be written")
        b = self.buf(ref.area, ref.db)
        n = ref.byte
        t = ref.type
        if t == "BOOL":
            m = 1 << ref.bit
            return f"{b}[{n}] = ({b}[{n}] | {m}) if {value_src} else ({b}[{n}] & {255 ^ m})"
        if t in ("BYTE", "CHAR"):
            return f"{b}[{n}] = ({value_src}) & 255"
        if t in ("WORD", "INT", "S5TIME", "DATE"):
            return f"{b}[{n}:{n + 2}] = (int({value_src}) & 65535).to_bytes(2, 'big')"
        if t in ("DWORD", "DINT", "TIME", "TIME_OF_DAY", "TOD"):
            return f"{b}[{n}:{n + 4}] = (int({value_src}) & 4294967295).to_bytes(4, 'big')"
        if t == "REAL":
            return f"_pack_f({b}, {n}, {value_src})"
        raise SymbolError(f"cannot write an operand of type {t}")

    def write_returned(self, ref: Ref, value_src: str) -> str:
        """``write`` of a value a called block returns: an untyped double word
        (``ref.flex``) holds a REAL's bits when the block gives a REAL, else the number."""
        if ref.kind == "mem" and ref.flex and ref.type == "DINT":
            return f"_put_double({self.buf(ref.area, ref.db)}, {ref.byte}, {value_src})"
        return self.write(ref, value_src)

    def set_bit(self, ref: Ref, on: bool) -> str:
        """A statement setting (``on``) or resetting a BOOL operand."""
        if ref.kind == "mem" and ref.type == "BOOL":
            b = self.buf(ref.area, ref.db)
            m = 1 << ref.bit
            op = f"| {m}" if on else f"& {255 ^ m}"
            return f"{b}[{ref.byte}] = {b}[{ref.byte}] {op}"
        return self.write(ref, "True" if on else "False")


# ------------------------------------------------------------ runtime helpers (bound globals)


def _signed_word(v: int) -> int:
    return v - 65536 if v & 0x8000 else v


_F = struct.Struct(">f")


def _unpack_f(buf: bytearray, n: int) -> tuple[float]:
    return _F.unpack_from(buf, n)


def _pack_f(buf: bytearray, n: int, v: float) -> None:
    """Write REAL ``v``; beyond the REAL range it is stored as an infinity of its sign, as
    the CPU's floating-point overflow gives."""
    try:
        _F.pack_into(buf, n, float(v))
    except OverflowError:
        _F.pack_into(buf, n, math.copysign(math.inf, v))


def _put_double(buf: bytearray, n: int, v: Any) -> None:
    """A double word from a block's output: a REAL's bits for a REAL, else the number."""
    if isinstance(v, float):
        _pack_f(buf, n, v)
    else:
        buf[n : n + 4] = (int(v) & 0xFFFFFFFF).to_bytes(4, "big")


def _put_pin(st: Any, name: str, v: Any) -> None:
    """An input pin the chart writes: the instance DB's value of it, as on S7, which the
    next call latches (its edge counts: ``S1 S SW_MAN`` selects MAN) unless the caller
    passes the pin, whose value then wins."""
    st.inputs[name] = v
    st.repin.append(name)


def _pin(st: Any, name: str) -> Any:
    """An FB pin: the latched input, else the output of the previous call, else 0."""
    v = st.inputs.get(name)
    if v is None:
        v = st.outputs.get(name, 0)
    return v


def _cell_q(mem: Any, kind: str, number: int) -> bool:
    """The status bit of S5 timer / counter cell ``number`` (T n / C n as a contact)."""
    cells = mem.timers if kind == "timer" else mem.counters
    cell = cells[number]
    for attr in ("q", "status", "Q"):
        if hasattr(cell, attr):
            return bool(getattr(cell, attr))
    return bool(cell)


def _cell_v(mem: Any, kind: str, number: int) -> int:
    """The value of S5 timer / counter cell ``number`` read as a number (``CELLS``)."""
    if kind == "timer":
        return int(mem.timers[number].binary())
    return int(mem.counters[number].value)


def _with_index(f: Any, i: int) -> Any:
    """Generated function ``f`` with its own-step default ``_i`` set to ``i`` (shared code)."""
    return FunctionType(f.__code__, f.__globals__, f.__name__, (i,), f.__closure__)


def _with_defaults(f: Any, values: tuple[int, ...]) -> Any:
    """Generated function ``f`` with other default values (``_i``, ``_j0``, …: shared code)."""
    return FunctionType(f.__code__, f.__globals__, f.__name__, values, f.__closure__)


def _s5t(ms: int) -> int:
    """The S5TIME word of a time in milliseconds (``S5T#…``, an FB variable): the finest time
    base that holds it, as STEP 7 encodes the constant (the time of a TL, TD or TF row)."""
    return ms_to_s5time(int(ms))


RUNTIME: dict[str, Any] = {
    "_with_index": _with_index,
    "_with_defaults": _with_defaults,
    "_signed_word": _signed_word,
    "_unpack_f": _unpack_f,
    "_pack_f": _pack_f,
    "_single": real32,
    "_put_double": _put_double,
    "_pin": _pin,
    "_put_pin": _put_pin,
    "_cell_q": _cell_q,
    "_cell_v": _cell_v,
    "_s5t": _s5t,
}


def area_buffer(mem: Any, area: str, db: int | None) -> bytearray:
    """The live ``bytearray`` of a memory area (or DB) of ``mem``."""
    fn = getattr(mem, "area_bytes", None)
    if fn is not None:
        try:
            return fn(area, db) if db is not None else fn(area)  # type: ignore[no-any-return]
        except TypeError:
            pass
    if area == "DB" and db is not None:
        blk = mem.dbs[db]
        for attr in ("data", "buf", "bytes"):
            if hasattr(blk, attr):
                return getattr(blk, attr)  # type: ignore[no-any-return]
    raise SymbolError(f"memory has no area {area}{db if db is not None else ''}")


def where(loc: SourceLocation | None) -> str:
    return str(loc) if loc is not None else "<input>"
