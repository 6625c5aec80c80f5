"""Cross-references of a chart: where each operand is used and how, as TIA Portal's
cross-reference list (Tools > Cross-references) shows a tag's uses (docs/cli.md,
"s7graph xref").

Every contact and operand of a transition's condition, a step's interlock and supervision,
its action rows and the permanent instructions is one :class:`Use`: the operand as written
(a symbol, an address, an FB variable, ``S3.X``, ``T2.TT``, a block, a step an ON/OFF row
acts on, a DB a call passes to a BLOCK_DB input: ``DB 5``), the element it stands in (``T1
"Start"``, ``S2 "Clamp" interlock``, ``S2 "Clamp" row 3``, ``permanent before 1``), its
access (:data:`ACCESS` by qualifier; contacts and the operands of an expression are read),
and its place in the source. A symbol and its address are one operand (``"Start_button"
(I0.7)``, ``"Recipe" (DB5)``), with the chart's own ``SYMBOLS`` and a symbol table; the
symbols the chart declares and never uses are listed as TIA lists unused tags. With the
S7-SCL sources of the blocks beside the chart, their uses are listed too
(``steps.scl.xref``: the element is the block, ``OB 35``), as TIA's list spans every block
of a program. Pure: the parsed chart and sources in, data out.
"""

from __future__ import annotations

import functools
import re
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from typing import Final

from s7graph import sfb
from s7graph.engine.blocks import Decl
from s7graph.engine.errors import SourceLocation
from s7graph.engine.symbols import SymbolTable
from s7graph.sequencer.text.elements import DeclRef, Ref, RowRef, StepRef, TransitionRef
from s7graph.sequencer.text.model import (
    ActionRow,
    Assignment,
    BlockCall,
    Chart,
    Coil,
    Expr,
    Operand,
    PermanentInstruction,
    Step,
    StepAttr,
    StepTarget,
    TransAttr,
)
from s7graph.sequencer.text.names import db_argument, db_symbol
from s7graph.sequencer.text.walk import nodes
from s7graph.steps.scl import model as scl
from s7graph.steps.scl.xref import block_name, interfaces, scl_uses

__all__ = ["ACCESS", "CrossReferences", "Use", "block_references", "cross_references"]

ACCESS: Final[dict[str, str]] = {
    "N": "write",
    "D": "write",
    "L": "write",
    "S": "set",
    "R": "reset",
    "CALL": "call",
    "ON": "activate",
    "OFF": "deactivate",
    "CS": "counter",
    "CU": "counter",
    "CD": "counter",
    "CR": "counter",
    "TL": "timer",
    "TD": "timer",
    "TF": "timer",
    "TR": "timer",
}
"""How an action row uses its operand, by qualifier (an assignment's target is written, a
block call's instance DB is its instance); every contact and expression operand is read."""
_COIL: Final = {"=": "write", "S": "set", "R": "reset"}


@dataclass(frozen=True, slots=True)
class Use:
    """One use of ``operand`` (as shown: ``"Start" (I0.0)``, ``count``, ``S3.X``): in
    ``element`` (``ref`` the editor selects it by), with ``access``, written at ``loc``."""

    operand: str
    element: str
    access: str
    loc: SourceLocation
    ref: Ref | None = None

    @property
    def place(self) -> str:
        """``file:line:col``."""
        return str(self.loc)


@dataclass(frozen=True, slots=True)
class CrossReferences:
    """The uses of a chart's operands, each operand's in the order written, operands
    sorted by name; ``unused``: the symbols the chart declares and never uses."""

    uses: tuple[Use, ...]
    unused: tuple[str, ...]
    shown: Callable[[str], str] = field(default=str, repr=False, compare=False)
    """How an operand written so is shown (the chart's names: ``_Names.shown``)."""

    def operands(self) -> dict[str, list[Use]]:
        """The uses by operand, sorted by the operand as shown (case-insensitive)."""
        out: dict[str, list[Use]] = {}
        for use in self.uses:
            out.setdefault(use.operand, []).append(use)
        return dict(sorted(out.items(), key=lambda kv: kv[0].casefold()))

    def of(self, name: str) -> list[Use]:
        """The uses of the operand written ``name`` (a symbol with or without quotes, an
        address, a variable, a block: ``DB5`` or ``DB 5``; any case)."""
        bare = name.strip().strip('"')
        keys = {self.shown(bare).casefold(), self.shown(f'"{bare}"').casefold()}
        keys.add(self.shown(block_name(bare)).casefold())  # DB5 as DB 5; else as above
        return [u for u in self.uses if u.operand.casefold() in keys]


def cross_references(
    chart: Chart, symbols: SymbolTable | None = None, blocks: Sequence[scl.Source] = ()
) -> CrossReferences:
    """Every use of an operand in ``chart``, then in the S7-SCL sources ``blocks`` in their
    order; ``symbols`` (optional) a symbol table beside the chart's own ``SYMBOLS``, which
    come first."""
    names = _Names(chart, symbols)
    dbs = functools.partial(db_argument, chart=chart, symbols=symbols)
    uses = [
        Use(names.shown(text), element, access, loc, ref)
        for (element, ref), text, access, loc in _walk(chart, dbs)
    ]
    uses += _block_uses(names, blocks)
    used = {u.operand for u in uses}
    unused = tuple(
        s.name
        for s in chart.symbols
        if names.shown(f'"{s.name}"') not in used and s.name.casefold() not in names.read_dbs
    )
    return CrossReferences(tuple(uses), unused, names.shown)


def block_references(
    blocks: Sequence[scl.Source], symbols: SymbolTable | None = None
) -> CrossReferences:
    """Every use of an operand from outside the blocks of the S7-SCL sources ``blocks`` (a
    program without a chart), a symbol shown with its address from ``symbols``."""
    names = _Names(None, symbols)
    return CrossReferences(tuple(_block_uses(names, blocks)), (), names.shown)


def _block_uses(names: _Names, blocks: Sequence[scl.Source]) -> list[Use]:
    """The uses in ``blocks``; a system block called by its name in another case is shown
    by its own (``stp()`` calls ``"STP"``), unless a source defines a block so named."""
    if not blocks:  # the editor asks at every edit of a chart: no system tables for none
        return []
    params = dict(_system_params())
    system = {b.name.upper(): f'"{b.name}"' for b in sfb.SYSTEM_BLOCKS}
    for source in blocks:
        own = interfaces(source)
        params.update(own)
        for name in own:
            system.pop(name, None)
    return [
        Use(_system_name(names.shown(u.operand), u.access, system), u.block, u.access, u.loc)
        for source in blocks
        for u in scl_uses(source, params)
    ]


def _system_name(operand: str, access: str, system: dict[str, str]) -> str:
    if access != "call" or not operand.startswith('"'):
        return operand
    return system.get(operand.strip('"').upper(), operand)


_SECTIONS: Final = {Decl.IN: "VAR_INPUT", Decl.OUT: "VAR_OUTPUT", Decl.IN_OUT: "VAR_IN_OUT"}
_PIN_SECTIONS: Final = {
    sfb.Direction.IN: "VAR_INPUT",
    sfb.Direction.OUT: "VAR_OUTPUT",
    sfb.Direction.IN_OUT: "VAR_IN_OUT",
}


@functools.cache
def _system_params() -> dict[str, dict[str, str]]:
    """The parameters of the system blocks an S7-SCL source may call, by name and number
    (``CONT_C``, ``SFB41``): made once, copied by the caller before it adds to it. An ANY
    pin is an input of the engine's block (its pointer text) but used as the catalogue
    declares it: BLKMOV's DSTBLK, FILL's BLK are written."""
    out: dict[str, dict[str, str]] = {}
    for block in sfb.SYSTEM_BLOCKS:
        params = {v.name.upper(): _SECTIONS[v.decl] for v in block.interface if v.decl in _SECTIONS}
        entry = sfb.find(block.label)
        for pin in entry.pins if entry is not None else ():
            if pin.type == "ANY" and pin.name in params:
                params[pin.name] = _PIN_SECTIONS[pin.direction]
        out[block.name.upper()] = out[block.label.upper()] = params
    return out


class _Names:
    """How an operand is shown: a symbol with its address, an address with its symbol
    (the chart's own first), a variable of a DB by name with its DB's symbol and number
    (``"T_S2".Q (DB10.Q)``, however written), anything else as written."""

    def __init__(self, chart: Chart | None, table: SymbolTable | None) -> None:
        self.by_name: dict[str, tuple[str, str]] = {}
        blocks = table.block_names() if table is not None else {}
        for source in (
            [(s.name, s.address) for s in chart.symbols] if chart is not None else [],
            [(s.name, str(s.address)) for s in table or ()],
            [(n, b) for n, b in blocks.items() if b.startswith("DB")],  # "Recipe" (DB5)
        ):
            for name, address in source:
                self.by_name.setdefault(name.casefold(), (name, address))
        self.by_address = {
            address.replace(" ", "").upper(): name for name, address in self.by_name.values()
        }
        self.variables = {v.name.casefold(): v.name for v in chart.vars} if chart else {}
        own = [(s.name, db_symbol(s)) for s in chart.symbols] if chart is not None else []
        theirs = [(n, int(b[2:])) for n, b in blocks.items() if b.startswith("DB")]
        first: dict[str, tuple[str, int | None]] = {}
        for name, number in [*own, *theirs]:  # the chart's symbol of an operand hides one
            first.setdefault(name.casefold(), (name, number))
        self.dbs = {k: (n, db) for k, (n, db) in first.items() if db is not None}
        """The DB symbols by folded name: (name, number), the chart's first."""
        self.db_names: dict[int, str] = {}
        for name, number in self.dbs.values():
            self.db_names.setdefault(number, name)
        self.members: dict[tuple[int, str], str] = {}
        """Each DB variable read by name as first written (S7 names ignore case)."""
        self.read_dbs: set[str] = set()
        """The DB symbols (folded) a variable read by name was shown with."""

    def shown(self, text: str) -> str:
        member = self._member(text)
        if member is not None:
            return member
        name = text.strip('"')
        found = self.by_name.get(name.casefold())
        if found is not None and (text.startswith('"') or name.casefold() not in self.variables):
            return f'"{found[0]}" ({found[1]})'
        if text.startswith('"'):
            return text
        symbol = self.by_address.get(text.replace(" ", "").upper())
        if symbol is not None:
            return f'"{symbol}" ({self.by_name[symbol.casefold()][1]})'
        return self.variables.get(text.casefold(), text)

    def _member(self, text: str) -> str | None:
        """``"T_S2".Q`` and ``DB10.Q`` as one operand: ``"T_S2".Q (DB10.Q)`` when a DB
        symbol names DB 10, else ``DB10.Q``; None for any other text."""
        m = _MEMBER.fullmatch(text)
        if m is None:
            return None
        if m["db"] is not None:
            number = int(m["db"])
        elif (named := self.dbs.get(m["symbol"].casefold())) is not None:
            number = named[1]
        else:
            return text  # no DB symbol of that name: as written
        member = self.members.setdefault((number, m["member"].casefold()), m["member"])
        symbol = self.db_names.get(number)
        if symbol is None:
            return f"DB{number}.{member}"
        self.read_dbs.add(symbol.casefold())
        return f'"{symbol}".{member} (DB{number}.{member})'


_MEMBER: Final = re.compile(
    r'(?:"(?P<symbol>[^"]+)"|(?i:DB)\s*(?P<db>\d+))\s*\.\s*'
    r"(?!(?i:DB[XBWD]\s*\d))(?P<member>[A-Za-z_][A-Za-z0-9_]*)"
)
"""A variable of a DB read by name, as written: ``DB10.Q``, ``"T_S2".Q``."""


_Element = tuple[str, Ref | None]  # the element as shown, and as the editor selects it
_Found = tuple[_Element, str, str, SourceLocation]  # element, operand as written, access, place


_Dbs = Callable[[object], int | None]
"""The DB an actual parameter names (``DB5``, ``"Recipe"``), if any (``db_argument``)."""


def _walk(chart: Chart, dbs: _Dbs) -> Iterator[_Found]:
    for label, instructions in (("before", chart.before), ("after", chart.after)):
        ref = DeclRef("permanent", label)
        for k, instruction in enumerate(instructions, 1):
            yield from _permanent((f"permanent {label} {k}", ref), instruction, dbs)
    for sequence in chart.sequences:
        for step in sequence.steps:
            yield from _step(step, dbs)
        for t in sequence.transitions:
            element = (f"T{t.number} {_quoted(t.name)}".strip(), TransitionRef(t.number))
            yield from _read(element, t.condition)


def _step(step: Step, dbs: _Dbs) -> Iterator[_Found]:
    name, n = f"S{step.number} {_quoted(step.name)}".strip(), step.number
    yield from _read((f"{name} interlock", StepRef(n, "interlock")), step.interlock)
    yield from _read((f"{name} supervision", StepRef(n, "supervision")), step.supervision)
    for k, row in enumerate(step.actions, 1):
        yield from _row((f"{name} row {k} ({_row_head(row)})", RowRef(n, k - 1)), row, dbs)


def _row(element: _Element, row: ActionRow, dbs: _Dbs) -> Iterator[_Found]:
    operand = row.operand
    if isinstance(operand, Assignment):
        yield element, _text(operand.target), "write", operand.target.loc
        yield from _read(element, operand.expr)
    elif isinstance(operand, BlockCall):
        yield from _call(element, operand, dbs)
    elif isinstance(operand, StepTarget):
        target = "S_ALL" if operand.step is None else f"S{operand.step}"
        yield element, target, ACCESS.get(row.qualifier, row.qualifier.lower()), operand.loc
    else:
        yield element, _text(operand), ACCESS.get(row.qualifier, "write"), operand.loc
    yield from _read(element, row.value)


def _permanent(element: _Element, instruction: PermanentInstruction, dbs: _Dbs) -> Iterator[_Found]:
    if isinstance(instruction, Coil):
        yield element, _text(instruction.target), _COIL[instruction.kind], instruction.target.loc
        yield from _read(element, instruction.condition)
    elif isinstance(instruction, Assignment):
        yield element, _text(instruction.target), "write", instruction.target.loc
        yield from _read(element, instruction.expr)
    else:
        yield from _call(element, instruction, dbs)


def _call(element: _Element, call: BlockCall, dbs: _Dbs) -> Iterator[_Found]:
    """The block, its instance DB, each DB passed (``src := DB5``: an *argument* of the
    DB, which the block may read or write), the operands of the other parameters."""
    yield element, _block(call.kind, call.block), "call", call.loc
    if call.instance is not None:
        yield element, _block("DB", call.instance), "instance", call.loc
    for _, expr in call.inputs:
        number = dbs(expr)
        if number is not None:
            yield element, _block("DB", number), "argument", getattr(expr, "loc", call.loc)
        else:
            yield from _read(element, expr)
    for _, out in call.outputs:
        yield element, _text(out), "write", out.loc


def _read(element: _Element, expr: Expr | None) -> Iterator[_Found]:
    """Every operand of ``expr``, read, in the order written."""
    if expr is None:
        return
    for node in nodes(expr):
        if isinstance(node, Operand):
            yield element, _text(node), "read", node.loc
        elif isinstance(node, StepAttr):
            yield element, f"S{node.step}.{node.attr}", "read", node.loc
        elif isinstance(node, TransAttr):
            yield element, f"T{node.transition}.{node.attr}", "read", node.loc


def _text(operand: Operand) -> str:
    text = f'"{operand.name}"' if operand.quoted else operand.name
    return f"{text}.{operand.member}" if operand.member else text  # DB10.Q: a read by name


def _block(kind: str, block: int | str) -> str:
    return f"{kind} {block}" if isinstance(block, int) else f'"{block}"'


def _quoted(name: str) -> str:
    return f'"{name}"' if name else ""


def _row_head(row: ActionRow) -> str:
    head = f"{row.event} " if row.event else ""
    return head + row.qualifier + ("C" if row.interlocked else "")
