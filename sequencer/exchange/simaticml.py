"""Read a TIA Portal Openness SimaticML export of an S7-GRAPH FB (``NetworkSource/Graph/v1``
… ``v6``, TIA V14–V21) into the chart model. GRAPH to GRAPH: steps keep their numbers and
names, transitions their numbers, names and order (a transition without a name, or with
TIA's default for its number, ``Trans3``, is unnamed, as the export writes it).

* Shape (``Connections``): a transition's preceding steps come in directly, through an
  ``AltBegin`` (its ``Out`` index is the branch's priority: leftmost first) or a
  ``SimEnd``; its following steps go out directly, through an ``AltEnd`` or a ``SimBegin``,
  or it ends the path (``EndConnection``: TO STOP). A ``Jump`` link is a jump.
* Conditions, interlocks, supervisions and permanent operations are LAD/FBD networks
  (``exchange.flgnet``); a supervision's alarm text is the step's message text.
* Action rows are ``Action`` elements (``Event``, ``Qualifier``, ``Interlock``) whose tokens
  spell the row as in the GRAPH editor: ``"Tag".member`` is the symbol ``"Tag.member"``
  (a DB symbol's member the instance DB's variable, ``"T_S2".Q``), ``#x`` the FB variable
  ``x``, ``%Q0.3`` the address ``Q0.3``.
* The FB's attributes: ``SkipSteps``, ``AcknowledgeErrorsRequired``, ``WithAlarmHandling``
  (messages); its parameter set is the set whose pins the interface holds. Static members
  of elementary types are FB variables.
* Operands, global tags (a block export does not carry the tag table: tags found in the
  symbol table given keep their addresses there, the others get marker addresses within
  the CPU's M area, reported, which the user replaces with the tag table's) and named
  constants: ``exchange.tia_operands``.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import replace

from s7graph.engine.errors import LiteralError, S7Error, SourceLocation
from s7graph.engine.symbols import SymbolTable
from s7graph.sequencer.change.base import MAX_NUMBER
from s7graph.sequencer.exchange.db_reads import not_in_table
from s7graph.sequencer.exchange.export_simaticml import S7GRAPH_COMMENT, default_name
from s7graph.sequencer.exchange.flgnet import Box, read_boxes, read_network
from s7graph.sequencer.exchange.iec_actions import permanent_assignment
from s7graph.sequencer.exchange.iec_to_chart import accepted, const
from s7graph.sequencer.exchange.markers import used_bytes
from s7graph.sequencer.exchange.problems import ImportFailed, Problems
from s7graph.sequencer.exchange.stalls import report_stalls
from s7graph.sequencer.exchange.tia_operands import TIA_TYPES, TiaOperands
from s7graph.sequencer.exchange.xmltree import ElementError, Node, is_true
from s7graph.sequencer.params import PARAMETER_SETS, pins_for
from s7graph.sequencer.text.model import (
    ActionRow,
    Assignment,
    BlockCall,
    Chart,
    ChartOptions,
    Coil,
    Const,
    Expr,
    Operand,
    PermanentInstruction,
    Sequence,
    Step,
    SymbolDecl,
    Transition,
    VarDecl,
)
from s7graph.sequencer.text.parse import ChartSyntaxError, parse_chart
from s7graph.sequencer.text.walk import nodes

__all__ = ["TIA_TYPES", "read_simaticml"]

_KEPT_DB = re.compile(r'"([^"]+)"\s*:\s*DB\s*(\d{1,5})\s*:\s*([^;\s]+)')


class _Reader(TiaOperands):
    """A GRAPH FB of a SimaticML document: its block, sequences and rows."""

    def network(self, holder: Node | None) -> list[tuple[Node, Expr | None]]:
        net = holder.child("FlgNet") if holder is not None else None
        if net is None:
            return []
        return read_network(net, self.access, self.file)

    def condition(self, holder: Node | None, what: str) -> Expr | None:
        coils = self.network(holder)
        if len(coils) != 1:
            raise ElementError(f"{what} needs exactly one coil", holder or self.fb)
        return coils[0][1]

    # ------------------------------------------------------------ rows

    def row(self, action: Node, step: int) -> ActionRow | None:
        pieces: list[str] = []
        for c in action.children:
            if c.tag == "Token":
                pieces.append(c.get("Text"))
            elif c.tag == "Access":
                pieces.append(self.access_text(c))
                try:
                    self.action_tag(c)
                except ElementError as exc:
                    self.p.warn(
                        "I023",
                        f"step {step}: action row with {pieces[-1]} not imported: {exc.message}",
                        self.at(exc.node),
                    )
                    return None
        text = "".join(pieces).strip()
        qualifier = action.get("Qualifier")
        if not text and not qualifier:
            return None  # the empty row that ends an action table
        event = action.get("Event")
        head = f"{event} " if event else ""
        head += qualifier + ("C" if action.flag("Interlock") else "")
        body = _graph_text(text.replace("\n", " "), self.is_db)
        source = (
            f'FUNCTION_BLOCK "x" SEQUENCE 1 STEP S{step}:\n{head} {body};\n'
            "END_STEP END_SEQUENCE END_FUNCTION_BLOCK"
        )
        try:
            chart = parse_chart(source, self.file)
        except ChartSyntaxError as exc:
            self.p.warn(
                "I021",
                f"action row {head} {text!r} not imported: {exc.diagnostics[0].message}",
                self.at(action),
            )
            return None
        row = chart.sequences[0].steps[0].actions[0]
        self.row_symbols(row, action)
        return _relocated(row, self.at(action))  # type: ignore[return-value]

    def row_symbols(self, row: ActionRow, at: Node) -> None:
        """Declare the tags a row names, typed by their use: a bit for N S R D L, a TIME
        for a D/L time, an assignment's target the type of its value."""
        op = row.operand
        if isinstance(op, Operand) and op.quoted and not op.member:
            want = {"D": "BOOL", "L": "BOOL", "N": "BOOL", "S": "BOOL", "R": "BOOL"}.get(
                row.qualifier
            )
            self.symbol(op.name, want, at)
        if isinstance(row.value, Operand) and row.value.quoted and not row.value.member:
            self.symbol(row.value.name, "TIME", at)
        if isinstance(op, Assignment):
            value_type = self.expr_type(op.expr)
            for o in nodes(op.expr):
                if isinstance(o, Operand) and o.quoted and not o.member:
                    self.symbol(o.name, value_type, at)
            if op.target.quoted:
                self.symbol(op.target.name, value_type or "INT", at)

    def expr_type(self, e: Expr) -> str | None:
        if isinstance(e, Const):
            return "INT" if e.type in ("INT", "DINT") and e.text.lstrip("-").isdigit() else e.type
        if isinstance(e, Operand):
            if e.quoted:
                return self.types.get(e.name)
            v = self.vars.get(e.name)
            return v.type if v is not None else None
        for child in (
            getattr(e, "left", None),
            getattr(e, "right", None),
            getattr(e, "operand", None),
        ):
            if child is not None:
                t = self.expr_type(child)
                if t is not None:
                    return t
        return None

    # ------------------------------------------------------------ the block

    def variables(self) -> None:
        self.block_constants()
        for section in self.fb.iter("Section"):
            if section.get("Name") != "Static" or section.parent is None:
                continue
            if section.parent.tag != "Sections" or section.parent.get("Datatype"):
                continue  # the GRAPH base section
            for m in section.all("Member"):
                t = m.get("Datatype").upper().strip('"')
                if t.startswith("G7_"):
                    continue
                graph_type = TIA_TYPES.get(t.split("[")[0], "")
                if graph_type == "STRING" and (n := re.fullmatch(r"STRING\s*\[\s*(\d+)\s*\]", t)):
                    graph_type = f"STRING[{n[1]}]"  # its length, as TIA declared it
                if not graph_type:
                    self.p.warn(
                        "I023",
                        f"static {m.get('Name')} : {m.get('Datatype')} not "
                        "imported: FB variables are of elementary types",
                        self.at(m),
                    )
                    continue
                start = m.child("StartValue")
                init: Const | None = None
                if start is not None and start.text.strip():
                    text = start.text.strip()
                    try:
                        init = const(text.upper() if graph_type == "BOOL" else text, self.at(start))
                    except (LiteralError, S7Error):
                        self.p.warn("I023", f"start value {text!r} not imported", self.at(start))
                self.vars[m.get("Name")] = VarDecl(m.get("Name"), graph_type, init, self.at(m))

    def options(self, kept: dict[str, str]) -> ChartOptions:
        """The block's options: its attributes and pins, and the settings s7graph's export
        kept in the block comment (``kept``)."""
        pins: set[str] = set()
        for section in self.fb.iter("Section"):
            if (
                section.get("Name") in ("Input", "Output")
                and section.parent is not None
                and not section.parent.get("Datatype")
            ):
                pins |= {m.get("Name") for m in section.all("Member")}
        parameters = "STANDARD"
        if pins:
            fits = [s for s in PARAMETER_SETS if {p.name for p in pins_for(s)} == pins]
            if fits:
                parameters = fits[0]
            else:
                bigger = [s for s in PARAMETER_SETS if {p.name for p in pins_for(s)} >= pins]
                parameters = bigger[0] if bigger else "USER"
                self.p.warn(
                    "I031",
                    f"the FB's pins are no GRAPH parameter set; read as {parameters}",
                    self.at(self.fb),
                )
        for name, what in (
            ("LockOperatingMode", "lock operating mode"),
            ("PermanentILProcessingInMANMode", "permanent interlock processing in MAN"),
        ):
            if is_true(self.attr(name)):
                self.p.warn(
                    "I020",
                    f"the block setting {what} is not imported (its behaviour is not documented)",
                    self.at(self.fb),
                )
        return ChartOptions(
            parameters=parameters,
            skip_steps=is_true(self.attr("SkipSteps")),
            ack_required=self.attr("AcknowledgeErrorsRequired").strip().lower()
            not in ("false", "0"),
            messages=is_true(self.attr("WithAlarmHandling")),
            ack_forces_switch=kept.get("ACK_FORCES_SWITCH") == "TRUE",
            order="codesys" if kept.get("ORDER") == "CODESYS" else "graph",
        )

    def kept(self) -> dict[str, str]:
        """What s7graph's export kept in the block comment (``s7graph: DB 1; ORDER := …``),
        read in one pass: its settings, returned, and its DB symbols (``"T_S2" : DB10 :
        SFB4``) into ``dbs`` — the chart reads those DBs' variables by name."""
        out: dict[str, str] = {}
        for item in self.fb.iter("MultilingualTextItem"):
            text = item.find("AttributeList", "Text")
            body = text.text.strip() if text is not None else ""
            if not body.startswith(S7GRAPH_COMMENT):
                continue
            for m in _KEPT_DB.finditer(body):
                decl = SymbolDecl(m[1], f"DB{m[2]}", m[3], "", self.at(item))
                self.dbs.setdefault(m[1].casefold(), decl)
            for part in body[len(S7GRAPH_COMMENT) :].split(";"):
                key, _, value = part.strip().partition(":=")
                if key.strip().startswith("DB ") and key.strip()[3:].isdigit():
                    out["DB"] = key.strip()[3:]
                elif value:
                    out[key.strip().upper()] = value.strip().upper()
        return out

    def chart(self, graph: Node) -> Chart:
        kept = self.kept()
        self.variables()
        opts = self.options(kept)
        seq_nodes = graph.all("Sequence")
        self.numbers(seq_nodes)
        before = self.permanent(graph.child("PreOperations"))
        sequences = tuple(self.sequence(q, i + 1) for i, q in enumerate(seq_nodes))
        after = self.permanent(graph.child("PostOperations"))
        self.p.fail_if_errors()
        used = {
            b
            for n in nodes((before, sequences, after))
            if isinstance(n, Operand) and not n.quoted
            for b in used_bytes(n.name)
        }
        symbols = self.finish_symbols(used) + not_in_table(self.dbs.values(), self.known)
        self.p.fail_if_errors()
        name = self.attr("Name") or "GRAPH"
        number = self.attr("Number")
        db = kept.get("DB")
        chart = Chart(
            name=name,
            fb_number=int(number) if number.isdigit() else None,
            db_number=int(db) if db is not None else None,
            options=opts,
            vars=tuple(self.vars.values()),
            symbols=symbols,
            before=before,
            sequences=sequences,
            after=after,
            file=self.file,
            loc=self.at(self.fb),
        )
        chart = accepted(chart, self.p, self.known)
        constants = {v.upper() for v in self.constant_vars.values()}
        why = {
            graph.upper(): f"is the constant {name}, whose value the export does not carry "
            "(it starts at 0)"
            for name, graph in self.constant_vars.items()
        }
        report_stalls(chart, self.p, constants, why)
        return chart

    def numbers(self, seq_nodes: list[Node]) -> None:
        """Every step's and transition's number by its name; a ``Number`` that is not an
        integer is an error (I013) naming the step or transition, and no chart."""
        holders: dict[tuple[str, int], str] = {}
        for q in seq_nodes:
            for what, el in [("step", s) for s in q.iter("Step")] + [
                ("transition", t) for t in q.iter("Transition")
            ]:
                names = self.step_names if what == "step" else self.trans_names
                name = el.get("Name")
                try:
                    number = _number(el, "Number")
                    if not 1 <= number <= MAX_NUMBER:
                        raise ElementError(f"Number {number} is outside 1..{MAX_NUMBER}", el)
                    first = holders.setdefault((what, number), name)
                    if first != name:
                        raise ElementError(f'Number {number} is {what} "{first}"\'s too', el)
                    names[name if name.strip() else default_name(what, number)] = number
                except ElementError as exc:
                    self.p.error(
                        "I013",
                        f'{what} "{name}": {exc.message} (GRAPH numbers {what}s 1, 2, …)',
                        self.at(el),
                    )
        self.p.fail_if_errors()

    def permanent(self, holder: Node | None) -> tuple[PermanentInstruction, ...]:
        out: list[PermanentInstruction] = []
        for op in holder.all("PermanentOperation") if holder is not None else []:
            try:
                for coil, cond in self.network(op):
                    out.append(self.coil(coil, cond, op))
                net = op.child("FlgNet")
                for box in read_boxes(net, self.access, self.file) if net is not None else []:
                    out.append(self.box(box))
            except ElementError as exc:
                self.p.warn(
                    "I022", f"permanent operation not imported: {exc.message}", self.at(exc.node)
                )
        return tuple(out)

    def box(self, box: Box) -> PermanentInstruction:
        """A ``Move`` box: an assignment; a ``Call`` box: a CALL of the block by its number
        (``FC2``, an instance ``DB10``) or by its name."""
        loc = self.at(box.node)
        outs: list[tuple[str, Operand]] = []
        for pin, e in box.outputs:
            if not isinstance(e, Operand):
                raise ElementError(f"output {pin} feeds no variable", box.node)
            outs.append((pin, e))
        if box.name == "Move":
            if len(box.inputs) != 1 or len(outs) != 1:
                raise ElementError("a MOVE box needs one input and one output", box.node)
            return permanent_assignment(outs[0][1], box.inputs[0][1], loc)
        m = _BLOCK.fullmatch(box.name.replace(" ", ""))
        kind, block = (m[1].upper(), int(m[2])) if m else ("", box.name)
        instance: int | str | None = box.instance
        if box.instance is not None and (d := _DB.fullmatch(box.instance.replace(" ", ""))):
            instance = int(d[1])
        return BlockCall(kind, block, instance, box.inputs, tuple(outs), loc)

    def coil(self, coil: Node, cond: Expr | None, op: Node) -> PermanentInstruction:
        net = op.child("FlgNet")
        assert net is not None
        target: Expr | None = None
        wires = net.child("Wires")
        for w in wires.children if wires is not None else []:
            ends = w.children
            if (
                ends
                and ends[0].tag == "IdentCon"
                and any(
                    e.get("UId") == coil.get("UId") and e.get("Name") == "operand" for e in ends[1:]
                )
            ):
                uid = ends[0].get("UId")
                acc = next((p for p in net.iter("Access") if p.get("UId") == uid), None)
                if acc is None:
                    raise ElementError(
                        f'the coil\'s operand is UId "{uid}", which no Access has', w
                    )
                target = self.access(acc, "BOOL")
        if not isinstance(target, Operand):
            raise ElementError("a coil without an operand", coil)
        value = cond if cond is not None else Const(True, "BOOL", "TRUE", self.at(coil))
        kind = {"SCoil": "S", "RCoil": "R"}.get(coil.get("Name"), "=")
        if kind == "=":
            return permanent_assignment(target, value, self.at(coil))
        return Coil(kind, target, value, self.at(coil))  # type: ignore[arg-type]

    def step(self, s: Node) -> Step:
        number = _number(s, "Number")  # checked by numbers()
        rows = []
        actions = s.child("Actions")
        for a in actions.all("Action") if actions is not None else []:
            row = self.row(a, number)
            if row is not None:
                rows.append(row)
        interlock = supervision = None
        message = ""
        try:
            il = s.find("Interlocks", "Interlock")
            interlock = self.condition(il, "an interlock") if il is not None else None
            sv = s.find("Supervisions", "Supervision")
            supervision = self.condition(sv, "a supervision") if sv is not None else None
            for holder in (sv, il):
                text = holder.find("AlarmText", "MultiLanguageText") if holder is not None else None
                if text is not None and text.text.strip() and not message:
                    message = text.text.strip()
        except ElementError as exc:
            self.p.error("I012", f"step {number}: {exc.message}", self.at(exc.node))
        for attr in ("MaximumStepTime", "WarningTime"):
            if s.get(attr) and s.get(attr).upper() not in ("T#10S", "T#7S", "T#0MS", "T#0S"):
                self.p.warn(
                    "I020",
                    f"step {number}: {attr} {s.get(attr)} is not imported (a "
                    "supervision can compare Sn.T)",
                    self.at(s),
                )
        return Step(
            number,
            s.get("Name"),
            s.flag("Init"),
            message,
            interlock,
            supervision,
            tuple(rows),
            self.at(s),
            self.at(s) if interlock is not None else None,
            self.at(s) if supervision is not None else None,
        )

    def sequence(self, q: Node, number: int) -> Sequence:
        steps = [self.step(s) for s in q.iter("Step")]
        title = q.find("Title", "MultiLanguageText")
        name = title.text.strip() if title is not None else ""
        trans = {_number(t, "Number"): t for t in q.iter("Transition")}  # checked by numbers()
        links = _Links(q, self)
        if links.broken:
            self.p.fail_if_errors()
        out: list[Transition] = []
        for n, t in trans.items():
            try:
                cond = self.condition(t, f"transition {n}")
            except ElementError as exc:
                self.p.error("I012", f"transition {n}: {exc.message}", self.at(exc.node))
                continue
            sources, targets = links.sources(n), links.targets(n)
            if not sources:
                self.p.error("I011", f"transition {n} has no preceding step", self.at(t))
                continue
            if targets is None:
                self.p.error("I011", f"transition {n} leads nowhere", self.at(t))
                continue
            out.append(
                Transition(
                    n,
                    _transition_name(t, n),
                    tuple(sources),
                    tuple(targets),
                    cond,
                    self.at(t),
                    tuple(self.at(t) for _ in sources),
                    tuple(self.at(t) for _ in targets),
                )
            )
        out = links.in_priority_order(out)
        return Sequence(number, name, tuple(steps), tuple(out), self.at(q))


class _Links:
    """The ``Connections`` of one sequence."""

    def __init__(self, q: Node, reader: _Reader) -> None:
        self.out: dict[tuple[str, int, int], list[tuple[str, int, int]]] = {}
        self.into: dict[tuple[str, int, int], list[tuple[str, int, int]]] = {}
        self.types: dict[int, str] = {}
        self.broken = False  # a branch or connection whose numbers are no numbers (I010)
        try:
            for b in q.iter("Branch"):
                self.types[_number(b, "Number")] = b.get("Type")
        except ElementError as exc:
            self.broken = True
            reader.p.error("I010", f"a branch's {exc.message}", reader.at(exc.node))
        for c in q.iter("Connection"):
            src, dst = c.child("NodeFrom"), c.child("NodeTo")
            if src is None or dst is None or not src.children or not dst.children:
                continue
            try:
                head, tail = _node(src.children[0], "Out"), _node(dst.children[0], "In")
            except ElementError as exc:
                self.broken = True
                reader.p.error(
                    "I010",
                    f"a connection's {exc.node.tag} {exc.message} (a connection names "
                    "its ends by number)",
                    reader.at(exc.node),
                )
                continue
            self.out.setdefault(head, []).append(tail)
            self.into.setdefault(tail, []).append(head)

    def upstream(self, node: tuple[str, int, int], seen: frozenset[int] = frozenset()) -> list[int]:
        """The steps a connection comes from, through branches (a branch that leads back
        into itself gives none)."""
        kind, n, _ = node
        if kind == "S":
            return [n]
        if kind == "B" and n not in seen:
            found: list[int] = []
            for (k, m, _), srcs in self.into.items():
                if k == "B" and m == n:
                    for s in srcs:
                        found += self.upstream(s, seen | {n})
            return found
        return []

    def downstream(
        self, node: tuple[str, int, int], seen: frozenset[int] = frozenset()
    ) -> list[int] | None:
        """The steps a connection leads to, through branches (a branch that leads back
        into itself gives none)."""
        kind, n, _ = node
        if kind == "S":
            return [n]
        if kind == "E":
            return []
        if kind == "B" and n not in seen:
            found: list[int] = []
            for key in sorted(k for k in self.out if k[0] == "B" and k[1] == n):
                for d in self.out[key]:
                    got = self.downstream(d, seen | {n})
                    if got:
                        found += got
            return found
        return None if kind != "B" else []

    def sources(self, t: int) -> list[int]:
        found: list[int] = []
        for src in self.into.get(("T", t, 0), []):
            found += self.upstream(src)
        return found

    def targets(self, t: int) -> list[int] | None:
        dsts = self.out.get(("T", t, 0), [])
        if not dsts:
            return None
        found: list[int] = []
        for d in dsts:
            got = self.downstream(d)
            if got is None:
                return None
            found += got
        return found

    def branch_index(self, t: int) -> tuple[int, int] | None:
        """(AltBegin number, Out index) of a transition that starts an alternative path."""
        for src in self.into.get(("T", t, 0), []):
            if src[0] == "B" and self.types.get(src[1]) == "AltBegin":
                return src[1], src[2]
        return None

    def in_priority_order(self, trs: list[Transition]) -> list[Transition]:
        """As written, except that the paths of each alternative branch take their places
        in the order of the branch's outputs (leftmost first)."""
        groups: dict[int, list[int]] = {}
        for i, t in enumerate(trs):
            b = self.branch_index(t.number)
            if b is not None:
                groups.setdefault(b[0], []).append(i)
        out = list(trs)
        for idxs in groups.values():
            ordered = sorted(
                (trs[i] for i in idxs), key=lambda t: self.branch_index(t.number) or (0, 0)
            )
            for i, t in zip(idxs, ordered, strict=True):
                out[i] = t
        return out


def _node(el: Node, port: str) -> tuple[str, int, int]:
    """A connection's end: (S|T|B|E|?, number, port); ``ElementError`` for a number that
    is not one (``<StepRef Number="Symbol"/>``)."""
    if el.tag == "EndConnection":
        return ("E", 0, 0)
    kind = {"StepRef": "S", "TransitionRef": "T", "BranchRef": "B"}.get(el.tag, "?")
    return (kind, _number(el, "Number", 0), _number(el, port, 0))


def _transition_name(t: Node, number: int) -> str:
    """A transition's name as its author gave it: none ("") for no ``Name``, an empty one
    or TIA's default for its number (``Trans3``), which TIA gives a transition nobody
    named — so that an export writes that default again and a round trip changes nothing."""
    name = t.get("Name")
    return "" if name.strip() in ("", default_name("transition", number)) else name


def _number(el: Node, attr: str, missing: int | None = None) -> int:
    """The integer attribute ``attr`` of ``el`` (``missing`` when it is absent or empty, if
    given); ``ElementError`` naming the element, the attribute and its value otherwise."""
    text = el.get(attr).strip()
    if not text and missing is not None:
        return missing
    if not re.fullmatch(r"[+-]?\d+", text):
        what = f'{attr}="{el.get(attr)}" is not a number' if text else f"has no {attr}"
        raise ElementError(what, el)
    return int(text)


_BLOCK = re.compile(r"(FB|FC|SFB|SFC)(\d+)", re.IGNORECASE)
_DB = re.compile(r"DB(\d+)", re.IGNORECASE)
_GLOBAL = re.compile(r'"((?:[^"]|"")*)"((?:\.[A-Za-z_][A-Za-z0-9_]*|\[[^\]]*\])*)')
_LOCAL = re.compile(r"#([A-Za-z_][A-Za-z0-9_]*)")
_ABSOLUTE = re.compile(
    r"%((?:P?[IQ]|M)[XBWD]?\d+(?:\.\d+)?|[TC]\d+|DB\d+\.DB[XBWD]\d+(?:\.\d+)?)(?![\w.])",
    re.IGNORECASE,
)


def _graph_text(text: str, is_db: Callable[[str], bool]) -> str:
    """A TIA action row's operand text in `.s7g` spelling (a DB symbol's member stays a
    read of the DB's variable: ``"T_S2".ET``)."""

    def tag(m: re.Match[str]) -> str:
        if is_db(m[1]) and re.fullmatch(r"\.[A-Za-z_][A-Za-z0-9_]*", m[2]):
            return m[0]
        return '"' + m[1] + m[2] + '"'

    text = _GLOBAL.sub(tag, text)
    text = _LOCAL.sub(lambda m: m.group(1), text)
    return _ABSOLUTE.sub(lambda m: m.group(1), text)


def _relocated(obj: object, loc: SourceLocation) -> object:
    """``obj`` with every place set to ``loc`` (a row parsed from a TIA action's text)."""
    import dataclasses

    if isinstance(obj, SourceLocation):
        return loc
    if isinstance(obj, tuple):
        return tuple(_relocated(x, loc) for x in obj)
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        return replace(
            obj,
            **{f.name: _relocated(getattr(obj, f.name), loc) for f in dataclasses.fields(obj)},
        )
    return obj


def read_simaticml(root: Node, problems: Problems, symbols: SymbolTable | None = None) -> Chart:
    """The GRAPH FB of a SimaticML document (raises ``ImportFailed``)."""
    fbs = [
        fb
        for fb in root.iter("SW.Blocks.FB")
        if (fb.find("AttributeList", "ProgrammingLanguage") or fb).text.strip() == "GRAPH"
    ]
    if not fbs:
        problems.error("I004", "no S7-GRAPH FB in the document", root.loc(problems.file))
        problems.fail_if_errors()
    fb = fbs[0]
    if len(fbs) > 1:
        problems.warn(
            "I005",
            f"{len(fbs)} GRAPH FBs in the document; the first is imported",
            fb.loc(problems.file),
        )
    graph = next(fb.iter("Graph"), None)
    if graph is None:
        problems.error("I004", "the FB has no GRAPH network source", fb.loc(problems.file))
        problems.fail_if_errors()
    assert graph is not None
    reader = _Reader(fb, problems, symbols)
    try:
        return reader.chart(graph)
    except ElementError as exc:  # one no part of the reader placed: located all the same
        problems.error("I001", f"<{exc.node.tag}>: {exc.message}", exc.node.loc(problems.file))
        raise ImportFailed(problems.items) from None
