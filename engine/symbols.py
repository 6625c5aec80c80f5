"""The global symbol table: name → address, type, comment (docs/runtime.md, "The block runtime",
docs/architecture.md, "Seams").

Accepted text forms, one per file (detected from the content): ``"Name" ; I0.7 ; BOOL ; comment``
lines; ``,``-separated CSV with a header row (columns named symbol/name, address, type, comment);
``"Name" : I0.7 : BOOL;`` entries as in the ``.s7g`` SYMBOLS section (docs/chart-format.md). ``//``
and ``#`` start comment lines. Names are unique regardless of case (as in the STEP 7 symbol editor
``[K]``). A row whose address is a block (``"Data" ; DB 20 ; DB 20``, ``"Motor" : FB17 : FB;``)
names that block, as the STEP 7 symbol table does: ``db_number`` finds a DB by it
(``"Data".temps[2]``); such rows are kept apart from the operand symbols.
"""

from __future__ import annotations

import csv
import io
import re
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

from s7graph.engine.address import Address, Area, Width, parse_address
from s7graph.engine.datatypes import type_of
from s7graph.engine.errors import AddressError, SourceLocation, SymbolError, TypeMismatch
from s7graph.engine.text import read_utf8

__all__ = ["BlockSymbol", "Symbol", "SymbolTable", "default_type"]

_WIDTH_TYPES: dict[Width, str] = {
    Width.BIT: "BOOL",
    Width.BYTE: "BYTE",
    Width.WORD: "WORD",
    Width.DWORD: "DWORD",
}


def default_type(address: Address) -> str:
    """The natural type of an address: BOOL/BYTE/WORD/DWORD by width, TIMER/COUNTER for T/C."""
    if address.area is Area.T:
        return "TIMER"
    if address.area is Area.C:
        return "COUNTER"
    return _WIDTH_TYPES[address.width]


@dataclass(frozen=True, slots=True)
class Symbol:
    """One symbol table row (docs/runtime.md, "The block runtime")."""

    name: str
    address: Address
    type: str
    comment: str = ""


@dataclass(frozen=True, slots=True)
class BlockSymbol:
    """A symbol table row naming a block (``"Data"`` for DB 20): kind ``DB``, ``FB``, …"""

    name: str
    kind: str
    number: int
    comment: str = ""


_BLOCK = re.compile(r"\s*(DB|FB|FC|SFB|SFC|UDT|OB|VAT)\s*(\d{1,5})\s*", re.IGNORECASE)


def _fits(address: Address, type_name: str) -> bool:
    """A type fits an address when its size equals the width (T/C: TIMER/COUNTER only)."""
    if address.area in (Area.T, Area.C):
        return type_name == default_type(address)
    if type_name in ("TIMER", "COUNTER"):
        return False
    bits = type_of(type_name).size_bits
    return bits == address.width if bits <= 32 else address.width is not Width.BIT


def _unquote(name: str) -> str:
    name = name.strip()
    if len(name) >= 2 and name[0] == name[-1] and name[0] in "\"'":
        return name[1:-1]
    return name


class SymbolTable:
    """Symbols by name; ``resolve`` turns a symbol or address text into an Address."""

    def __init__(self) -> None:
        self._by_key: dict[str, Symbol] = {}
        self._where: dict[str, SourceLocation | None] = {}
        self._blocks: dict[str, BlockSymbol] = {}

    def __len__(self) -> int:
        return len(self._by_key)

    def __iter__(self) -> Iterator[Symbol]:
        return iter(self._by_key.values())

    def __contains__(self, name: object) -> bool:
        return isinstance(name, str) and _unquote(name).casefold() in self._by_key

    def add(
        self,
        name: str,
        address: Address | str,
        type: str | None = None,
        comment: str = "",
        *,
        where: SourceLocation | None = None,
    ) -> Symbol | BlockSymbol:
        """Add a symbol (a block's when ``address`` is one, ``DB 20``); a duplicate name, a
        bad address or an unknown/unfitting type raises SymbolError naming ``where`` (and the
        first definition for duplicates)."""
        bare = _unquote(name)
        if not bare:
            raise SymbolError("empty symbol name", where)
        key = bare.casefold()
        if key in self._by_key or key in self._blocks:
            first = self._where.get(key)
            also = f" (first defined at {first})" if first is not None else ""
            raise SymbolError(f'duplicate symbol "{bare}"{also}', where)
        block = _BLOCK.fullmatch(address) if isinstance(address, str) else None
        if block is not None:
            return self._add_block(bare, block, comment, where)
        try:
            addr = parse_address(address, where) if isinstance(address, str) else address
        except AddressError as exc:
            raise SymbolError(f'symbol "{bare}": {exc.message}', where) from None
        tname = (type or default_type(addr)).strip().upper()
        try:
            tname = type_of(tname).name
        except TypeMismatch:
            raise SymbolError(f'symbol "{bare}": unknown data type {type!r}', where) from None
        if not _fits(addr, tname):
            raise SymbolError(f'symbol "{bare}": type {tname} does not fit {addr}', where)
        sym = Symbol(bare, addr, tname, comment.strip())
        self._by_key[key] = sym
        self._where[key] = where
        return sym

    def _add_block(
        self, bare: str, block: re.Match[str], comment: str, where: SourceLocation | None
    ) -> BlockSymbol:
        number = int(block[2])
        if not 0 <= number <= 65535:
            raise SymbolError(f'symbol "{bare}": block number {number} is not 0…65535', where)
        sym = BlockSymbol(bare, block[1].upper(), number, comment.strip())
        self._blocks[bare.casefold()] = sym
        self._where[bare.casefold()] = where
        return sym

    def block(self, name: str) -> BlockSymbol | None:
        """The block symbol called ``name`` (quotes optional, case-insensitive), else None."""
        return self._blocks.get(_unquote(name).casefold())

    def block_names(self) -> dict[str, str]:
        """The block symbols as names → labels (``{"Data": "DB20"}``), for a compiler."""
        return {b.name: f"{b.kind}{b.number}" for b in self._blocks.values()}

    def db_number(self, name: str) -> int | None:
        """The number of the DB the symbol ``name`` names; None when the table does not
        have ``name``; SymbolError when ``name`` names another block or an operand."""
        block = self.block(name)
        if block is not None:
            if block.kind != "DB":
                raise SymbolError(f'"{block.name}" is {block.kind} {block.number}, not a DB')
            return block.number
        operand = self.lookup(name)
        if operand is not None:
            raise SymbolError(f'"{operand.name}" is the operand {operand.address}, not a DB')
        return None

    def lookup(self, name: str) -> Symbol | None:
        """The symbol called ``name`` (quotes optional, case-insensitive), else None."""
        return self._by_key.get(_unquote(name).casefold())

    def resolve(self, text: str, where: SourceLocation | None = None) -> Address:
        """A symbol (``"Start_button"``) or an absolute address text → Address.

        A quoted unknown name raises SymbolError; other text must parse as an address.
        """
        return self.resolve_typed(text, where)[0]

    def resolve_typed(self, text: str, where: SourceLocation | None = None) -> tuple[Address, str]:
        """Like ``resolve`` but also gives the type (declared, or the address's default)."""
        sym = self.lookup(text)
        if sym is not None:
            return sym.address, sym.type
        if text.strip().startswith('"'):
            raise SymbolError(f"unknown symbol {text.strip()}", where)
        addr = parse_address(text, where)
        return addr, default_type(addr)

    # ---- loading -------------------------------------------------------------------------

    @classmethod
    def from_file(cls, path: str | Path) -> SymbolTable:
        """Load a symbol file (format detected, see the module docstring)."""
        p = Path(path)
        return cls.from_text(read_utf8(p), file=str(p))

    @classmethod
    def from_text(cls, text: str, *, file: str = "<symbols>", line: int = 1) -> SymbolTable:
        """Parse symbol text; ``line`` is the line number of its first line (for errors)."""
        table = cls()
        table.load_text(text, file=file, line=line)
        return table

    def load_text(self, text: str, *, file: str = "<symbols>", line: int = 1) -> None:
        """Add every symbol in ``text`` (any of the accepted forms) to this table."""
        lines = text.splitlines()
        content = [ln for ln in lines if ln.strip() and not _is_comment(ln)]
        if not content:
            return
        first = content[0]
        if _COLON_ENTRY.match(first.strip()):
            self._load_colon(text, file, line)
        elif ";" in first:
            self._load_rows(lines, file, line, ";")
        else:
            self._load_rows(lines, file, line, ",")

    def _load_rows(self, lines: list[str], file: str, line0: int, sep: str) -> None:
        columns: tuple[int, int, int, int] | None = None
        for i, raw in enumerate(lines):
            where = SourceLocation(file, line0 + i, 1)
            if not raw.strip() or _is_comment(raw):
                continue
            try:
                row = next(csv.reader(io.StringIO(raw), delimiter=sep, skipinitialspace=True))
            except csv.Error as exc:  # a field over the csv module's limit (131,072 characters)
                raise SymbolError(f"cannot read the row: {exc}", where) from None
            row = [c.strip() for c in row]
            if columns is None and _looks_like_header(row):
                columns = _header_columns(row, where)
                continue
            n, a, t, c = columns or (0, 1, 2, 3)
            if len(row) <= max(n, a):
                raise SymbolError(f"expected name{sep} address{sep} type{sep} comment", where)
            kind = row[t] if t < len(row) else ""
            note = row[c] if c < len(row) else ""
            self.add(row[n], row[a], kind or None, note, where=where)

    def _load_colon(self, text: str, file: str, line0: int) -> None:
        pos = 0
        for m in _COLON_ENTRY.finditer(text):
            gap = _strip_comments(text[pos : m.start()])
            where = SourceLocation(file, line0 + text.count("\n", 0, m.start("name")), 1)
            if gap.strip(" \t\r\n;"):
                raise SymbolError(f"cannot read symbol entry {gap.strip()[:40]!r}", where)
            comment = _unquote(m["comment"] or "")
            self.add(m["name"], m["addr"], m["type"], comment, where=where)
            pos = m.end()
        rest = _strip_comments(text[pos:]).strip(" \t\r\n;")
        if rest:
            where = SourceLocation(file, line0 + text.count("\n", 0, pos), 1)
            raise SymbolError(f"cannot read symbol entry {rest[:40]!r}", where)


_COLON_ENTRY = re.compile(
    r'\s*(?P<name>"[^"]+")\s*:\s*(?P<addr>[^:;"\n]+?)\s*:\s*(?P<type>[A-Za-z_][\w\[\] ]*?)\s*'
    r"(?::\s*(?P<comment>'[^'\n]*'|\"[^\"\n]*\"))?\s*;"
)
_HEADER_WORDS = {
    "name": 0,
    "symbol": 0,
    "address": 1,
    "adresse": 1,
    "type": 2,
    "data type": 2,
    "datatype": 2,
    "datentyp": 2,
    "comment": 3,
    "kommentar": 3,
}


def _is_comment(line: str) -> bool:
    s = line.lstrip()
    return s.startswith("//") or s.startswith("#")


def _strip_comments(text: str) -> str:
    return "\n".join(ln.split("//", 1)[0] for ln in text.splitlines())


def _looks_like_header(row: list[str]) -> bool:
    return any(c.strip().lower() in ("address", "adresse") for c in row)


def _header_columns(row: list[str], where: SourceLocation) -> tuple[int, int, int, int]:
    found = {0: -1, 1: -1, 2: 99, 3: 99}
    for i, cell in enumerate(row):
        role = _HEADER_WORDS.get(cell.strip().lower())
        if role is not None and found[role] in (-1, 99):
            found[role] = i
    if found[0] < 0 or found[1] < 0:
        raise SymbolError("a symbol CSV header needs name/symbol and address columns", where)
    return found[0], found[1], found[2], found[3]
