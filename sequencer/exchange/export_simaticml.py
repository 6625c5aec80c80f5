"""Write a chart as a TIA Portal Openness SimaticML GRAPH FB (``Graph/v5``, GraphVersion
6.0, the interface in ``Interface/v4``, as TIA V16 exports and V20 imports it).

GRAPH to GRAPH: steps and transitions keep numbers and names (an unnamed one gets TIA's
default, ``Step3``, ``Trans3``, which the import reads back as no name for a transition);
a step with several transitions leaving it opens an ``AltBegin`` branch (``Out`` 0 is the
first written, the highest priority), a transition to several steps a ``SimBegin``, a
transition from several steps closes a ``SimEnd``, a step reached forward by several
transitions an ``AltEnd``; a transition that leads back up, or into another sequence, is a
``Jump`` link, ``TO STOP`` an ``EndConnection``. Conditions, interlocks, supervisions
(with the step's message text as alarm text) and bit coils of the permanent instructions
are LAD networks (``exchange.flgnet``); action rows are ``Action`` elements with the row's
text as tokens (``"Tag"``, ``#variable``, ``%Q0.3``). Symbols are global tags with their
address as informative data. What a GRAPH block has no field for — the instance DB number,
``ORDER``, ``ACK_FORCES_SWITCH``, the DB symbols (``"T_S2" : DB10 : SFB4``) — is kept in
the block comment (``s7graph: …``), which the importer reads. An instance DB's variable read
by name is a global access to a DB member, as TIA writes one (``"T_S2".Q``; ``DB10.Q`` by
the DB's symbol, reported, and refused when DB 10 has none). ``XOR`` in a condition is
drawn as (a AND NOT b) OR (NOT a AND b). A permanent CALL is a LAD ``Call`` box, a
permanent assignment of an operand or constant to a non-bit a ``Move`` box; one of an
arithmetic expression has no form here: a ``ValueError`` naming its place, as for every
chart part this export cannot write. A DB a call passes to a BLOCK_DB input (``src :=
DB5``, ``src := "Recipe"``) is TIA's access to a DB as a whole: area DB, type Block_DB, the
DB's number and no bit offset (TIA Portal Openness system manual, "Major changes", the
``Address`` node of ``SW.PlcBlocks.Access.xsd``: ``OPN %DB12``), under its symbol when it
has one, the address then informative.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from xml.sax.saxutils import escape, quoteattr

from s7graph.engine.address import Address, parse_address
from s7graph.engine.errors import AddressError, SourceLocation
from s7graph.engine.symbols import SymbolTable
from s7graph.sequencer.checks.diagnostics import Diagnostic
from s7graph.sequencer.exchange.db_reads import DbReads, member_text
from s7graph.sequencer.exchange.flgnet import write_call, write_move, write_network
from s7graph.sequencer.exchange.problems import Problems
from s7graph.sequencer.exchange.shape import shape_of
from s7graph.sequencer.params import Direction, pins_for
from s7graph.sequencer.text.format import format_expr, format_row, quote, row_body
from s7graph.sequencer.text.model import (
    ActionRow,
    Assignment,
    BlockCall,
    Chart,
    Coil,
    Const,
    Expr,
    Operand,
    PermanentInstruction,
    Sequence,
    Step,
    StepAttr,
    TransAttr,
    Transition,
)
from s7graph.sequencer.text.names import db_argument

__all__ = ["S7GRAPH_COMMENT", "default_name", "export_simaticml"]

S7GRAPH_COMMENT = "s7graph:"
_GRAPH_NS = "http://www.siemens.com/automation/Openness/SW/NetworkSource/Graph/v5"
_IFACE_NS = "http://www.siemens.com/automation/Openness/SW/Interface/v4"
_TIA = {
    "BOOL": "Bool",
    "BYTE": "Byte",
    "WORD": "Word",
    "DWORD": "DWord",
    "INT": "Int",
    "DINT": "DInt",
    "REAL": "Real",
    "TIME": "Time",
    "S5TIME": "S5Time",
    "DATE": "Date",
    "TIME_OF_DAY": "Time_Of_Day",
    "CHAR": "Char",
    "DATE_AND_TIME": "Date_And_Time",
}
_AREA = {"I": "Input", "Q": "Output", "M": "Memory"}
_IDENT = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


def call_naming(c: BlockCall) -> str:
    """How a call names its block and instance DB, as X012 says it: ``the block and its
    instance DB by number`` (``CALL FB 17, DB 10``), ``the block by name, its instance DB by
    number`` (``CALL "TON", DB 10``) …, and what to do in TIA, which calls blocks and DBs by
    their symbolic names."""
    block = "number" if c.kind else "name"
    db = {int: "number", str: "name"}.get(type(c.instance), "")
    if not db:
        words = f"the block by {block}"
    elif db == block:
        words = f"the block and its instance DB by {block}"
    else:
        words = f"the block by {block}, its instance DB by {db}"
    if "number" in (block, db):
        return f"{words}; TIA calls blocks and DBs by their symbolic names: rename them there"
    return f"{words}; TIA calls them by those symbolic names: its project must have them"


def default_name(what: str, number: int) -> str:
    """The name TIA gives a ``step`` or ``transition`` of that number that nobody named
    (``Step3``, ``Trans3``): what the export writes for an unnamed one, and what the import
    reads back as no name for a transition."""
    return f"{'Step' if what == 'step' else 'Trans'}{number}"


def _tia_type(t: str) -> str:
    if t.startswith("STRING"):
        return "String" + t[6:]
    return _TIA.get(t, t)


def _text(text: str) -> str:
    return f'<MultiLanguageText Lang="en-US">{escape(text)}</MultiLanguageText>'


class _Export:
    def __init__(self, chart: Chart, symbols: SymbolTable | None) -> None:
        self.chart = chart
        self.table = symbols
        self.p = Problems(chart.file)
        self.reads = DbReads(chart, symbols)
        self.warned_call = False
        self.step_names: dict[int, str] = {}
        self.trans_names: dict[int, str] = {}
        self._unique_names()

    def _unique_names(self) -> None:
        """A name per step and transition, unique in the block as TIA requires (they are
        members of its interface): a name taken before gets ``_2``, ``_3`` … (X013)."""
        taken: set[str] = set()
        elements: list[tuple[Step | Transition, str, dict[int, str]]] = [
            (s, "step", self.step_names) for s in self.chart.all_steps()
        ]
        elements += [(t, "transition", self.trans_names) for t in self.chart.all_transitions()]
        for e, what, names in elements:
            name = e.name or default_name(what, e.number)
            unique, k = name, 1
            while unique.casefold() in taken:
                k += 1
                unique = f"{name}_{k}"
            if unique != name:
                self.p.warn(
                    "X013",
                    f"{what} {what[0].upper()}{e.number} {name!r} is named {unique!r}: TIA "
                    "takes a name once per block (steps and transitions alike)",
                    e.loc,
                )
            taken.add(unique.casefold())
            names[e.number] = unique

    # ------------------------------------------------------------ operands

    def address_of(self, name: str) -> tuple[str, str] | None:
        """(S7 address, type) of a symbol, from the chart or the table."""
        for s in self.chart.symbols:
            if s.name.casefold() == name.casefold():
                return s.address, s.type
        sym = self.table.lookup(name) if self.table is not None else None
        return (str(sym.address), sym.type) if sym is not None else None

    def access(self, e: Expr, uid: str) -> str:
        if isinstance(e, Const):
            ctype = _TIA.get(e.type, e.type)
            return (
                f'<Access Scope="LiteralConstant" UId="{uid}"><Constant><ConstantType>{ctype}'
                f"</ConstantType><ConstantValue>{escape(e.text)}</ConstantValue></Constant>"
                "</Access>"
            )
        if isinstance(e, StepAttr | TransAttr):
            owner = (
                self.step_names.get(e.step, default_name("step", e.step))
                if isinstance(e, StepAttr)
                else self.trans_names.get(e.transition, default_name("transition", e.transition))
            )
            return (
                f'<Access Scope="LocalVariable" UId="{uid}"><Symbol><Component '
                f'Name={quoteattr(owner)} /><Component Name="{e.attr}" /></Symbol></Access>'
            )
        if not isinstance(e, Operand):
            raise _Refused(
                f"{_loc(e)}: {format_expr(e)}: an operand LAD draws is a tag, a variable or a "
                "constant, not an expression"
            )
        if e.member:
            return self.member_access(e, uid)
        if not e.quoted and not any(v.name.upper() == e.name.upper() for v in self.chart.vars):
            addr = _address(e)
            return (
                f'<Access Scope="GlobalVariable" UId="{uid}"><Address Area='
                f'"{_AREA.get(str(addr.area), str(addr.area))}" Type="{_address_type(e.name)}"'
                f' BitOffset="{addr.byte * 8 + addr.bit}" /></Access>'
            )
        if not e.quoted:
            return (
                f'<Access Scope="LocalVariable" UId="{uid}"><Symbol><Component '
                f"Name={quoteattr(e.name)} /></Symbol></Access>"
            )
        info = ""
        found = self.address_of(e.name)
        if found is not None and found[0][0] in _AREA:
            addr = _address(Operand(found[0], False, e.loc))
            info = (
                f'<Address Area="{_AREA[found[0][0]]}" Type="{_tia_type(found[1])}" '
                f'BitOffset="{addr.byte * 8 + addr.bit}" Informative="true" />'
            )
        comps = "".join(f"<Component Name={quoteattr(p)} />" for p in _path(e.name))
        return f'<Access Scope="GlobalVariable" UId="{uid}"><Symbol>{comps}{info}</Symbol></Access>'

    def member_access(self, e: Operand, uid: str) -> str:
        """An instance DB's variable read by name as TIA writes a DB member: a global
        access by the DB's name and the variable's (``"T_S2".Q``). ``DB10.Q`` goes by the
        DB symbol naming DB 10 (X013); without one it is refused, naming its place."""
        number = self.reads.db(e)
        name = e.name if e.quoted else self.reads.name(number)
        if name is None:
            raise _Refused(
                f"{e.loc}: {member_text(e)}: TIA reads a DB's variables by the DB's name, "
                f"and DB {number} has none: name it in the chart's SYMBOLS "
                f'("Timer_{number}" : DB{number} : {self.reads.block(number)};) or in the '
                "symbol table"
            )
        if not e.quoted:
            self.p.warn(
                "X013",
                f'{member_text(e)} is written "{name}".{e.member}: TIA reads a DB\'s '
                "variables by the DB's name",
                e.loc,
            )
        return (
            f'<Access Scope="GlobalVariable" UId="{uid}"><Symbol><Component Name='
            f"{quoteattr(name)} /><Component Name={quoteattr(e.member)} /></Symbol></Access>"
        )

    def passed_db(self, e: Expr) -> int | None:
        """The number of the DB a call's actual parameter names (``DB5``, ``"Recipe"``: the
        chart's ``SYMBOLS`` first, then the symbol table's), None for any other."""
        return db_argument(e, self.chart, self.table)

    def argument(self, e: Expr, uid: str) -> str:
        """A call's actual parameter: a DB passed (``src := DB5``) as TIA writes a DB as a
        whole — ``Address`` area DB, type Block_DB, its number, no bit offset; under the
        DB's symbol, that address informative — any other operand as :meth:`access` does."""
        number = self.passed_db(e)
        if number is None or not isinstance(e, Operand):
            return self.access(e, uid)
        address = f'<Address Area="DB" Type="Block_DB" BlockNumber="{number}"'
        if not e.quoted:
            return f'<Access Scope="GlobalVariable" UId="{uid}">{address} /></Access>'
        return (
            f'<Access Scope="GlobalVariable" UId="{uid}"><Symbol><Component '
            f'Name={quoteattr(e.name)} />{address} Informative="true" /></Symbol></Access>'
        )

    def spell(self, e: Expr) -> str | None:
        """An operand in a TIA action's text."""
        if isinstance(e, Operand) and e.quoted:
            parts = _path(e.name)
            return '"' + parts[0] + '"' + "".join("." + p for p in parts[1:])
        if isinstance(e, Operand) and any(
            v.name.upper() == e.name.upper() for v in self.chart.vars
        ):
            return "#" + e.name
        if isinstance(e, Operand):
            return "%" + e.name
        return None

    # ------------------------------------------------------------ elements

    def network(self, cond: Expr | None, coil: str, target: Expr | None = None) -> str:
        return write_network(cond, coil, self.access, target)

    def action(self, r: ActionRow, step: int) -> str:
        """An ``Action``: the row's text as tokens, each symbol an ``Access`` element with
        its address (informative, as in the networks) so that it reads back at it; a CALL
        row in s7graph's spelling of the call (reported: TIA names blocks by symbol)."""
        attrs = f' Event="{r.event}"' if r.event else ""
        attrs += ' Interlock="true"' if r.interlocked else ""
        attrs += f' Qualifier="{r.qualifier}"'
        accesses: list[str] = []

        call = isinstance(r.operand, BlockCall)

        def spell(e: Expr) -> str | None:
            passed = call and self.passed_db(e) is not None  # src := DB5: an Access too
            if isinstance(e, Operand) and (e.quoted or e.member or passed):
                accesses.append(self.argument(e, str(21 + len(accesses))))
                return f"\x00{len(accesses) - 1}\x00"
            return self.spell(e)

        if isinstance(r.operand, BlockCall):
            text = self.call_text(r.operand, spell)
            if not self.warned_call:
                self.warned_call = True
                self.p.warn(
                    "X012",
                    f"S{step} row {format_row(r)!r}: CALL rows are written in s7graph's "
                    f"spelling ({call_naming(r.operand)})",
                    r.loc,
                )
        else:
            text = row_body(r, spell)
        parts = []
        for i, piece in enumerate(text.split("\x00")):
            if i % 2:
                parts.append(accesses[int(piece)])
            elif piece:
                parts.append(f"<Token Text={quoteattr(piece)} />")
        return f'<Action{attrs}>{"".join(parts)}<Token Text="&#xA;" /></Action>'

    def call_text(self, c: BlockCall, spell: Callable[[Expr], str | None]) -> str:
        """A call as s7graph writes it, its operands spelled as TIA's tokens."""
        block = f"{c.kind} {c.block}" if c.kind else quote(str(c.block))
        if c.instance is not None:
            inst = f"DB {c.instance}" if isinstance(c.instance, int) else quote(c.instance)
            block += f", {inst}"
        params = [f"{n} := {format_expr(v, spell)}" for n, v in c.inputs]
        params += [f"{n} => {format_expr(o, spell)}" for n, o in c.outputs]
        return f"{block} ({', '.join(params)})" if params else block

    def step(self, s: Step) -> str:
        rows = "".join(self.action(r, s.number) for r in s.actions)
        alarm = f"<AlarmText>{_text(s.message)}</AlarmText>" if s.message else ""
        return (
            f'<Step Number="{s.number}" Init="{str(s.initial).lower()}" '
            f'Name={quoteattr(self.step_names[s.number])} MaximumStepTime="T#10S" '
            f'WarningTime="T#7S"><Actions>{rows}<Action /></Actions>'
            f'<Supervisions><Supervision ProgrammingLanguage="LAD">{alarm}'
            f"{self.network(s.supervision, 'SvCoil')}</Supervision></Supervisions>"
            f'<Interlocks><Interlock ProgrammingLanguage="LAD">'
            f"{self.network(s.interlock, 'IlCoil')}</Interlock></Interlocks></Step>"
        )

    def sequence(self, q: Sequence) -> str:
        branches: list[str] = []
        links: list[tuple[str, str, str]] = []

        def branch(kind: str, card: int) -> int:
            branches.append(
                f'<Branch Number="{len(branches) + 1}" Type="{kind}" Cardinality="{card}" />'
            )
            return len(branches)

        drawn = shape_of(q)
        leaving, forward, jumps = drawn.leaving, drawn.arriving, drawn.jumps
        # into each transition
        into_trans: dict[int, list[str]] = {}
        for s, trs in leaving.items():
            if len(trs) > 1:
                b = branch("AltBegin", len(trs))
                links.append(
                    (f'<StepRef Number="{s}" />', f'<BranchRef Number="{b}" In="0" />', "Direct")
                )
                for i, tn in enumerate(trs):
                    into_trans.setdefault(tn, []).append(f'<BranchRef Number="{b}" Out="{i}" />')
            else:
                into_trans.setdefault(trs[0], []).append(f'<StepRef Number="{s}" />')
        for t in q.transitions:
            srcs = into_trans.get(t.number, [])
            if len(t.sources) > 1:
                b = branch("SimEnd", len(t.sources))
                for i, src in enumerate(srcs):
                    links.append((src, f'<BranchRef Number="{b}" In="{i}" />', "Direct"))
                srcs = [f'<BranchRef Number="{b}" Out="0" />']
            for src in srcs:
                links.append((src, f'<TransitionRef Number="{t.number}" />', "Direct"))
        # out of each transition
        alt_end: dict[int, int] = {}
        for d, trs in forward.items():
            if len(trs) > 1:
                alt_end[d] = branch("AltEnd", len(trs))
                links.append(
                    (
                        f'<BranchRef Number="{alt_end[d]}" Out="0" />',
                        f'<StepRef Number="{d}" />',
                        "Direct",
                    )
                )
        for t in q.transitions:
            tref = f'<TransitionRef Number="{t.number}" />'
            if not t.targets:
                links.append((tref, "<EndConnection />", "Direct"))
                continue
            src = tref
            if len(t.targets) > 1:
                b = branch("SimBegin", len(t.targets))
                links.append((tref, f'<BranchRef Number="{b}" In="0" />', "Direct"))
                outs = [f'<BranchRef Number="{b}" Out="{i}" />' for i in range(len(t.targets))]
            else:
                outs = [src]
            for out, d in zip(outs, t.targets, strict=True):
                if (t.number, d) in jumps:
                    links.append((out, f'<StepRef Number="{d}" />', "Jump"))
                elif d in alt_end:
                    i = forward[d].index(t.number)
                    links.append((out, f'<BranchRef Number="{alt_end[d]}" In="{i}" />', "Direct"))
                else:
                    links.append((out, f'<StepRef Number="{d}" />', "Direct"))
        title = f"<Title>{_text(q.name)}</Title>" if q.name else ""
        steps = "".join(self.step(s) for s in q.steps)
        trans = "".join(
            f'<Transition IsMissing="false" Name={quoteattr(self.trans_names[t.number])} '
            f'Number="{t.number}" ProgrammingLanguage="LAD">{self.network(t.condition, "TrCoil")}'
            "</Transition>"
            for t in q.transitions
        )
        conns = "".join(
            f"<Connection><NodeFrom>{a}</NodeFrom><NodeTo>{b}</NodeTo>"
            f"<LinkType>{k}</LinkType></Connection>"
            for a, b, k in links
        )
        return (
            f"<Sequence>{title}<Steps>{steps}</Steps><Transitions>{trans}</Transitions>"
            f"<Branches>{''.join(branches)}</Branches><Connections>{conns}</Connections>"
            "</Sequence>"
        )

    def permanent(self, items: tuple[PermanentInstruction, ...]) -> str:
        """Each permanent instruction a LAD network: a bit's coil, a ``Move`` box of an
        operand or constant, a ``Call`` box; an arithmetic expression is refused (an error
        naming its place: the boxes TIA would draw it with are not written here)."""
        out: list[str] = []
        for p in items:
            if isinstance(p, Coil):
                coil = {"=": "Coil", "S": "SCoil", "R": "RCoil"}[p.kind]
                net = self.network(p.condition, coil, p.target)
            elif isinstance(p, Assignment) and self.is_bit(p.target):
                net = self.network(p.expr, "Coil", p.target)
            elif isinstance(p, Assignment) and isinstance(p.expr, Operand | Const):
                net = write_move(p.expr, p.target, self.access)
            elif isinstance(p, BlockCall):
                net = self.call_network(p)
            else:
                raise ValueError(
                    f"{p.loc}: permanent instruction {format_expr(p.target)} := "
                    f"{format_expr(p.expr)}: an arithmetic expression has no LAD form in "
                    "this export (TIA draws it with ADD/SUB/MUL/DIV or CALCULATE boxes); "
                    "compute it in an FC the permanent instructions call"
                )
            out.append(f'<PermanentOperation ProgrammingLanguage="LAD">{net}</PermanentOperation>')
        return "".join(out)

    def call_network(self, c: BlockCall) -> str:
        """A permanent CALL as a LAD ``Call`` box fed by the power rail, the block and its
        instance DB named by number (``FC2``, ``DB10``: reported once, as for CALL rows)."""
        name = f"{c.kind}{c.block}" if c.kind else str(c.block)
        kind = c.kind or ("FB" if c.instance is not None else "FC")
        params = "".join(
            f'<Parameter Name={quoteattr(n)} Section="{section}"{self.type_attr(e)} />'
            for section, pins in (("Input", c.inputs), ("Output", c.outputs))
            for n, e in pins
        )

        def info(uid: str) -> str:
            inst = ""
            if c.instance is not None:
                db = f"DB{c.instance}" if isinstance(c.instance, int) else c.instance
                inst = (
                    f'<Instance Scope="GlobalVariable" UId="{uid}"><Component '
                    f"Name={quoteattr(db)} /></Instance>"
                )
            head = f"<CallInfo Name={quoteattr(name)} BlockType={quoteattr(kind)}>"
            return f"{head}{inst}{params}</CallInfo>"

        if not self.warned_call:
            self.warned_call = True
            self.p.warn(
                "X012",
                f"CALL {name}: calls are written as the chart writes them ({call_naming(c)})",
                c.loc,
            )
        return write_call(info, c.inputs, c.outputs, self.argument)

    def type_attr(self, e: Expr) -> str:
        """`` Type="Int"`` of an operand or constant whose type is known, else ""."""
        t: str | None = None
        if self.passed_db(e) is not None:
            t = "Block_DB"  # a DB as a whole: the parameter TIA's S7-SCL block declares
        elif isinstance(e, Const):
            t = e.type
        elif isinstance(e, Operand) and e.member:
            t = None  # the block's variable: TIA knows its type
        elif isinstance(e, Operand) and e.quoted:
            found = self.address_of(e.name)
            t = found[1] if found is not None else None
        elif isinstance(e, Operand):
            var = next((v for v in self.chart.vars if v.name.upper() == e.name.upper()), None)
            t = var.type if var is not None else None
        return f' Type="{_tia_type(t)}"' if t else ""

    def is_bit(self, op: Operand) -> bool:
        if op.quoted:
            found = self.address_of(op.name)
            return found is None or found[1] == "BOOL"
        var = next((v for v in self.chart.vars if v.name.upper() == op.name.upper()), None)
        return var.type == "BOOL" if var is not None else "." in op.name

    # ------------------------------------------------------------ the document

    def interface(self) -> str:
        params = self.chart.options.parameters
        ins = [p for p in pins_for(params) if p.direction is Direction.IN]
        outs = [p for p in pins_for(params) if p.direction is not Direction.IN]

        def member(name: str, t: str, start: str = "") -> str:
            sv = f"<StartValue>{escape(start)}</StartValue>" if start else ""
            return f'<Member Name={quoteattr(name)} Datatype="{_tia_type(t)}">{sv}</Member>'

        statics = "".join(
            member(v.name, v.type, v.init.text if v.init else "") for v in self.chart.vars
        )
        return (
            f'<Interface><Sections xmlns="{_IFACE_NS}"><Section Name="Base">'
            '<Sections Datatype="GRAPH_BASE" Version="1.0"><Section Name="Input" />'
            '<Section Name="Output" /><Section Name="InOut" /><Section Name="Static" />'
            "</Sections></Section>"
            f'<Section Name="Input">{"".join(member(p.name, p.type) for p in ins)}</Section>'
            f'<Section Name="Output">{"".join(member(p.name, p.type) for p in outs)}</Section>'
            f'<Section Name="InOut" /><Section Name="Static">{statics}</Section>'
            '<Section Name="Temp" /><Section Name="Constant" /></Sections></Interface>'
        )

    def comment(self) -> str:
        o = self.chart.options
        keep = []
        if self.chart.db_number is not None:
            keep.append(f"DB {self.chart.db_number}")
        if o.order != "graph":
            keep.append(f"ORDER := {o.order.upper()}")
        if o.ack_forces_switch:
            keep.append("ACK_FORCES_SWITCH := TRUE")
        keep += [f'"{s.name}" : {s.address} : {s.type}' for s in self.reads.carried(True)]
        return f"{S7GRAPH_COMMENT} {'; '.join(keep)}" if keep else ""

    def document(self) -> str:
        c = self.chart
        o = c.options
        sequences = "".join(self.sequence(q) for q in c.sequences)
        number = f"<Number>{c.fb_number}</Number>" if c.fb_number is not None else ""
        comment = self.comment()
        alarms = "".join(
            f'<AlarmSupervisionCategory Id="{i}" DisplayClass="0" />' for i in range(1, 9)
        )
        return (
            '<?xml version="1.0" encoding="utf-8"?>\n<Document><Engineering version="V16" />'
            '<SW.Blocks.FB ID="0"><AttributeList>'
            f"<AcknowledgeErrorsRequired>{str(o.ack_required).lower()}</AcknowledgeErrorsRequired>"
            "<GraphVersion>6.0</GraphVersion>"
            f"{self.interface()}"
            "<LanguageInNetworks>LAD</LanguageInNetworks>"
            "<LockOperatingMode>false</LockOperatingMode>"
            f"<Name>{escape(c.name)}</Name>{number}"
            "<PermanentILProcessingInMANMode>false</PermanentILProcessingInMANMode>"
            "<ProgrammingLanguage>GRAPH</ProgrammingLanguage>"
            "<SetENOAutomatically>false</SetENOAutomatically>"
            f"<SkipSteps>{str(o.skip_steps).lower()}</SkipSteps>"
            f"<WithAlarmHandling>{str(o.messages).lower()}</WithAlarmHandling>"
            "</AttributeList><ObjectList>"
            '<MultilingualText ID="1" CompositionName="Comment"><ObjectList>'
            '<MultilingualTextItem ID="2" CompositionName="Items"><AttributeList>'
            f"<Culture>en-US</Culture><Text>{escape(comment)}</Text></AttributeList>"
            "</MultilingualTextItem></ObjectList></MultilingualText>"
            '<SW.Blocks.CompileUnit ID="3" CompositionName="CompileUnits"><AttributeList>'
            f'<NetworkSource><Graph xmlns="{_GRAPH_NS}">'
            f"<PreOperations>{self.permanent(c.before)}</PreOperations>{sequences}"
            f"<PostOperations>{self.permanent(c.after)}</PostOperations>"
            f"<AlarmsSettings><AlarmSupervisionCategories>{alarms}</AlarmSupervisionCategories>"
            '<AlarmInterlockCategory Id="1" /><AlarmSubcategory1Interlock Id="0" />'
            '<AlarmSubcategory2Interlock Id="0" /><AlarmCategorySupervision Id="1" />'
            '<AlarmSubcategory1Supervision Id="0" /><AlarmSubcategory2Supervision Id="0" />'
            '<AlarmWarningCategory Id="2" /><AlarmSubcategory1Warning Id="0" />'
            '<AlarmSubcategory2Warning Id="0" /></AlarmsSettings></Graph></NetworkSource>'
            "<ProgrammingLanguage>GRAPH</ProgrammingLanguage></AttributeList></SW.Blocks.CompileUnit>"
            "</ObjectList></SW.Blocks.FB></Document>\n"
        )


class _Refused(ValueError):
    """A chart part this export refuses, its message naming the place."""


def _path(name: str) -> list[str]:
    """A tag name's components: ``A.b.c`` → [A, b, c] when each is an identifier."""
    parts = name.split(".")
    return parts if len(parts) > 1 and all(_IDENT.fullmatch(p) for p in parts) else [name]


def _loc(e: Expr) -> SourceLocation:
    return getattr(e, "loc", SourceLocation())


def _address(e: Operand) -> Address:
    """The S7 address ``e`` names; a name that is none (no address, FB variable or symbol
    of the chart: ``s7graph check`` says more) is refused, naming its place."""
    try:
        return parse_address(e.name)
    except AddressError as exc:
        raise _Refused(
            f"{e.loc}: {exc.message}: TIA needs a tag, an address or an FB "
            "variable here (s7graph check says more)"
        ) from None


def _address_type(address: str) -> str:
    a = parse_address(address)
    return {1: "Bool", 8: "Byte", 16: "Word", 32: "DWord"}.get(int(a.width), "Word")


def export_simaticml(
    chart: Chart, symbols: SymbolTable | None = None
) -> tuple[str, list[Diagnostic]]:
    """The SimaticML document of ``chart`` and what TIA may read otherwise (located
    warnings); ``ValueError`` for what it cannot hold."""
    export = _Export(chart, symbols)
    text = export.document()
    return text, export.p.items
