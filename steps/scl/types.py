"""S7-SCL data types: what a type is, which values an operator takes, what converts
implicitly, zero values and the memory layout of a DB (docs/scl.md, "Types and
conversions"; Siemens' S7-SCL V5.3 for S7-300/400, "Data types" and "Expressions").

Classes of implicit conversion (class A of the S7-SCL manual; the guide ch. 13 lists them):
BOOL → BYTE → WORD → DWORD, INT → DINT → REAL, CHAR → STRING. Everything else converts only
through a function (class B). An untyped number (``5``, ``16#FF``) takes the type of what it
is assigned or passed to when its value fits there; in an operation it is INT (DINT when
larger) or, written with a radix, WORD (DWORD when larger).

Python values (docs/architecture.md, "Seams"): BOOL ``bool``; BYTE WORD DWORD unsigned
``int``; INT DINT signed ``int``; REAL ``float`` (rounded to 32 bits after each operation);
TIME, S5TIME, TIME_OF_DAY ``int`` ms; DATE ``date``; DATE_AND_TIME ``datetime``; CHAR and
STRING ``str``; an ARRAY a flat ``list`` (row-major), a STRUCT a ``dict``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

from s7graph.engine.datatypes import DATE_EPOCH, DT_MIN

BITS = ("BOOL", "BYTE", "WORD", "DWORD")
INTS = ("INT", "DINT")
NUMS = ("INT", "DINT", "REAL")
ELEMENTARY = frozenset(
    {
        *BITS,
        *NUMS,
        "CHAR",
        "TIME",
        "S5TIME",
        "DATE",
        "TIME_OF_DAY",
        "DATE_AND_TIME",
        "TIMER",
        "COUNTER",
        "BLOCK_DB",
    }
)
ALIASES = {"TOD": "TIME_OF_DAY", "DT": "DATE_AND_TIME"}
WIDTH = {"BOOL": 1, "BYTE": 8, "CHAR": 8, "WORD": 16, "INT": 16, "S5TIME": 16, "DATE": 16}
WIDTH |= {"DWORD": 32, "DINT": 32, "REAL": 32, "TIME": 32, "TIME_OF_DAY": 32}
RANGE = {"INT": (-32768, 32767), "DINT": (-(2**31), 2**31 - 1), "TIME": (-(2**31), 2**31 - 1)}
MASK = {"BYTE": 0xFF, "WORD": 0xFFFF, "DWORD": 0xFFFF_FFFF}
MAX_STRING = 254


@dataclass(frozen=True, slots=True)
class SclType:
    """A data type. ``kind``: an elementary type name, ``STRING`` (``length``), ``ARRAY``
    (``dims``, ``element``), ``STRUCT`` (``fields``; ``name`` of its UDT), ``FB`` (a
    multi-instance, ``name`` the FB's label), ``ANY`` (a system block's parameter of any
    type), ``VOID`` or ``ERROR`` (after a diagnostic: fits everything)."""

    kind: str
    length: int = 0
    dims: tuple[tuple[int, int], ...] = ()
    element: SclType | None = None
    fields: tuple[tuple[str, SclType], ...] = ()
    name: str = field(default="", compare=False)
    _members: dict[str, tuple[str, SclType]] | None = field(
        default=None, init=False, compare=False, repr=False
    )

    def __str__(self) -> str:
        if self.kind == "STRING":
            return f"STRING[{self.length}]"
        if self.kind == "ARRAY":
            dims = ", ".join(f"{lo}..{hi}" for lo, hi in self.dims)
            return f"ARRAY[{dims}] OF {self.element}"
        if self.kind == "STRUCT":
            return self.name or "STRUCT"
        if self.kind == "FB":
            return self.name
        return self.kind

    @property
    def count(self) -> int:
        """Elements of an ARRAY (1 for anything else)."""
        n = 1
        for lo, hi in self.dims:
            n *= hi - lo + 1
        return n

    def field_type(self, name: str) -> tuple[str, SclType] | None:
        """A STRUCT's member by name (case-insensitive): its declared spelling and type (the
        first so spelled). The index is built once per type: a DB of N members set in its
        BEGIN section is looked up N times."""
        members = self._members
        if members is None:
            members = {}
            for fname, ftype in self.fields:
                members.setdefault(fname.upper(), (fname, ftype))
            object.__setattr__(self, "_members", members)
        return members.get(name.upper())

    @property
    def aggregate(self) -> bool:
        return self.kind in ("ARRAY", "STRUCT")


def elementary(name: str) -> SclType:
    return SclType(ALIASES.get(name, name))


BOOL, BYTE, WORD, DWORD = (elementary(n) for n in BITS)
INT, DINT, REAL = (elementary(n) for n in NUMS)
CHAR, TIME, S5TIME, DATE = (elementary(n) for n in ("CHAR", "TIME", "S5TIME", "DATE"))
TOD, DT = elementary("TIME_OF_DAY"), elementary("DATE_AND_TIME")
TIMER, COUNTER = elementary("TIMER"), elementary("COUNTER")
BLOCK_DB = elementary("BLOCK_DB")  # a parameter: a DB's number, its bytes reached as p.DW[i]
STRING = SclType("STRING", MAX_STRING)
ANY = SclType("ANY")
VOID = SclType("VOID")
ERROR = SclType("ERROR")


def string(n: int = MAX_STRING) -> SclType:
    return SclType("STRING", n)


def by_name(name: str) -> SclType | None:
    """An elementary type (or STRING) by its name, case-insensitive; None if not one."""
    key = name.upper()
    key = ALIASES.get(key, key)
    if key in ELEMENTARY:
        return SclType(key)
    if key == "STRING":
        return STRING
    return None


def is_bits(t: SclType) -> bool:
    return t.kind in BITS


def is_int(t: SclType) -> bool:
    return t.kind in INTS


def is_num(t: SclType) -> bool:
    return t.kind in NUMS


# ---------------------------------------------------------------- implicit conversion


def widens(src: SclType, dst: SclType) -> bool:
    """True if ``src`` converts to ``dst`` without a function (class A, or equal)."""
    if src.kind == "ERROR" or dst.kind in ("ERROR", "ANY"):
        return True
    if src.kind == dst.kind:
        if src.kind == "STRING":
            return True
        if src.kind == "ARRAY":
            assert src.element is not None and dst.element is not None
            return same(src, dst)  # the same bounds and element type (a whole ARRAY)
        if src.kind == "STRUCT":
            return same(src, dst)
        if src.kind == "FB":
            return src.name == dst.name
        return True
    for chain in (BITS, NUMS):
        if src.kind in chain and dst.kind in chain:
            return chain.index(src.kind) <= chain.index(dst.kind)
    return src.kind == "CHAR" and dst.kind == "STRING"


def same(a: SclType, b: SclType) -> bool:
    """Structurally the same type (member names do not matter; the S7-SCL rule for whole
    STRUCT and ARRAY assignments)."""
    if a.kind != b.kind:
        return "ERROR" in (a.kind, b.kind)
    if a.kind == "STRUCT":
        return len(a.fields) == len(b.fields) and all(
            same(x[1], y[1]) for x, y in zip(a.fields, b.fields, strict=True)
        )
    if a.kind == "ARRAY":
        assert a.element is not None and b.element is not None
        return a.dims == b.dims and same(a.element, b.element)
    if a.kind == "STRING":
        return a.length == b.length
    return a.kind != "FB" or a.name == b.name


def common(a: SclType, b: SclType) -> SclType | None:
    """The type both operands widen to, or None (two strings: the longer one)."""
    if (
        a.kind in ("STRING", "CHAR")
        and b.kind in ("STRING", "CHAR")
        and "STRING" in (a.kind, b.kind)
    ):
        return string(
            max(a.length if a.kind == "STRING" else 1, b.length if b.kind == "STRING" else 1)
        )
    if widens(a, b):
        return b if b.kind not in ("ERROR", "ANY") else a
    if widens(b, a):
        return a
    return None


def literal_fits(t: SclType, value: object) -> bool:
    """Whether an untyped number ``value`` can be taken as a constant of type ``t``."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        return False
    if t.kind == "REAL":
        return True
    if not isinstance(value, int):
        return False
    if t.kind == "BOOL":
        return value in (0, 1)
    if t.kind in MASK:
        return 0 <= value <= MASK[t.kind]
    if t.kind in RANGE:
        lo, hi = RANGE[t.kind]
        return lo <= value <= hi
    return False


# ---------------------------------------------------------------- values


def zero(t: SclType) -> object:
    """The value of a fresh variable of type ``t`` (FALSE, 0, 0.0, '', D#1990-01-01 …);
    an aggregate's zero is built by ``zero_factory``."""
    kind = t.kind
    if kind == "BOOL":
        return False
    if kind == "REAL":
        return 0.0
    if kind in ("STRING", "CHAR"):
        return "" if kind == "STRING" else "\0"
    if kind == "DATE":
        return DATE_EPOCH
    if kind == "DATE_AND_TIME":
        return DT_MIN
    if t.aggregate:
        return zero_factory(t)()
    return 0


def zero_factory(t: SclType) -> Callable[[], object]:
    """A function returning a fresh zero value of ``t`` (a new list or dict each call)."""
    if t.kind == "ARRAY":
        assert t.element is not None
        elem, n = t.element, t.count
        if elem.aggregate:
            inner = zero_factory(elem)
            return lambda: [inner() for _ in range(n)]
        value = zero(elem)
        return lambda: [value] * n
    if t.kind == "STRUCT":
        parts = [(name, zero_factory(ft)) for name, ft in t.fields]
        return lambda: {name: make() for name, make in parts}
    value = zero(t)
    return lambda: value


def clone(value: object) -> object:
    """A copy of an aggregate value (lists and dicts copied, elementary values shared)."""
    if isinstance(value, list):
        if value and isinstance(value[0], list | dict):
            return [clone(v) for v in value]
        return list(value)
    if isinstance(value, dict):
        return {k: clone(v) for k, v in value.items()}
    return value


def recast(value: object, t: SclType) -> object:
    """A copy of ``value`` as a value of ``t``, a type structurally the same as its own
    (``same``): a STRUCT's members take ``t``'s names, in order — an assignment copies by
    position, as S7-SCL does for STRUCTs whose members differ only in their names."""
    if t.kind == "STRUCT" and isinstance(value, dict):
        return {
            name: recast(v, member)
            for (name, member), v in zip(t.fields, value.values(), strict=True)
        }
    if t.kind == "ARRAY" and isinstance(value, list):
        assert t.element is not None
        return [recast(v, t if isinstance(v, list) else t.element) for v in value]
    return clone(value)


def engine_type(t: SclType) -> str:
    """The type name of a block interface (``engine.blocks.Var``): elementary names,
    ``STRING[n]``, ``OBJECT`` for an aggregate (a list or dict value), a BLOCK_DB's
    number a ``WORD``."""
    if t.kind == "BLOCK_DB":
        return "WORD"
    if t.kind == "STRING":
        return f"STRING[{t.length}]"
    if t.aggregate:
        return "OBJECT"
    return t.kind


def is_block_db_var(type_name: object, comment: object) -> bool:
    """Whether an engine interface variable is a BLOCK_DB parameter: the WORD holding a
    DB's number (:func:`engine_type`), marked ``BLOCK_DB`` in its comment
    (``steps.scl.blocks``), so a block from another source keeps the type."""
    return comment == BLOCK_DB.kind and str(type_name).upper() == engine_type(BLOCK_DB)


# ---------------------------------------------------------------- memory layout


def size_of(t: SclType) -> int:
    """Bytes a value of ``t`` takes in a DB (a BOOL alone: 1; arrays and structures are
    rounded up to even) — Siemens' Program Design for S7-300/400, appendix C."""
    kind = t.kind
    if kind == "STRING":
        return t.length + 2
    if kind == "DATE_AND_TIME":
        return 8
    if kind == "ARRAY":
        assert t.element is not None
        if t.element.kind == "BOOL":
            size = (t.count + 7) // 8
        else:
            one = size_of(t.element)
            size = t.count * (one + (one & 1) if one > 1 else one)
        return size + (size & 1)
    if kind == "STRUCT":
        return struct_layout(t)[1]
    return max(1, WIDTH.get(kind, 16) // 8)


def element_stride(t: SclType) -> int:
    """Bytes from one element of an ARRAY to the next (bits for an ARRAY of BOOL)."""
    assert t.element is not None
    if t.element.kind == "BOOL":
        return 1
    one = size_of(t.element)
    return one + (one & 1) if one > 1 else one


def struct_layout(t: SclType) -> tuple[dict[str, tuple[int, int]], int]:
    """Offsets ``(byte, bit)`` of a STRUCT's members and its size: consecutive BOOLs share
    a byte, BYTE and CHAR take the next byte, everything else starts on an even byte, and
    the member after a STRING, an ARRAY or a STRUCT too."""
    offsets: dict[str, tuple[int, int]] = {}
    byte, bit = 0, 0
    for name, ft in t.fields:
        if ft.kind == "BOOL":
            offsets[name] = (byte, bit)
            bit += 1
            if bit == 8:
                byte, bit = byte + 1, 0
            continue
        if bit:
            byte, bit = byte + 1, 0
        size = size_of(ft)
        if size > 1 or ft.aggregate:
            byte += byte & 1
        offsets[name] = (byte, 0)
        byte += size
        if ft.kind == "STRING":  # what follows a STRING starts on an even byte, as after
            byte += byte & 1  # an ARRAY or a STRUCT (whose sizes are even)
    if bit:
        byte += 1
    return offsets, byte + (byte & 1)
