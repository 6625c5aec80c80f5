"""What an operand written in a chart stands for (docs/runtime.md, "The block runtime";
docs/semantics.md, "FB pins" and "Conditions").

``resolve_operand(op, chart, symbols, blocks=…)`` is pure: it reads the chart's
declarations, the FB pin table (``sequencer.params``, the one table of pins), an optional
symbol table and the program's user blocks (their interfaces, when known), and returns a
:class:`Resolved`. The order of lookup is the rule:

* a quoted name (``"Start_button"``) is a symbol: the chart's own ``SYMBOLS`` section first,
  then the symbol table given; unknown → ``SymbolError``;
* an unquoted name is, in this order, an FB variable (``VAR``), an FB pin (``S_NO``,
  ``ERR_FLT`` ...; any parameter set — whether the chart's set has it is the compiler's
  business), or an absolute address (``I0.7``, ``MW10``, ``T5``, ``DB1.DBX0.0``; a malformed
  one raises ``AddressError`` at the operand's own column); anything else → ``SymbolError``;
* a name with a member (``DB10.Q``, ``"T_S2".Q``: the DB by its chart or table symbol) is a
  variable of an instance DB a call of the chart names: an output or in/out of a system
  block, or — given the program's ``blocks`` — an output, in/out or static variable of a
  user FB; anything else → ``MemberError``.

Types: a symbol or variable has its declared type, a pin its table type, an absolute address
its natural type (``engine.symbols.default_type``: BOOL BYTE WORD DWORD TIMER COUNTER). An
absolute address is untyped memory: the validator lets a WORD address stand for INT and a
DWORD address for DINT, REAL or TIME (``is_untyped``).
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Final, Literal

from s7graph.engine.address import Address, Area, parse_address
from s7graph.engine.datatypes import string_chars
from s7graph.engine.errors import SymbolError
from s7graph.engine.symbols import SymbolTable, default_type
from s7graph.sequencer.checks.interfaces import ProgramBlocks
from s7graph.sequencer.params import Direction, check_pin, pin
from s7graph.sequencer.text.call_sites import call_sites
from s7graph.sequencer.text.model import BlockCall, Chart, Operand, SymbolDecl, VarDecl
from s7graph.sfb import catalogue
from s7graph.steps.operands import TYPE_BYTES

Kind = Literal["address", "symbol", "var", "pin", "member"]

# The shape of an absolute address (as the grammar's ADDRESS terminal, blanks removed).
ADDRESS_SHAPE: Final = re.compile(
    r"(?i)(DB\d+\.DB[XBWD]\d+(\.\d+)?|P[IQEA][XBWD]?\d+(\.\d+)?|[IQEAML][XBWD]?\d+(\.\d+)?"
    r"|[TCZ]\d+)"
)


@dataclass(frozen=True, slots=True)
class Resolved:
    """An operand resolved: ``kind`` address | symbol | var | pin; ``address`` for addresses
    and symbols (None for FB variables and pins); ``type`` the S7 type name (upper case);
    ``writable`` is False for FB output pins (the FB itself writes them) and for the
    peripheral inputs (PI: the modules write them). A ``member`` (``DB10.Q``) names its
    instance DB's number (``db``) and variable (``member``, as the block spells it); the
    chart only reads it."""

    kind: Kind
    address: Address | None
    type: str
    writable: bool = True
    db: int | None = None
    member: str = ""

    @property
    def is_untyped(self) -> bool:
        """An absolute address: its width, not a declaration, gives the type."""
        return self.kind == "address"


def looks_like_address(name: str) -> bool:
    """The text has the shape of an absolute address (it may still be out of range)."""
    return ADDRESS_SHAPE.fullmatch(re.sub(r"\s+", "", name)) is not None


class _Declared:
    """A chart's FB variables by upper-case name and its symbols by case-folded name, the
    first of each name (a second one is an error of its own, E013)."""

    def __init__(self, chart: Chart) -> None:
        self.chart = chart
        self.vars: dict[str, VarDecl] = {}
        for v in chart.vars:
            self.vars.setdefault(v.name.upper(), v)
        self.symbols: dict[str, SymbolDecl] = {}
        for s in chart.symbols:
            self.symbols.setdefault(s.name.casefold(), s)
        self.instances: dict[int, BlockCall] = {}
        """The instance DBs the chart's calls name: number → the first call naming it."""
        for site in call_sites(chart):
            if isinstance(site.call.instance, int):
                self.instances.setdefault(site.call.instance, site.call)


_declared: list[_Declared] = []  # the chart resolved last (its operands come in a row)


def _declarations(chart: Chart) -> _Declared:
    """The declarations of ``chart``, indexed once per chart (not per operand: a chart of
    thousands of sequencers has thousands of variables). Only an index of the chart's own
    declarations is remembered, so ``resolve_operand`` stays a function of its arguments."""
    if _declared and _declared[0].chart is chart:
        return _declared[0]
    found = _Declared(chart)
    _declared[:] = [found]
    return found


def instance_calls(chart: Chart) -> Mapping[int, BlockCall]:
    """The instance DBs ``chart``'s calls name: number → the first call naming it."""
    return _declarations(chart).instances


def resolve_operand(
    op: Operand,
    chart: Chart,
    symbols: SymbolTable | None = None,
    *,
    blocks: ProgramBlocks | None = None,
) -> Resolved:
    """Resolve one operand (rule in the module docstring). Raises ``SymbolError`` for an
    unknown name and ``AddressError`` for a malformed address, both with ``op.loc``.
    ``blocks``: the program's user blocks, whose instance DBs' variables a chart reads by
    name (``"Motor_DB".Running``)."""
    if op.member:
        return _member(op, chart, symbols, blocks)
    if op.quoted:
        return _symbol(op, chart, symbols)
    key = op.name.upper()
    v = _declarations(chart).vars.get(key)
    if v is not None:
        return Resolved("var", None, v.type.upper())
    p = pin(op.name)
    if p is not None:  # only a pin of the chart's parameter set exists in its FB
        p = check_pin(op.name, chart.options.parameters, op.loc)
        return Resolved("pin", None, p.type, writable=p.direction is Direction.IN)
    if looks_like_address(op.name):
        addr = parse_address(op.name, op.loc)
        return Resolved("address", addr, default_type(addr), writable=addr.area is not Area.PI)
    hint = ""
    if (symbols is not None and symbols.lookup(op.name) is not None) or any(
        s.name.upper() == key for s in chart.symbols
    ):
        hint = f'; symbols are written in double quotes: "{op.name}"'
    raise SymbolError(
        f"unknown name {op.name!r}: not an FB variable, FB pin or address{hint}", op.loc
    )


def _symbol(op: Operand, chart: Chart, symbols: SymbolTable | None) -> Resolved:
    s = _declarations(chart).symbols.get(op.name.casefold())
    if s is not None:
        db = db_symbol(s)
        if db is not None:
            raise SymbolError(
                f'"{op.name}" is DB {db}, not an operand: its variables are read by name '
                f'("{op.name}".name)',
                op.loc,
            )
        addr = parse_address(s.address, s.loc)
        return Resolved("symbol", addr, s.type.upper(), writable=addr.area is not Area.PI)
    if symbols is not None:
        sym = symbols.lookup(op.name)
        if sym is not None:
            writable = sym.address.area is not Area.PI
            return Resolved("symbol", sym.address, sym.type.upper(), writable=writable)
    raise SymbolError(f'unknown symbol "{op.name}"', op.loc)


_DB_SYMBOL: Final = re.compile(r"(?i)DB\s*(\d+)")


def db_symbol(s: SymbolDecl) -> int | None:
    """The number of the DB a chart's symbol names (``"T_S2" : DB10 : SFB4;``), None for a
    symbol of an operand."""
    m = _DB_SYMBOL.fullmatch(s.address.strip())
    return int(m[1]) if m else None


def db_argument(e: object, chart: Chart | None, symbols: SymbolTable | None) -> int | None:
    """The number of the DB an actual parameter of a call names — ``DB5`` (unless the chart
    has a variable so named), or a DB symbol: the chart's ``SYMBOLS`` first, then those of
    ``symbols`` — as a BLOCK_DB input of S7-SCL takes a DB; None for anything else."""
    if not isinstance(e, Operand) or e.member:
        return None
    if not e.quoted:
        m = _DB_SYMBOL.fullmatch(e.name.strip())
        declared = chart is not None and e.name.upper() in _declarations(chart).vars
        return int(m[1]) if m and not declared else None
    own = _declarations(chart).symbols.get(e.name.casefold()) if chart is not None else None
    if own is not None:
        return db_symbol(own)
    block = symbols.block(e.name) if symbols is not None else None
    return block.number if block is not None and block.kind == "DB" else None


class MemberError(SymbolError):
    """A variable of an instance DB read by name (``DB10.Q``) the chart cannot read (E048)."""


def member_text(op: Operand) -> str:
    """An instance DB's variable as written: ``DB10.Q``, ``"T_S2".Q``."""
    return f'"{op.name}".{op.member}' if op.quoted else f"{op.name}.{op.member}"


def _member(
    op: Operand, chart: Chart, symbols: SymbolTable | None, blocks: ProgramBlocks | None
) -> Resolved:
    """``DB10.Q`` / ``"T_S2".Q`` (S7-SCL's structured access to a data block): an output or
    in-out of the block whose instance DB one of the chart's calls names (by number; a DB
    symbol of the chart's ``SYMBOLS``, then of the symbol table given, may name that DB) —
    of a system block, or of a user FB of the program's ``blocks``, whose static variables
    are read too. Raises ``MemberError``."""
    text = member_text(op)
    db = db_number(op, chart, symbols) if op.quoted else int(op.name[2:])
    call = _declarations(chart).instances.get(db)
    if call is None:
        raise MemberError(
            f"{text}: DB{db} is not an instance DB of this chart's calls "
            f'(CALL "TON", DB {db} (...) names one)',
            op.loc,
        )
    entry = catalogue.find(f"{call.kind}{call.block}")
    if entry is None:
        return _user_member(op, db, call, blocks)
    pin = entry.pin(op.member)
    if pin is None or (pin.is_input and not pin.is_output):
        outs = ", ".join(p.name for p in entry.outputs) or "none"
        why = "is an input of" if pin is not None else "is not a variable of"
        raise MemberError(
            f"{text}: {op.member} {why} {entry.key} {entry.name} (its outputs: {outs})", op.loc
        )
    return Resolved("member", None, pin.type, writable=False, db=db, member=pin.name)


def db_number(op: Operand, chart: Chart, symbols: SymbolTable | None) -> int:
    """The DB a quoted name before a member names: the chart's ``SYMBOLS`` first, then the
    symbol table given; ``MemberError`` when neither names a DB so."""
    text = member_text(op)
    own = _declarations(chart).symbols.get(op.name.casefold())
    if own is not None:
        db = db_symbol(own)
        if db is None:
            raise MemberError(
                f'{text}: "{own.name}" is the operand {own.address}, not a DB', op.loc
            )
        return db
    try:
        number = symbols.db_number(op.name) if symbols is not None else None
    except SymbolError as exc:
        raise MemberError(f"{text}: {exc.message}", op.loc) from None
    if number is None:
        raise MemberError(
            f'{text}: no DB symbol "{op.name}" in the chart\'s SYMBOLS or the symbol table',
            op.loc,
        )
    return number


_READABLE: Final = frozenset((*TYPE_BYTES, "DATE_AND_TIME", "STRING"))
"""The types of a user FB's variable a chart reads by name: those of its own variables."""


def _user_member(op: Operand, db: int, call: BlockCall, blocks: ProgramBlocks | None) -> Resolved:
    """A variable of a user FB's instance DB: an output, in/out or static variable of the
    FB's interface in the program's ``blocks`` (docs/chart-format.md)."""
    text = member_text(op)
    label = f"{call.kind}{call.block}" if call.kind else f'"{call.block}"'
    block = blocks.find(call.kind, call.block) if blocks is not None else None
    if block is None:
        why = (
            f"; {label} is not in the program's blocks ({blocks.sources}):"
            if blocks is not None
            else ", whose variables are read by name only with the program's blocks "
            "(--blocks): give them, or"
        )
        raise MemberError(
            f"{text}: DB{db} is the instance DB of {label}{why} take the output out with the "
            "call's => (Q => x)",
            op.loc,
        )
    fb = block.label if block.name.upper() == block.label else f'{block.label} "{block.name}"'
    if block.kind != "FB":
        raise MemberError(f"{text}: {fb} is an {block.kind}: it has no instance DB", op.loc)
    var = block.variable(op.member)
    if var is None or var.direction == "IN":
        have = [p.name for p in (*block.pins, *block.statics) if p.direction != "IN"]
        why = "is an input of" if var is not None else "is not a variable of"
        raise MemberError(
            f"{text}: {op.member} {why} {fb} (its outputs and static variables: "
            f"{', '.join(have) or 'none'})",
            op.loc,
        )
    t = var.type.upper()
    t = "DATE_AND_TIME" if t == "DT" else t
    if t not in _READABLE and string_chars(t) is None:
        kind = "an ARRAY, a STRUCT or a multi-instance" if t == "OBJECT" else t
        raise MemberError(
            f"{text}: {var.name} of {fb} is {kind}; a chart reads a variable of an "
            "elementary type by name",
            op.loc,
        )
    return Resolved("member", None, t, writable=False, db=db, member=var.name)
