"""Names and operands → places: variables, constants, absolute and indexed operands,
symbols, DB and instance DB variables, array elements and structure members (docs/scl.md,
"Operands").

A path resolves to a ``Place`` (readable, maybe writable), a constant ``X``, or a
``Target`` to call. Absolute operands take their type from their width — BOOL, BYTE, WORD,
DWORD (the guide ch. 13: memory operands are WORD-typed, ``MW0 := INT_TO_WORD(23)``); a
symbol takes its table type. An index outside an array's bounds is E225 when the compiler
sees it, a block error when the program does.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from s7graph.engine.address import Address, Area, Width, parse_address
from s7graph.engine.errors import AddressError, SourceLocation
from s7graph.steps.scl import model as m
from s7graph.steps.scl import types as ty
from s7graph.steps.scl.builtins import BUILTINS, bind
from s7graph.steps.scl.calls import S5_COUNTERS, S5_TIMERS
from s7graph.steps.scl.consts import Constant
from s7graph.steps.scl.declare import BlockInfo
from s7graph.steps.scl.diagnostics import Problem
from s7graph.steps.scl.gen import HOLE, Block, Place, Resolved, Target, X, in_memory
from s7graph.steps.scl.tia import function_hint

_INDEXED = re.compile(r"(PI|PQ|I|Q|M)([XBWD]?)", re.IGNORECASE)
_DB_INDEXED = re.compile(r"D?B?([XBWD])", re.IGNORECASE)
_DB_SHORT = re.compile(r"(DB\d+)\.D([XBWD]\d+(?:\.\d+)?)")
_DB_FIXED = re.compile(r"(?:DB|D)([BWD])(\d{1,5})", re.IGNORECASE)
_DB_BIT = re.compile(r"D(?:BX|X)?(\d+)\.(\d+)", re.IGNORECASE)  # parse.py's bit_member
_RUNTIME_DB = "an access: .DW[i], .DB[i], .DD[i], .DX[i, j] or .DW2, .DB0, .DD4, .DX0.1"
_WIDTH_TYPE = {Width.BIT: ty.BOOL, Width.BYTE: ty.BYTE, Width.WORD: ty.WORD, Width.DWORD: ty.DWORD}
_LETTER_BITS = {"X": 1, "": 1, "B": 8, "W": 16, "D": 32}
_BITS_TYPE = {1: ty.BOOL, 8: ty.BYTE, 16: ty.WORD, 32: ty.DWORD}


@dataclass(frozen=True, slots=True)
class MemRef:
    """A value in an operand area or DB: its byte and bit as Python sources."""

    area: str
    db: int | None
    byte: str
    bit: str
    type: ty.SclType
    what: str


class Places:
    """The path resolver of one block."""

    def __init__(self, b: Block) -> None:
        self.b = b

    # ---- entry points

    def resolve(self, path: m.Path) -> Resolved:
        base, sels = path.base, list(path.selectors)
        if base.kind == "name":
            return self._name(path, sels)
        if base.kind == "address":
            return self._selectless(self._address(base.text, base.loc), sels, path)
        if base.kind == "db_address":
            text = _DB_SHORT.sub(r"\1.DB\2", base.text)
            return self._selectless(self._address(text, base.loc), sels, path)
        if base.kind == "block":
            return self._block(base.text, sels, path)
        if base.kind == "symbol":
            blk = self.b.prog.block(base.text)
            if blk is not None:
                return self._block_path(blk, sels, path)
            return self._selectless(self._symbol(base.text, base.loc), sels, path)
        number = int(base.text[1:])
        cell = ty.TIMER if base.text[0] == "T" else ty.COUNTER
        return self._selectless(X(cell, str(number), Constant(cell, number)), sels, path)

    def place(self, path: m.Path, writing: bool = False) -> Place:
        """The place ``path`` names (E223 if it is a constant or read-only and written)."""
        got = self.resolve(path)
        if isinstance(got, Target):
            raise Problem("E232", "a call is not a variable", path.loc)
        if isinstance(got, X):
            if writing:
                raise Problem("E223", f"cannot assign to the constant {path.base.text}", path.loc)
            return Place(got.type, got.src, None, path.base.text)
        if writing and got.put is None:
            raise Problem("E223", f"{got.what} cannot be written", path.loc)
        return got

    # ---- names

    def _name(self, path: m.Path, sels: list[m.Selector]) -> Resolved:
        b = self.b
        text, key, loc = path.base.text, path.base.text.upper(), path.base.loc
        local = b.locals.get(key)
        if local is not None:
            place = local.place
            if place.type.kind == "FB":
                return self._instance(place.get, place.type.name, sels, path, multi=True)
            if place.type.kind == "BLOCK_DB" and sels:  # p.DW[i]: the DB the caller passed
                return self.db_access(place.get, sels, path, place.what)
            return self.select(place, sels)
        if key in b.info.consts:
            t, v = b.info.consts[key]
            c = Constant(t, v, key in b.info.untyped)
            return self._selectless(X(t, b.literal_src(v), c), sels, path)
        special = self._special(key, sels, loc)
        if special is not None:
            return special
        called = sels and isinstance(sels[0], m.Args)
        if called and key == "WORD_TO_BLOCK_DB":
            return self._runtime_db(sels, path)
        if called and (key in BUILTINS or key in _S5_FUNCTIONS):
            assert isinstance(sels[0], m.Args)
            return self._after_call(Target("builtin", key, sels[0], loc), sels[1:], loc)
        blk = b.prog.block(text)
        if blk is not None:
            return self._block_path(blk, sels, path)
        if key in b.prog.names:
            return self._block(b.prog.names[key], sels, path)
        found = _INDEXED.fullmatch(text.lstrip("%"))
        if found and sels and isinstance(sels[0], m.Index):
            area, letter = found[1].upper(), found[2].upper()
            return self._indexed(area, None, letter, sels, path)
        if b.prog.symbols is not None and b.prog.symbols.lookup(text) is not None:
            return self._selectless(self._symbol(text, loc), sels, path)
        hint = function_hint(text) if called else None
        raise Problem("E211", hint or f"unknown name {text!r}", loc)

    def _special(self, key: str, sels: list[m.Selector], loc: SourceLocation) -> Place | None:
        b = self.b
        if key == "OK" and not sels:
            return Place(ty.BOOL, "_ok[0]", f"_ok[0] = {HOLE}", "OK")
        if key == "ENO" and not sels:
            return Place(ty.BOOL, "_eno[0]", None, "ENO")
        unit = b.info.unit
        if b.kind == "FC" and unit is not None and key == unit.name.upper() and not sels:
            if b.info.ret is None:
                raise Problem("E223", f"{unit.name} is VOID: it has no value to set", loc)
            return Place(b.info.ret, "_ret", f"_ret = {HOLE}", unit.name)
        return None

    def _selectless(self, got: Resolved, sels: list[m.Selector], path: m.Path) -> Resolved:
        if sels:
            raise Problem("E224", f"{path.base.text} takes no index, member or call", path.loc)
        return got

    # ---- blocks and instances

    def _block(self, text: str, sels: list[m.Selector], path: m.Path) -> Resolved:
        own = self._special(text.upper(), sels, path.loc)
        if own is not None:
            return own
        blk = self.b.prog.block(text)
        if blk is not None:
            return self._block_path(blk, sels, path)
        if text.startswith("DB") and text[2:].isdigit():
            number = int(text[2:])
            owner = self.b.prog.instances.get(number)
            if owner is not None:
                return self._instance(f"_idb(ctx, {number}, {owner!r})", owner, sels, path)
            return self._db_absolute(number, sels, path)
        raise Problem("E213", f"unknown block {text}", path.loc)

    def _block_path(self, blk: BlockInfo, sels: list[m.Selector], path: m.Path) -> Resolved:
        loc = path.loc
        if blk.kind in ("FC", "SFC"):
            if not sels or not isinstance(sels[0], m.Args):
                raise Problem("E232", f"{blk.label} is a function: call it with (…)", loc)
            return self._after_call(Target("fc", blk.label, sels[0], loc, blk), sels[1:], loc)
        if blk.kind in ("FB", "SFB"):
            if not sels or not isinstance(sels[0], m.Member):
                raise Problem(
                    "E233",
                    f"{blk.label} is a function block: call it with its instance DB, "
                    f"{blk.label}.DB10(…), or as a multi-instance declared in VAR",
                    loc,
                )
            inst = sels[0].name
            number = self.b.prog.db_number(inst)
            if number is None:
                raise Problem("E233", f"{inst} is not a DB for an instance of {blk.label}", loc)
            declared = self.b.prog.global_db(inst)
            if declared is not None and declared.unit is not None:
                raise Problem(
                    "E233",
                    f"DB{number} is a global DB ({declared.unit.loc}), not an instance of "
                    f"{blk.label}",
                    loc,
                )
            self.b.prog.instances.setdefault(number, blk.label)
            if self.b.prog.instances[number] != blk.label:
                raise Problem("E233", f"DB{number} is an instance of another FB", loc)
            idb = f"_idb(ctx, {number}, {blk.label!r})"
            return self._instance(idb, blk.label, sels[1:], path)
        if blk.kind == "DB":
            if blk.instance_of:
                idb = f"_idb(ctx, {blk.number}, {blk.instance_of!r})"
                return self._instance(idb, blk.instance_of, sels, path)
            member = sels[0] if sels and isinstance(sels[0], m.Member) else None
            if blk.db_type is not None and member and blk.db_type.field_type(member.name):
                start = MemRef("DB", blk.number, "0", "0", blk.db_type, blk.name)
                return self._mem_select(start, sels, path)
            indexed = len(sels) > 1 and isinstance(sels[1], m.Index)  # DB20.DW[i]
            if blk.db_type is not None and member and not indexed:
                has = ", ".join(n for n, _ in blk.db_type.fields[:8]) or "no members"
                raise Problem(
                    "E224",
                    f"DB{blk.number} has no member {member.name}; it has {has}",
                    member.loc if hasattr(member, "loc") else path.loc,
                )
            return self._db_absolute(blk.number, sels, path)
        raise Problem("E213", f"{blk.label} cannot be used here", loc)

    def _after_call(self, target: Target, rest: list[m.Selector], loc: SourceLocation) -> Target:
        if rest:
            raise Problem("E224", f"nothing may follow a call of {target.name}", rest[0].loc)
        return target

    def _instance(
        self, idb: str, fb: str, sels: list[m.Selector], path: m.Path, multi: bool = False
    ) -> Resolved:
        """An FB instance: called (``inst(…)``) or one of its variables read
        (``DB10.CONTROL``, ``inst.out``)."""
        info = self.b.prog.block(fb)
        if info is None:
            raise Problem("E213", f"unknown FB {fb}", path.loc)
        if sels and isinstance(sels[0], m.Args):
            kind = "multi" if multi else "fb"
            target = Target(kind, info.label, sels[0], path.loc, info, idb)
            return self._after_call(target, sels[1:], path.loc)
        if not sels or not isinstance(sels[0], m.Member):
            raise Problem("E224", f"an instance of {fb} is used by a variable: inst.name", path.loc)
        member = sels[0]
        param = info.params.get(member.name.upper())
        if param is None:
            raise Problem("E224", f"{fb} has no variable {member.name!r}", member.loc)
        item = f"{idb}.values[{param.name!r}]"
        if param.type.kind == "FB":
            return self._instance(item, param.type.name, sels[1:], path, multi=True)
        place = Place(param.type, item, f"{item} = {HOLE}", f"{path.base.text}.{param.name}")
        return self.select(place, sels[1:])

    # ---- selecting inside Python values

    def select(self, place: Place, sels: list[m.Selector]) -> Place:
        """Array elements and structure members of a variable held as a Python value."""
        for sel in sels:
            t = place.type
            if isinstance(sel, m.Index):
                if t.kind != "ARRAY":
                    raise Problem("E224", f"{place.what} is not an ARRAY", sel.loc)
                assert t.element is not None
                flat = self.flat_index(t, sel, place.what)
                get = f"{place.get}[{flat}]"
                place = Place(t.element, get, f"{get} = {HOLE}", f"{place.what}[…]")
            elif isinstance(sel, m.Member):
                found = t.field_type(sel.name) if t.kind == "STRUCT" else None
                if found is None:
                    raise Problem("E224", f"{place.what} has no member {sel.name!r}", sel.loc)
                get = f"{place.get}[{found[0]!r}]"
                place = Place(found[1], get, f"{get} = {HOLE}", f"{place.what}.{found[0]}")
            else:
                raise Problem("E232", f"{place.what} cannot be called", sel.loc)
        return place

    def flat_index(self, t: ty.SclType, sel: m.Index, what: str) -> str:
        """Python source of the row-major position of ``sel`` in the ARRAY ``t``."""
        if len(sel.items) != len(t.dims):
            n = len(t.dims)
            raise Problem("E224", f"{what} needs {n} ind{'ex' if n == 1 else 'ices'}", sel.loc)
        parts: list[str] = []
        stride = 1
        for (lo, hi), item in reversed(list(zip(t.dims, sel.items, strict=True))):
            x = self.b.exprs.expr(item)
            if not ty.is_int(x.type) and x.type.kind != "ERROR":
                raise Problem("E224", f"an index is an INT or DINT, not {x.type}", item.loc)
            if x.const is not None and isinstance(x.const.value, int):
                if not lo <= x.const.value <= hi:
                    raise Problem("E225", f"index {x.const.value} is outside {lo}..{hi}", item.loc)
                part = str(x.const.value - lo)
            else:
                part = f"_ix({x.src}, {lo}, {hi}, {self.b.where(item.loc)})"
            parts.append(part if stride == 1 else f"{part} * {stride}")
            stride *= hi - lo + 1
        return " + ".join(reversed(parts))

    # ---- operands in memory

    def _address(self, text: str, loc: SourceLocation) -> Place:
        try:
            addr = parse_address(text)
        except AddressError as exc:
            raise Problem("E205", exc.message, loc) from None
        if addr.area in (Area.T, Area.C):
            raise Problem("E205", f"{text}: a timer or counter is no operand here", loc)
        return self._static(addr, _WIDTH_TYPE[addr.width], text)

    def _static(self, addr: Address, t: ty.SclType, what: str) -> Place:
        pointer = repr("P#{} {} {}".format(addr, *_any_type(t)))
        return in_memory(t, self.b.const(addr), what, pointer)

    def _symbol(self, text: str, loc: SourceLocation) -> Resolved:
        table = self.b.prog.symbols
        sym = table.lookup(text) if table is not None else None
        if sym is None:
            raise Problem("E211", f"unknown symbol {text!r}", loc)
        if sym.address.area in (Area.T, Area.C):
            cell = ty.TIMER if sym.address.area is Area.T else ty.COUNTER
            n = sym.address.byte
            return X(cell, str(n), Constant(cell, n))
        t = ty.by_name(sym.type) or _WIDTH_TYPE[sym.address.width]
        return self._static(sym.address, t, f'"{sym.name}"')

    def _indexed(
        self,
        area: str,
        db: int | str | None,
        letter: str,
        sels: list[m.Selector],
        path: m.Path,
    ) -> Place:
        """``MD[i]``, ``PIW[252 + i]``, ``Q[i, 0]``, ``DB11.DW[i]``, ``DB12.DX[w, b]``; ``db``
        the DB's number, or Python source computing it (``WORD_TO_BLOCK_DB``)."""
        index = sels[0]
        assert isinstance(index, m.Index)
        bits = _LETTER_BITS[letter]
        need = 2 if bits == 1 else 1
        if len(index.items) != need or len(sels) > 1:
            what = "a bit takes byte and bit" if need == 2 else "an operand takes one index"
            raise Problem("E224", f"indexed {path.base.text}: {what}", path.loc)
        xs = [self.b.exprs.expr(e) for e in index.items]
        for x, e in zip(xs, index.items, strict=True):
            if not ty.is_int(x.type) and x.type.kind != "ERROR":
                raise Problem("E224", f"an index is an INT or DINT, not {x.type}", e.loc)
        bit = xs[1].src if need == 2 else "0"
        addr = f"_ad({area!r}, {bits}, {xs[0].src}, {bit}, {db})"
        t = _BITS_TYPE[bits]
        return _mem_access(t, addr, f"{path.base.text}[…]")

    def _runtime_db(self, sels: list[m.Selector], path: m.Path) -> Place:
        """``WORD_TO_BLOCK_DB(w).DW[i]``, ``….DX[i, j]``, ``….DW2``, ``….DX0.1``: an address in
        the DB whose number the WORD ``w`` holds when the statement runs (S7-SCL manual,
        "Data types", BLOCK_DB, and the class B conversions)."""
        call = sels[0]
        assert isinstance(call, m.Args)
        db = f"({self.block_db_number(call, path.loc)})"
        return self.db_access(db, sels[1:], path, "WORD_TO_BLOCK_DB(…)")

    def block_db_number(self, call: m.Args, loc: SourceLocation) -> str:
        """Python source of the DB number ``WORD_TO_BLOCK_DB(w)`` gives: the WORD ``w``."""
        args = [(a.name, self.b.exprs.expr(a.value), a.loc) for a in call.items]
        (w,) = bind("WORD_TO_BLOCK_DB", ("IN",), args, loc)
        return self.b.exprs.convert(w, ty.WORD, call.loc, "pass")

    def db_access(self, db: str, sels: list[m.Selector], path: m.Path, what: str) -> Place:
        """An address in the DB numbered ``db`` (Python source) when the statement runs,
        reached as S7-SCL reaches a DB's bytes absolutely (S7-SCL manual, "Shared data": the
        DB, then ``D`` and a size prefix X, B, W or D — ``.DW2``, ``.DX0.1``, ``.D0.1`` — or
        indexed, ``.DW[i]``, ``.DX[i, j]``); STL's ``.DBW2``, ``.DBX0.1`` too. A missing DB,
        DB0 or an instance DB of an S7-SCL FB is a block error at the statement."""
        access = sels[0] if sels else None
        if not isinstance(access, m.Member):
            where = access.loc if access is not None else path.loc
            raise Problem("E224", f"{what} is followed by {_RUNTIME_DB}", where)
        indexed = _DB_INDEXED.fullmatch(access.name)
        if indexed and len(sels) > 1 and isinstance(sels[1], m.Index):
            return self._indexed("DB", db, indexed[1].upper(), sels[1:], path)
        fixed = _DB_FIXED.fullmatch(access.name)
        bit = _DB_BIT.fullmatch(access.name)
        if (fixed is None and bit is None) or len(sels) > 1:
            raise Problem("E224", f"{what} is followed by {_RUNTIME_DB}", access.loc)
        if bit is not None:
            byte, n = int(bit[1]), int(bit[2])
            if n > 7 or byte > 65535:
                why = f"bit {n} outside 0..7" if n > 7 else f"byte {byte} outside 0..65535"
                raise Problem("E205", f"{what}.{access.name}: {why}", access.loc)
            return _mem_access(ty.BOOL, f"_ad('DB', 1, {byte}, {n}, {db})", f"{what}.{access.name}")
        assert fixed is not None
        bits = _LETTER_BITS[fixed[1].upper()]
        addr = f"_ad('DB', {bits}, {int(fixed[2])}, 0, {db})"
        return _mem_access(_BITS_TYPE[bits], addr, f"{what}.{access.name}")

    def _db_absolute(self, number: int, sels: list[m.Selector], path: m.Path) -> Place:
        if len(sels) == 2 and isinstance(sels[0], m.Member) and isinstance(sels[1], m.Index):
            found = _DB_INDEXED.fullmatch(sels[0].name)
            if found:
                return self._indexed("DB", number, found[1].upper(), sels[1:], path)
        raise Problem("E224", f"DB{number}: use DB{number}.DW[i] or a declared DB", path.loc)

    def _mem_select(self, ref: MemRef, sels: list[m.Selector], path: m.Path) -> Place:
        """Members and elements of a DB declared in the source, down to a place."""
        for sel in sels:
            t = ref.type
            if isinstance(sel, m.Member) and t.kind == "STRUCT":
                from s7graph.steps.scl.types import struct_layout

                found = t.field_type(sel.name)
                if found is None:
                    raise Problem("E224", f"{ref.what} has no member {sel.name!r}", sel.loc)
                offsets, _ = struct_layout(t)
                byte, bit = offsets[found[0]]
                ref = MemRef(
                    ref.area,
                    ref.db,
                    _add(ref.byte, byte),
                    _add(ref.bit, bit),
                    found[1],
                    f"{ref.what}.{found[0]}",
                )
            elif isinstance(sel, m.Index) and t.kind == "ARRAY":
                ref = self._mem_element(ref, sel)
            else:
                raise Problem("E224", f"{ref.what} has no such member or index", sel.loc)
        return self._mem_place(ref)

    def _mem_element(self, ref: MemRef, sel: m.Index) -> MemRef:
        t = ref.type
        assert t.element is not None
        flat = self.flat_index(t, sel, ref.what)
        stride = ty.element_stride(t)
        if t.element.kind == "BOOL":
            k = f"({flat})"
            return MemRef(
                ref.area, ref.db, f"{ref.byte} + {k} // 8", f"{k} % 8", t.element, f"{ref.what}[…]"
            )
        byte = f"{ref.byte} + ({flat}) * {stride}"
        return MemRef(ref.area, ref.db, byte, "0", t.element, f"{ref.what}[…]")

    def _mem_place(self, ref: MemRef) -> Place:
        t = ref.type
        static = _static_int(ref.byte), _static_int(ref.bit)
        if t.aggregate:
            k = self.b.const(t)
            head = f"_mem, {ref.area!r}, {ref.db}, {ref.byte}, {k}"
            start = f"_ad({ref.area!r}, 8, {ref.byte}, 0, {ref.db})"
            pointer = "_anyp({}, {!r}, {})".format(start, *_any_type(t))
            return Place(t, f"_mget({head})", f"_mset({head}, {HOLE})", ref.what, pointer)
        bits = _bits_of(t)
        if static[0] is not None and static[1] is not None:
            width = {1: Width.BIT, 8: Width.BYTE, 16: Width.WORD, 32: Width.DWORD}[bits]
            addr = Address(Area(ref.area), width, static[0], static[1], ref.db)
            return self._static(addr, t, ref.what)
        addr_src = f"_ad({ref.area!r}, {bits}, {ref.byte}, {ref.bit}, {ref.db})"
        return _mem_access(t, addr_src, ref.what)


_S5_FUNCTIONS = frozenset(S5_TIMERS) | frozenset(S5_COUNTERS)


def _bits_of(t: ty.SclType) -> int:
    """The width of the address a value of ``t`` is read at (longer types: from a byte)."""
    if t.kind == "BOOL":
        return 1
    size = ty.size_of(t)
    return size * 8 if size in (1, 2, 4) else 8


def _mem_access(t: ty.SclType, addr: str, what: str) -> Place:
    """The place of a value of ``t`` at the address ``addr`` computes (Python source)."""
    pointer = "_anyp({}, {!r}, {})".format(addr, *_any_type(t))
    return in_memory(t, addr, what, pointer)


_ANY_TYPES = frozenset({"BOOL", "BYTE", "CHAR", "WORD", "INT", "DWORD", "DINT", "REAL", "TIME"})


def _any_type(t: ty.SclType) -> tuple[str, int]:
    """The type and count an ANY pointer to a value of ``t`` names: an elementary type one
    of it, a STRING, a DATE_AND_TIME, an ARRAY or a STRUCT its bytes."""
    if t.kind in _ANY_TYPES:
        return t.kind, 1
    return "BYTE", ty.size_of(t)


def _add(src: str, n: int) -> str:
    if n == 0:
        return src
    static = _static_int(src)
    return str(static + n) if static is not None else f"{src} + {n}"


def _static_int(src: str) -> int | None:
    try:
        return int(src)
    except ValueError:
        return None
