"""What an operand written in a chart stands for (docs/runtime.md, "The block runtime";
docs/semantics.md, "FB pins" and "Conditions").

``resolve_operand(op, chart, symbols)`` is pure: it reads the chart's declarations, the FB
pin table (``sequencer.params``, the one table of pins) and an optional symbol table, and
returns a :class:`Resolved`. The order of lookup is the rule:

* a quoted name (``"Start_button"``) is a symbol: the chart's own ``SYMBOLS`` section first,
  then the symbol table given; unknown → ``SymbolError``;
* an unquoted name is, in this order, an FB variable (``VAR``), an FB pin (``S_NO``,
  ``ERR_FLT`` ...; any parameter set — whether the chart's set has it is the compiler's
  business), or an absolute address (``I0.7``, ``MW10``, ``T5``, ``DB1.DBX0.0``; a malformed
  one raises ``AddressError`` at the operand's own column); anything else → ``SymbolError``.

Types: a symbol or variable has its declared type, a pin its table type, an absolute address
its natural type (``engine.symbols.default_type``: BOOL BYTE WORD DWORD TIMER COUNTER). An
absolute address is untyped memory: the validator lets a WORD address stand for INT and a
DWORD address for DINT, REAL or TIME (``is_untyped``).
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Final, Literal

from s7graph.engine.address import Address, Area, parse_address
from s7graph.engine.errors import SymbolError
from s7graph.engine.symbols import SymbolTable, default_type
from s7graph.sequencer.params import Direction, check_pin, pin
from s7graph.sequencer.text.model import BlockCall, Chart, Operand, SymbolDecl, VarDecl
from s7graph.sfb import catalogue

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
        for call in _calls(chart):
            if isinstance(call.instance, int):
                self.instances.setdefault(call.instance, call)


def _calls(chart: Chart) -> list[BlockCall]:
    """The chart's block calls: its action rows' and its permanent instructions'."""
    calls: list[object] = [r.operand for s in chart.all_steps() for r in s.actions]
    calls += [*chart.before, *chart.after]
    return [c for c in calls if isinstance(c, BlockCall)]


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


def resolve_operand(op: Operand, chart: Chart, symbols: SymbolTable | None = None) -> Resolved:
    """Resolve one operand (rule in the module docstring). Raises ``SymbolError`` for an
    unknown name and ``AddressError`` for a malformed address, both with ``op.loc``."""
    if op.member:
        return _member(op, chart, symbols)
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
        addr = parse_address(s.address, s.loc)
        return Resolved("symbol", addr, s.type.upper(), writable=addr.area is not Area.PI)
    if symbols is not None:
        sym = symbols.lookup(op.name)
        if sym is not None:
            writable = sym.address.area is not Area.PI
            return Resolved("symbol", sym.address, sym.type.upper(), writable=writable)
    raise SymbolError(f'unknown symbol "{op.name}"', op.loc)


class MemberError(SymbolError):
    """A variable of an instance DB read by name (``DB10.Q``) the chart cannot read (E048)."""


def member_text(op: Operand) -> str:
    """An instance DB's variable as written: ``DB10.Q``, ``"T_S2".Q``."""
    return f'"{op.name}".{op.member}' if op.quoted else f"{op.name}.{op.member}"


def _member(op: Operand, chart: Chart, symbols: SymbolTable | None) -> Resolved:
    """``DB10.Q`` / ``"T_S2".Q`` (S7-SCL's structured access to a data block): an output or
    in-out of the block whose instance DB one of the chart's calls names (by number; a
    symbol of the symbol table given may name that DB). Raises ``MemberError``."""
    text = member_text(op)
    if op.quoted:
        try:
            db = symbols.db_number(op.name) if symbols is not None else None
        except SymbolError as exc:
            raise MemberError(f"{text}: {exc.message}", op.loc) from None
        if db is None:
            raise MemberError(f'{text}: no DB symbol "{op.name}" in the symbol table', op.loc)
    else:
        db = int(op.name[2:])
    call = _declarations(chart).instances.get(db)
    if call is None:
        raise MemberError(
            f"{text}: DB{db} is not an instance DB of this chart's calls "
            f'(CALL "TON", DB {db} (...) names one)',
            op.loc,
        )
    entry = catalogue.find(f"{call.kind}{call.block}")
    if entry is None:
        label = f"{call.kind}{call.block}" if call.kind else f'"{call.block}"'
        raise MemberError(
            f"{text}: DB{db} is the instance DB of {label}; only a system block's variables "
            "are read by name: take the output out with the call's => (Q => x)",
            op.loc,
        )
    pin = entry.pin(op.member)
    if pin is None or (pin.is_input and not pin.is_output):
        outs = ", ".join(p.name for p in entry.outputs) or "none"
        why = "is an input of" if pin is not None else "is not a variable of"
        raise MemberError(
            f"{text}: {op.member} {why} {entry.key} {entry.name} (its outputs: {outs})", op.loc
        )
    return Resolved("member", None, pin.type, writable=False, db=db, member=pin.name)
