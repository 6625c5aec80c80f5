"""An instance DB's variables a chart reads by name (``DB10.Q``, ``"T_S2".Q``: S7-SCL's
structured access to a data block), as the exporters see them: which DB a read names,
which symbol names a DB, and the DB symbols an export carries — and an import, of those
it carried, declares: those the symbol table given does not hold (docs/import-export.md).

A DB is named by a symbol of the chart's ``SYMBOLS`` (``"T_S2" : DB10 : SFB4;``) first,
then by a DB symbol of the symbol table given, as the chart's own names resolve
(``sequencer.text.names``); the instance DB's block is that of the chart's first call
naming it.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping

from s7graph.engine.address import parse_address
from s7graph.engine.errors import AddressError, SourceLocation
from s7graph.engine.symbols import SymbolTable
from s7graph.sequencer.text.call_sites import call_sites
from s7graph.sequencer.text.model import BlockCall, Chart, Operand, SymbolDecl
from s7graph.sequencer.text.names import (
    MemberError,
    db_argument,
    db_number,
    db_symbol,
    instance_calls,
    member_text,
)
from s7graph.sequencer.text.walk import nodes
from s7graph.sfb import catalogue

__all__ = ["DbReads", "member_text", "not_in_table", "user_fb_reads"]


class DbReads:
    """The instance DBs of one chart's calls and the DB symbols naming them."""

    def __init__(self, chart: Chart, table: SymbolTable | None) -> None:
        self.chart = chart
        self.table = table
        self.calls: Mapping[int, BlockCall] = instance_calls(chart)
        self.own: dict[str, tuple[SymbolDecl, int]] = {}
        for s in chart.symbols:
            number = db_symbol(s)
            if number is not None:
                self.own.setdefault(s.name.casefold(), (s, number))
        self._named: dict[int, str] = {}
        """The DB symbols naming DBs by number: the chart's first, then the table's."""
        for s, n in self.own.values():
            self._named.setdefault(n, s.name)
        names = table.block_names().items() if table is not None else ()
        for name, label in names:
            if label.startswith("DB") and label[2:].isdigit():
                self._named.setdefault(int(label[2:]), name)

    def db(self, op: Operand) -> int:
        """The DB number of a read ``op``; ``ValueError`` naming its place when no call of
        the chart names that instance DB (a chart ``check`` refuses, E048)."""
        number: int | None
        try:
            number = db_number(op, self.chart, self.table) if op.quoted else int(op.name[2:])
        except MemberError:
            number = None
        if number is None or number not in self.calls:
            why = (
                f'no DB symbol "{op.name}"'
                if number is None
                else f"DB{number} is no instance DB of this chart's calls"
            )
            raise ValueError(f"{op.loc}: {member_text(op)}: {why} (s7graph check says more)")
        return number

    def name(self, number: int) -> str | None:
        """The DB symbol naming DB ``number``: the chart's, else the symbol table's."""
        return self._named.get(number)

    def block(self, number: int) -> str:
        """The block whose instance DB ``number`` is, as a chart's type column writes it
        (``SFB4`` for ``CALL "TON"`` too, ``FB17``, a user block called by name as named)."""
        call = self.calls[number]
        label = f"{call.kind}{call.block}" if call.kind else str(call.block)
        entry = catalogue.find(label)  # CALL "TON": SFB4, as STEP 7's symbol table says
        return entry.key if entry is not None else label

    def carried(self, by_symbol: bool = False) -> list[SymbolDecl]:
        """The DB symbols an export carries: every one of the chart's ``SYMBOLS``, then
        those of the symbol table a read names (``"T_S2" : DB10 : SFB4``) — with
        ``by_symbol``, also those a read by number is written with (``DB10.Q``) — and those
        a call passes to a BLOCK_DB input (``src := "Other"``: ``"Other" : DB6 : DB6``)."""
        out = [s for s, _ in self.own.values()]
        for site in call_sites(self.chart):
            for _, e in site.call.inputs:
                number = db_argument(e, self.chart, self.table)
                if number is None or not isinstance(e, Operand) or self.table is None:
                    continue
                found = self.table.block(e.name) if e.quoted else None
                if found is not None and all(s.name.casefold() != e.name.casefold() for s in out):
                    out.append(SymbolDecl(found.name, f"DB{number}", f"DB{number}"))
        for op in nodes(self.chart):
            if not (isinstance(op, Operand) and op.member and (op.quoted or by_symbol)):
                continue
            number = self.db(op)
            name = op.name if op.quoted else self.name(number)
            found = self.table.block(name) if self.table is not None and name else None
            if found is None or any(s.name.casefold() == found.name.casefold() for s in out):
                continue
            out.append(SymbolDecl(found.name, f"DB{number}", self.block(number)))
        return out


def not_in_table(decls: Iterable[SymbolDecl], table: SymbolTable | None) -> tuple[SymbolDecl, ...]:
    """``decls`` but those the symbol table given holds already — the same name, in any
    case (the table holds a name once regardless of case, as STEP 7's symbol editor does),
    at the same address, or a DB symbol naming the same DB: they stay in the table, as for
    a chart exported and imported with it."""
    if table is None:
        return tuple(decls)
    return tuple(s for s in decls if not _in_table(s, table))


def _in_table(s: SymbolDecl, table: SymbolTable) -> bool:
    number = db_symbol(s)
    if number is not None:
        block = table.block(s.name)
        return block is not None and block.kind == "DB" and block.number == number
    found = table.lookup(s.name)
    try:
        return found is not None and parse_address(s.address, s.loc) == found.address
    except AddressError:
        return False


def user_fb_reads(chart: Chart, table: SymbolTable | None) -> set[SourceLocation]:
    """The places of the reads of a user FB's instance DB (``"Motor_DB".Running`` with
    ``CALL FB 17, DB 12``): only the program's blocks say whether the FB has that
    variable, and an import has none (``s7graph check --blocks`` checks them)."""
    reads = DbReads(chart, table)
    out: set[SourceLocation] = set()
    for op in nodes(chart):
        if isinstance(op, Operand) and op.member:
            try:
                number = reads.db(op)
            except ValueError:
                continue
            if catalogue.find(reads.block(number)) is None:
                out.add(op.loc)
    return out
