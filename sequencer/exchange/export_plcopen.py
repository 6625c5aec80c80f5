"""Write a chart as PLCopen TC6 XML 2.01 (``tc6_0201``): an SFC body other IEC tools read,
plus the chart's `.s7g` source in the POU's ``addData`` (PLCopen's place for a tool's own
data), from which s7graph reads it back exactly.

The SFC body: one ``step`` per step (IEC name: the GRAPH name as an identifier, Cyrillic
transliterated, when it is unique, else ``S<n>``), the transitions leaving a step left to
right in their priority order (after a ``selectionDivergence`` when there are several),
``simultaneousDivergence`` / ``simultaneousConvergence`` for ``TO (…)`` / ``FROM (…)``, a
``selectionConvergence`` before a step several transitions lead to, and a ``jumpStep`` for
a transition that leads back up. Conditions are inline ST. Action rows with an IEC
equivalent (``exchange.mapping`` read backwards) become actions: ``N S R D L`` on a bit as
Boolean actions, ``S1``/``S0`` rows as ``P``/``P0`` actions, assignments as inline ST, a
call of an IEC timer or counter (``CALL SFB 4, DB 10 (…)``) as the call of an FB instance
``TON_DB10`` the POU declares; the others (interlocked rows, other events, other calls, S5
counters and timers) an inline ST comment holding the GRAPH row. Symbols are global
variables of the configuration at their IEC address. An instance DB's variable read by
name (``"T_S2".Q``, ``DB10.Q``) is the access to that instance's output, ``TON_DB10.Q``
(a DB of another block: a global instance of the block's type, reported); a DB symbol is
no IEC variable (one no read goes through is reported). IEC 61131-3 has no BLOCK_DB: a call
passing a DB (``src := DB5``) is an ST comment in its S7 spelling, as any call of a user
block, the DB named in its report. Interlocks, supervisions, options,
permanent instructions and ``TO STOP`` live in the `.s7g` source only.
"""

from __future__ import annotations

import re
from collections import Counter
from dataclasses import replace
from xml.sax.saxutils import escape, quoteattr

from s7graph.engine.symbols import SymbolTable
from s7graph.sequencer.checks.diagnostics import Diagnostic
from s7graph.sequencer.exchange.db_reads import DbReads, member_text
from s7graph.sequencer.exchange.iec_to_chart import S7_PIN, SFB_OF
from s7graph.sequencer.exchange.naming import s7_to_iec, transliterate
from s7graph.sequencer.exchange.plcopen import S7GRAPH_DATA, TRANSITION_IDS
from s7graph.sequencer.exchange.problems import Problems
from s7graph.sequencer.exchange.shape import priority, shape_of
from s7graph.sequencer.text.call_sites import call_sites
from s7graph.sequencer.text.format import format_chart, format_expr, format_row
from s7graph.sequencer.text.model import (
    ActionRow,
    Assignment,
    Binary,
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
    SymbolDecl,
    TransAttr,
    Unary,
)
from s7graph.sequencer.text.names import db_argument, db_symbol
from s7graph.sfb import catalogue

__all__ = ["export_plcopen"]

_NS = "http://www.plcopen.org/xml/tc6_0201"
_STEP_REF = re.compile(r"S\d+", re.IGNORECASE)  # the names of unnamed steps
_OTHER_IDS = 200_000  # the other elements' localIds start here
_TYPES = {"TIME_OF_DAY": "TOD", "DATE_AND_TIME": "DT"}
_IEC_PIN = {s7: iec for iec, s7 in S7_PIN.items()}  # S7's LOAD → IEC's LD


def _ident(name: str, fallback: str = "_x") -> str:
    """``name`` as an IEC 61131-3 identifier (section 6.1.2): in Latin letters
    (``naming.transliterate``: ``Подача`` → ``Podacha``), then ASCII letters, digits and
    single underscores, none at the end, not starting with a digit (``Start ä x`` →
    ``Start_a_x``); ``fallback`` when no letter or digit is left (``注水``)."""
    out = "".join(
        c if (c.isascii() and c.isalnum()) or c == "_" else "_" for c in transliterate(name)
    )
    out = re.sub(r"_{2,}", "_", out).rstrip("_")
    if not out.strip("_"):
        return fallback
    return "_" + out if out[0].isdigit() else out


class _Export:
    def __init__(self, chart: Chart, symbols: SymbolTable | None) -> None:
        self.chart = chart
        self.table = symbols
        self.ids = _OTHER_IDS
        self.instances: dict[str, str] = {}  # IEC FB instances the calls name → their type
        self.db_globals: dict[str, str] = {}  # instances only read, as globals → their type
        self.p = Problems(chart.file)
        self.reads = DbReads(chart, symbols)
        self.read_dbs: set[int] = set()  # the instance DBs the SFC reads a variable of
        self.step_name: dict[int, str] = {}
        self.symbol_name: dict[str, str] = {}
        self._iec_names()
        self.permanent_xml = self.permanent()

    def _iec_names(self) -> None:
        """An IEC identifier per step and symbol, each once in the POU (IEC 61131-3 compares
        names without case; steps, variables and globals share the POU's names): a step keeps
        its name's identifier when no other step, variable or ``S<n>`` has it, else it is
        ``S<n>``; a symbol whose identifier is taken gets ``_2``, ``_3`` … (X013)."""
        taken = {v.name.upper() for v in self.chart.vars}
        steps = self.chart.all_steps()
        idents = [_ident(s.name, "") for s in steps]
        counts = Counter(i.upper() for i in idents)
        for s, ident in zip(steps, idents, strict=True):
            free = counts[ident.upper()] == 1 and ident.upper() not in taken
            keep = ident and free and not _STEP_REF.fullmatch(ident)
            self.step_name[s.number] = ident if keep else f"S{s.number}"
            if s.name and not ident:
                self.p.warn(
                    "X013",
                    f"step S{s.number} {s.name!r} is named S{s.number} in the SFC: its name "
                    "has no letter or digit an IEC identifier can hold",
                    s.loc,
                )
            if ident and not keep and ident.upper() != f"S{s.number}":
                self.p.warn(
                    "X013",
                    f"step S{s.number} {s.name!r} is named S{s.number} in the SFC: its IEC "
                    f"name {ident} is taken (IEC compares names without case)",
                    s.loc,
                )
        taken |= {n.upper() for n in self.step_name.values()}
        where = {d.name: d.loc for d in self.chart.symbols}
        for name, _, _ in self.symbols():
            base = unique = _ident(name)
            k = 1
            while unique.upper() in taken:
                k += 1
                unique = f"{base}_{k}"
            if unique != base:
                self.p.warn(
                    "X013",
                    f"symbol {name!r} is the global {unique} in the SFC: {base} is taken "
                    "(IEC compares names without case)",
                    where.get(name, self.chart.loc),
                )
            taken.add(unique.upper())
            self.symbol_name[name] = unique

    def next_id(self) -> int:
        self.ids += 1
        return self.ids

    # ------------------------------------------------------------ ST text

    def st(self, e: Expr) -> str:
        """``e`` in ST: the `.s7g` expression with IEC operands and constants."""
        return format_expr(e, self.iec)

    def iec(self, e: Expr) -> str | None:
        if isinstance(e, Const) and e.type in ("WORD", "DWORD", "BYTE"):
            m = re.fullmatch(r"\w+#(16|8|2)#(.+)", e.text)
            if m:  # W#16#FF, DW#2#1010: the IEC type's own prefix
                return f"{e.type}#{m[1]}#{m[2]}"
        if isinstance(e, Const) and e.text.upper().startswith("L#"):  # L#70000: a DINT
            return f"DINT#{e.text[2:]}"
        if isinstance(e, Operand) and e.member:
            return self.member_st(e)
        if isinstance(e, Operand) and e.quoted:
            return self.symbol_name.get(e.name) or _ident(e.name)
        if isinstance(e, Operand):
            return s7_to_iec(e.name) or e.name
        if isinstance(e, StepAttr):
            return f"{self.step_name.get(e.step, f'S{e.step}')}.{'T' if e.attr == 'U' else e.attr}"
        if isinstance(e, TransAttr):
            return f"T{e.transition}_TT"
        return None

    def member_st(self, e: Operand) -> str:
        """An instance DB's variable read by name as IEC 61131-3's access to an FB
        instance's output (6.6.1.2.2): ``"T_S2".Q`` / ``DB10.Q`` of an IEC timer or
        counter is ``TON_DB10.Q``, the instance its call is written with; of another
        block, a global instance of the block's type that an IEC tool does not call
        (X010, once per DB)."""
        number = self.reads.db(e)
        self.read_dbs.add(number)
        call = self.reads.calls[number]
        entry = catalogue.find(f"{call.kind}{call.block}")
        pin = entry.pin(e.member) if entry is not None else None
        member = pin.name if pin is not None else e.member
        if entry is not None and entry.kind == "SFB" and entry.name in SFB_OF:
            name = f"{entry.name}_DB{number}"
            self.instances[name] = entry.name
            return f"{name}.{member}"
        fb = entry.name if entry is not None else _ident(self.reads.block(number))
        name = _ident(self.reads.name(number) or f"DB{number}")
        if name not in self.db_globals:
            self.db_globals[name] = fb
            self.p.warn(
                "X010",
                f"{member_text(e)}: DB {number} is the instance of {self.reads.block(number)}, "
                f"whose call other tools do not run: their SFC reads the global {name} : {fb}, "
                "which nothing calls (the chart is in s7graph's data)",
                e.loc,
            )
        return f"{name}.{member}"

    def unread_dbs(self) -> None:
        """A DB symbol of the chart's ``SYMBOLS`` no read goes through has no IEC form (a
        DB is no variable): left out of the SFC, reported (X010) — one a call passes to a
        BLOCK_DB input too: IEC 61131-3 has no BLOCK_DB, and that call is an ST comment."""
        passed = {
            n for site in call_sites(self.chart) for n in _passed(site.call, self.chart, self.table)
        }
        for s in self.chart.symbols:
            number = db_symbol(s)
            if number is None or number in self.read_dbs:
                continue
            why = (
                "a call passes it to a BLOCK_DB input, which IEC 61131-3 has not (the call "
                "is an ST comment)"
                if number in passed
                else "no read goes through it"
            )
            self.p.warn(
                "X010",
                f'DB symbol "{s.name}" (DB {number}) has no IEC form and {why}: kept in '
                "s7graph's data only",
                s.loc,
            )

    # ------------------------------------------------------------ actions

    def action(self, r: ActionRow) -> str:
        op = r.operand
        plain = not r.interlocked
        qualifier = {None: "", "S1": "P", "S0": "P0"}.get(r.event)
        if plain and qualifier == "" and r.qualifier in ("N", "S", "R") and isinstance(op, Operand):
            return self.bool_action(r.qualifier, op)
        if (
            plain
            and qualifier == ""
            and r.qualifier in ("D", "L")
            and isinstance(op, Operand)
            and r.value is not None
        ):
            return self.bool_action(r.qualifier, op, self.st(r.value))
        if plain and qualifier is not None and isinstance(op, Assignment) and r.qualifier == "N":
            body = f"{self.st(op.target)} := {self.st(op.expr)};"
            return self.inline(qualifier or "N", body)
        if plain and qualifier and r.qualifier in ("S", "R") and isinstance(op, Operand):
            body = f"{self.st(op)} := {'TRUE' if r.qualifier == 'S' else 'FALSE'};"
            return self.inline(qualifier, body)
        if plain and qualifier == "P" and r.qualifier == "N" and isinstance(op, Operand):
            return self.bool_action("P", op)
        if plain and qualifier is not None and r.qualifier == "CALL" and isinstance(op, BlockCall):
            call = self.fb_call(op)
            if call is not None:
                return self.inline(qualifier or "N", call)
        note = _db_note(op, self.chart, self.table)
        self.p.warn(
            "X010",
            f"row {format_row(r)!r} has no IEC form{f' ({note})' if note else ''}: an ST comment "
            "in the SFC other tools read, kept in s7graph's data",
            r.loc,
        )
        return self.inline("N", f"(* s7graph: {format_row(r).replace('*)', '* )')} *)")

    def fb_call(self, c: BlockCall) -> str | None:
        """``CALL SFB 4, DB 10 (IN := x, …)`` as the call of the IEC FB instance
        ``TON_DB10`` (declared in the POU), for the IEC timers and counters; else None."""
        entry = catalogue.find(f"{c.kind}{c.block}")  # CALL SFB 4 or CALL "TON"
        if entry is None or entry.kind != "SFB" or entry.name not in SFB_OF:
            return None
        if not isinstance(c.instance, int):
            return None
        name = f"{entry.name}_DB{c.instance}"
        self.instances[name] = entry.name
        params = [f"{_IEC_PIN.get(pin.upper(), pin)} := {self.st(e)}" for pin, e in c.inputs]
        params += [f"{pin} => {self.st(o)}" for pin, o in c.outputs]
        return f"{name}({', '.join(params)});"

    def permanent(self) -> str:
        """The permanent instructions as an IEC tool runs them: the body of an inline
        action stored (S) on the chart's first initial step and never reset, which runs
        every call for good (s7graph reads it back as PERMANENT AFTER). PERMANENT BEFORE
        goes first in it; an IEC tool runs it after the transitions (reported)."""
        items = [*self.chart.before, *self.chart.after]
        if not items:
            return ""
        if self.chart.before:
            self.p.warn(
                "X011",
                "PERMANENT BEFORE runs, in an IEC tool, in a stored action of the initial "
                "step, after the transitions: what it writes reaches the conditions one call "
                "later",
                self.chart.before[0].loc,
            )
        if not any(s.initial for s in self.chart.all_steps()):
            self.p.warn(
                "X010",
                "the permanent instructions have no IEC form without an initial step to "
                "store them on: kept in s7graph's data only",
                items[0].loc,
            )
            return ""
        body = "\n".join(self.permanent_st(p) for p in items)
        return self.inline("S", body)

    def permanent_st(self, p: PermanentInstruction) -> str:
        """One permanent instruction in ST (a set coil ``x := x OR c``, a reset coil ``x :=
        x AND NOT c``, a call of an IEC timer or counter as its instance's call)."""
        if isinstance(p, Coil):
            value: Expr = p.condition
            if p.kind == "S":
                value = Binary("OR", p.target, p.condition, p.loc)
            elif p.kind == "R":
                c = p.condition
                no = c.operand if isinstance(c, Unary) and c.op == "NOT" else Unary("NOT", c, p.loc)
                value = Binary("AND", p.target, no, p.loc)
            return f"{self.st(p.target)} := {self.st(value)};"
        if isinstance(p, Assignment):
            return f"{self.st(p.target)} := {self.st(p.expr)};"
        call = self.fb_call(p)
        if call is not None:
            return call
        text, note = _permanent_text(p), _db_note(p, self.chart, self.table)
        self.p.warn(
            "X010",
            f"{text!r} has no IEC form (an IEC tool calls only the IEC timers and counters "
            f"here{f'; {note}' if note else ''}): an ST comment, kept in s7graph's data",
            p.loc,
        )
        return f"(* s7graph: {text.replace('*)', '* )')} *)"

    def left_out(self, q: Sequence) -> None:
        """Report what of ``q`` an IEC tool does not see (kept in s7graph's data)."""
        for st in q.steps:
            for what, cond, loc in (
                ("interlock", st.interlock, st.interlock_loc),
                ("supervision", st.supervision, st.supervision_loc),
            ):
                if cond is not None:
                    self.p.warn(
                        "X010",
                        f"S{st.number}'s {what} has no IEC form: kept in s7graph's data",
                        loc or st.loc,
                    )
        for t in q.transitions:
            if not t.targets:
                self.p.warn(
                    "X010",
                    f"T{t.number} TO STOP (a branch stop) has no IEC form: the transition "
                    "leads nowhere in the SFC other tools read",
                    t.loc,
                )

    def bool_action(self, qualifier: str, op: Operand, duration: str = "") -> str:
        dur = f" duration={quoteattr(duration)}" if duration else ""
        return (
            f'<action localId="0" qualifier="{qualifier}"{dur}><relPosition x="0" y="0"/>'
            f"<reference name={quoteattr(self.st(op))}/></action>"
        )

    def inline(self, qualifier: str, body: str) -> str:
        return (
            f'<action localId="0" qualifier="{qualifier}"><relPosition x="0" y="0"/><inline><ST>'
            f"<xhtml:p><![CDATA[{body}]]></xhtml:p></ST></inline></action>"
        )

    # ------------------------------------------------------------ SFC body

    def sequence(self, q: Sequence, column: int, out: list[str]) -> None:
        order = {s.number: i for i, s in enumerate(q.steps)}
        x0 = 40 + column * 400
        step_id: dict[int, int] = {s.number: s.number for s in q.steps}
        trans_id: dict[int, int] = {t.number: TRANSITION_IDS + t.number for t in q.transitions}
        self.left_out(q)
        drawn = shape_of(q)
        leaving, arriving, jumps = drawn.leaving, drawn.arriving, drawn.jumps
        # what a transition's input connects to: a step, or that step's divergence
        out_of: dict[int, int] = {}
        for s, trs in leaving.items():
            if s not in step_id:
                continue
            if len(trs) > 1:
                at = (x0, 60 + order.get(s, 0) * 120 + 40)
                out_of[s] = self.branch("selectionDivergence", [step_id[s]], len(trs), out, at)
            else:
                out_of[s] = step_id[s]
        after: dict[int, int] = {}  # transition → the element after it (simultaneous div.)
        for t in q.transitions:
            targets = [d for d in t.targets if (t.number, d) not in jumps]
            if len(t.targets) > 1:
                at = (x0, 60 + order.get(t.sources[0], 0) * 120 + 100)
                div = self.branch(
                    "simultaneousDivergence", [trans_id[t.number]], len(t.targets), out, at
                )
                after[t.number] = div
            else:
                after[t.number] = trans_id[t.number]
            for d in t.targets:
                if (t.number, d) in jumps or (len(t.targets) > 1 and d not in targets):
                    jid = self.next_id()
                    y = 60 + order.get(t.sources[0], 0) * 120 + 110
                    out.append(
                        f'<jumpStep localId="{jid}" height="13" width="12" '
                        f"targetName={quoteattr(self.step_name[d])}>"
                        f'<position x="{x0}" y="{y}"/>{_cpin([after[t.number]])}</jumpStep>'
                    )
        for st in q.steps:
            ins = [after[t] for t in arriving.get(st.number, [])]
            y = 60 + order[st.number] * 120
            if len(ins) > 1:
                ins = [self.branch("selectionConvergence", ins, 1, out, (x0, y - 20))]
            out.append(self.step(st, step_id[st.number], ins, x0, y))
        for t in q.transitions:
            srcs = [out_of.get(s, step_id.get(s, 0)) for s in t.sources]
            if len(srcs) > 1:
                at = (x0, 60 + order.get(t.sources[0], 0) * 120 + 60)
                srcs = [self.branch("simultaneousConvergence", srcs, 1, out, at)]
            first = t.sources[0]
            rank = priority(leaving.get(first, [t.number])).index(t.number)
            x = x0 + rank * 160
            y = 60 + order.get(first, 0) * 120 + 80
            cond = self.st(t.condition) if t.condition is not None else "TRUE"
            out.append(  # TC6 names no transition: the name stays in s7graph's data
                f'<transition localId="{trans_id[t.number]}" height="2" width="20">'
                f'<position x="{x}" y="{y}"/>{_cpin(srcs)}<connectionPointOut/>'
                f'<condition><inline name=""><ST><xhtml:p><![CDATA[{cond}]]></xhtml:p>'
                "</ST></inline></condition></transition>"
            )

    def branch(
        self, tag: str, ins: list[int], outs: int, out: list[str], at: tuple[int, int] = (0, 0)
    ) -> int:
        """A divergence (one input, ``outs`` outputs, each named as TC6 requires) or a
        convergence (one input point per element in ``ins``, one output) drawn at ``at``;
        returns its localId."""
        bid = self.next_id()
        divergence = tag.endswith("Divergence")
        points = _cpin(ins) if divergence else "".join(_cpin([i]) for i in ins)
        point_out = (
            '<connectionPointOut formalParameter=""/>' if divergence else ("<connectionPointOut/>")
        )
        out.append(
            f'<{tag} localId="{bid}" height="2" width="200">'
            f'<position x="{at[0]}" y="{at[1]}"/>{points}' + point_out * outs + f"</{tag}>"
        )
        return bid

    def step(self, s: Step, sid: int, ins: list[int], x: int, y: int) -> str:
        init = "true" if s.initial else "false"
        cp = _cpin(ins) if ins else ""
        xml = (
            f'<step localId="{sid}" height="30" width="80" '
            f'name={quoteattr(self.step_name[s.number])} initialStep="{init}">'
            f'<position x="{x}" y="{y}"/>{cp}'
            '<connectionPointOut formalParameter=""/>'
            '<connectionPointOutAction formalParameter=""/></step>'
        )
        extra = ""
        if self.permanent_xml and s.initial:
            extra, self.permanent_xml = self.permanent_xml, ""
        if s.actions or extra:
            bid = self.next_id()
            xml += (
                f'<actionBlock localId="{bid}" height="30" width="200">'
                f'<position x="{x + 120}" y="{y}"/>{_cpin([sid])}'
                + "".join(self.action(r) for r in s.actions)
                + extra
                + "</actionBlock>"
            )
        return xml

    # ------------------------------------------------------------ the document

    def interface(self) -> tuple[str, str]:
        local = []
        for v in self.chart.vars:
            init = (
                f"<initialValue><simpleValue value={quoteattr(self.st(v.init))}/></initialValue>"
                if v.init is not None
                else ""
            )
            local.append(f"<variable name={quoteattr(v.name)}>{_type(v.type)}{init}</variable>")
        for name, fb in self.instances.items():
            derived = f"<type><derived name={quoteattr(fb)}/></type>"
            local.append(f"<variable name={quoteattr(name)}>{derived}</variable>")
        external, globals_ = [], []
        for name, fb in self.db_globals.items():
            derived = f"<variable name={quoteattr(name)}><type><derived name={quoteattr(fb)}/>"
            external.append(derived + "</type></variable>")
            globals_.append(derived + "</type></variable>")
        for name, address, type_name in self.symbols():
            ident = self.symbol_name[name]
            external.append(f"<variable name={quoteattr(ident)}>{_type(type_name)}</variable>")
            iec = s7_to_iec(address)
            at = f" address={quoteattr(iec)}" if iec else ""
            globals_.append(f"<variable name={quoteattr(ident)}{at}>{_type(type_name)}</variable>")
        iface = ""
        if local:
            iface += "<localVars>" + "".join(local) + "</localVars>"
        if external:
            iface += "<externalVars>" + "".join(external) + "</externalVars>"
        return iface, "".join(globals_)

    def symbols(self) -> list[tuple[str, str, str]]:
        """The symbols of operands (the chart's, then the table's): the globals."""
        seen: dict[str, tuple[str, str, str]] = {}
        for s in self.chart.symbols:
            if db_symbol(s) is None:
                seen[s.name] = (s.name, s.address, s.type)
        for sym in self.table or ():
            seen.setdefault(sym.name, (sym.name, str(sym.address), sym.type))
        return list(seen.values())

    def kept_symbols(self) -> tuple[SymbolDecl, ...]:
        """The chart's symbols, then the table's operands and the DB symbols of the table
        the chart reads through."""
        if self.table is None:  # (a table of DB symbols only has no len)
            return self.chart.symbols
        out = list(self.chart.symbols)
        names = {s.name for s in out}
        out += [SymbolDecl(n, a, t) for n, a, t in self.symbols() if n not in names]
        names = {s.name.casefold() for s in out}
        return (*out, *(s for s in self.reads.carried() if s.name.casefold() not in names))

    def options(self) -> None:
        o = self.chart.options
        changed = [
            name
            for name, value, default in (
                ("SKIP_STEPS", o.skip_steps, False),
                ("ACK_REQUIRED", o.ack_required, True),
                ("MESSAGES", o.messages, False),
                ("ACK_FORCES_SWITCH", o.ack_forces_switch, False),
                ("ORDER", o.order, "graph"),
            )
            if value != default
        ]
        if changed:
            self.p.warn(
                "X010",
                f"the block options {', '.join(changed)} have no IEC form: kept in s7graph's data",
                self.chart.loc,
            )

    def document(self) -> str:
        self.options()
        body: list[str] = []
        for i, q in enumerate(self.chart.sequences):
            self.sequence(q, i, body)
        self.unread_dbs()
        iface, globals_ = self.interface()
        # the chart kept with the symbols it was exported with (from --symbols too, the DB
        # symbols its reads name): read back, it passes check without the symbol file
        kept = replace(self.chart, symbols=self.kept_symbols())
        source = format_chart(kept).replace("]]>", "]]]]><![CDATA[>")
        name = quoteattr(self.chart.name)
        pou = quoteattr(_ident(self.chart.name))  # an IEC identifier (the chart keeps its own)
        return (
            '<?xml version="1.0" encoding="utf-8"?>\n'
            f'<project xmlns="{_NS}" xmlns:xhtml="http://www.w3.org/1999/xhtml">\n'
            '<fileHeader companyName="s7graph" productName="s7graph" productVersion="1" '
            'creationDateTime="2000-01-01T00:00:00"/>\n'
            f'<contentHeader name={name}><coordinateInfo><fbd><scaling x="1" y="1"/></fbd>'
            '<ld><scaling x="1" y="1"/></ld><sfc><scaling x="1" y="1"/></sfc>'
            "</coordinateInfo></contentHeader>\n"
            f'<types><dataTypes/><pous><pou name={pou} pouType="functionBlock">\n'
            f"<interface>{iface}</interface>\n"
            "<body><SFC>\n" + "\n".join(body) + "\n</SFC></body>\n"
            f'<addData><data name="{S7GRAPH_DATA}" handleUnknown="discard">'
            f"<text><![CDATA[{source}]]></text></data></addData>\n"
            "</pou></pous></types>\n"
            '<instances><configurations><configuration name="s7graph">'
            f'<resource name="cpu"><task name="OB1" priority="1" interval="T#10ms">'
            f'<pouInstance name="{escape(_ident(self.chart.name))}_DB" typeName={pou}/></task>'
            f"</resource><globalVars>{globals_}</globalVars></configuration></configurations>"
            "</instances>\n</project>\n"
        )


def _cpin(refs: list[int]) -> str:
    conns = "".join(f'<connection refLocalId="{r}"/>' for r in refs)
    return f"<connectionPointIn>{conns}</connectionPointIn>"


def _type(type_name: str) -> str:
    t = _TYPES.get(type_name, type_name)
    if t.startswith("STRING"):
        length = t[7:-1] if "[" in t else ""
        return f'<type><string length="{length}"/></type>' if length else "<type><string/></type>"
    return f"<type><{t}/></type>"


def _passed(call: BlockCall, chart: Chart, table: SymbolTable | None) -> list[int]:
    """The DBs ``call`` passes (``src := DB5``, ``src := "Recipe"``)."""
    return [n for _, e in call.inputs if (n := db_argument(e, chart, table)) is not None]


def _db_note(op: object, chart: Chart, table: SymbolTable | None) -> str:
    """What an ST comment's report says of the DBs a call passes: IEC 61131-3 has no
    BLOCK_DB, nor a DB as a value, so the call keeps its S7 spelling."""
    dbs = _passed(op, chart, table) if isinstance(op, BlockCall) else []
    if not dbs:
        return ""
    return f"IEC 61131-3 has no BLOCK_DB to pass {', '.join(f'DB {n}' for n in dbs)} to"


def _permanent_text(p: PermanentInstruction) -> str:
    text = format_chart(Chart("x", after=(p,)))
    return text.split("PERMANENT AFTER\n", 1)[1].split("\nEND_PERMANENT", 1)[0].strip()


def export_plcopen(
    chart: Chart, symbols: SymbolTable | None = None
) -> tuple[str, list[Diagnostic]]:
    """The PLCopen XML document of ``chart`` (``symbols``: the table its symbols are in),
    and what of the chart other IEC tools do not see or run otherwise (located warnings;
    all of it is in s7graph's data)."""
    export = _Export(chart, symbols)
    text = export.document()
    return text, export.p.items
