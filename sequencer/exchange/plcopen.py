"""Read PLCopen TC6 XML SFC bodies (tc6_0200, tc6_0201 and the old ``tc6.xsd`` namespace)
into ``IecChart`` s, in the Beremiz/OpenPLC, CODESYS and TwinCAT dialects.

The chart's shape comes from the ``connectionPointIn`` references between its elements:
a transition's preceding steps are found back through selection divergences and
simultaneous convergences, its following steps forward through selection convergences,
simultaneous divergences and jump steps (IEC 61131-3 §6.7; PLCopen TC6 XML 2.01 §6.6).
Conditions are inline ST, references to named transitions (ST, LD or FBD bodies) or wired
from networks of the SFC body (``exchange.networks``); actions are action blocks of a
step, inline or named. CODESYS step actions (entry, active, exit) are read from the
step's vendor data. A file written by s7graph carries its `.s7g` source in the POU's
``addData`` and is read from it while the SFC is what the export wrote
(``exchange.own_data``); an SFC edited since is read as any other.
"""

from __future__ import annotations

from dataclasses import dataclass

from s7graph.engine.errors import SourceLocation
from s7graph.sequencer.exchange.iec_model import (
    IecAction,
    IecAssociation,
    IecChart,
    IecStep,
    IecTransition,
    IecVar,
    StatementBody,
    Unsupported,
)
from s7graph.sequencer.exchange.networks import Network
from s7graph.sequencer.exchange.problems import Problems
from s7graph.sequencer.exchange.st import (
    SExpr,
    SLiteral,
    StSyntaxError,
    parse_expression,
    parse_statements,
)
from s7graph.sequencer.exchange.xmltree import ElementError, Node

__all__ = ["S7GRAPH_DATA", "TRANSITION_IDS", "Kept", "read_plcopen"]

S7GRAPH_DATA = "urn:s7graph:chart"
TRANSITION_IDS = 100_000  # s7graph's export: a transition's localId is this plus its number
CODESYS_DATA = "http://www.3s-software.com/plcopenxml/sfc/element"
_CODESYS_STEP_ACTIONS = {
    "a6b08bd8-b696-47e3-9cbf-7408b61c9ff8": "entry",
    "700a583f-b4d4-43e4-8c14-629c7cd3bec8": "active",
    "a2621e18-7de3-4ea6-ae6d-89e9e0b7befd": "exit",
}
_CODESYS_PRIORITY = "8294df19-5962-4dee-a874-1051dabb0e3e"
_CODESYS_TIMES = {
    "cacf1a68-236e-47c2-b7b1-1cf9199718cb": "minimum time",
    "b693554c-1b01-4a8d-afde-9e3a46f7465d": "maximum time",
}
_SECTIONS = {
    "inputVars": "input",
    "outputVars": "output",
    "inOutVars": "inout",
    "localVars": "local",
    "externalVars": "external",
    "globalVars": "global",
    "tempVars": "temp",
}


def dialect_of(root: Node) -> str:
    """beremiz | codesys | twincat | s7graph | iec, from the file header."""
    head = root.child("fileHeader")
    text = " ".join(head.attrib.values()).lower() if head is not None else ""
    for key, name in (
        ("s7graph", "s7graph"),
        ("beckhoff", "twincat"),
        ("twincat", "twincat"),
        ("codesys", "codesys"),
        ("3s", "codesys"),
        ("beremiz", "beremiz"),
        ("openplc", "beremiz"),
    ):
        if key in text.split() or key in text:
            return name
    return "iec"


def s7graph_source(pou: Node) -> tuple[str, int, int] | None:
    """The `.s7g` text s7graph wrote into a POU's ``addData``, with its place."""
    for data in pou.iter("data"):
        if data.get("name") == S7GRAPH_DATA:
            text, line, col = data.deep_text()
            if text.strip():
                return text, line, col
    return None


class _Reader:
    def __init__(self, root: Node, problems: Problems) -> None:
        self.root = root
        self.p = problems
        self.file = problems.file
        self.dialect = dialect_of(root)
        self.aliases: dict[str, Node] = {d.get("name").upper(): d for d in root.iter("dataType")}
        self.warned_types: set[str] = set()
        self.globals: dict[str, IecVar] = {}
        for section in root.iter("globalVars"):
            for v in self.variables(section, "global"):
                self.globals[v.name.upper()] = v

    def at(self, node: Node) -> SourceLocation:
        return node.loc(self.file)

    # ------------------------------------------------------------ declarations

    def type_of(self, var: Node) -> str:
        t = var.child("type")
        if t is None or not t.children:
            return "BOOL"
        first = t.children[0]
        if first.tag == "derived":
            return self.resolve(first.get("name"), first, set())
        if first.tag in ("string", "wstring"):
            length = first.get("length")
            return f"STRING[{length}]" if length else "STRING"
        if first.tag == "array":
            return self.array(first)
        return first.tag.upper()

    def array(self, node: Node) -> str:
        """``ARRAY OF <element type>`` (the element type resolved as far as it goes)."""
        inner = node.child("baseType")
        elem = inner.children[0] if inner is not None and inner.children else None
        if elem is None:
            return "ARRAY OF ?"
        if elem.tag == "derived":
            return "ARRAY OF " + self.resolve(elem.get("name"), elem, set())
        return "ARRAY OF " + elem.tag.upper()

    def resolve(self, name: str, at: Node, seen: set[str]) -> str:
        """A derived type: its elementary base when it is an alias or a subrange (the range
        is not checked in GRAPH: reported), else its name."""
        d = self.aliases.get(name.upper())
        if d is None or name.upper() in seen:
            return name.upper()
        base = d.child("baseType")
        first = base.children[0] if base is not None and base.children else None
        if first is None:
            return name.upper()
        if first.tag == "derived":
            return self.resolve(first.get("name"), at, seen | {name.upper()})
        if first.tag in ("subrangeSigned", "subrangeUnsigned"):
            inner = first.find("baseType")
            rng = first.child("range")
            elem = inner.children[0].tag.upper() if inner is not None and inner.children else ""
            if elem and name.upper() not in self.warned_types:
                self.warned_types.add(name.upper())
                bounds = f"{rng.get('lower')}..{rng.get('upper')}" if rng is not None else ""
                self.p.warn(
                    "I023",
                    f"type {name} is {elem} {bounds}: GRAPH does not check the range",
                    self.at(d),
                )
            return elem or name.upper()
        if first.tag == "array":
            return self.array(first)
        if first.tag in ("enum", "struct"):
            return name.upper()
        return first.tag.upper()

    def variables(self, section: Node, kind: str) -> list[IecVar]:
        out: list[IecVar] = []
        for v in section.all("variable"):
            init: SExpr | None = None
            simple = v.find("initialValue", "simpleValue")
            if simple is not None and simple.get("value"):
                init = self.literal(simple.get("value"), simple)
            out.append(
                IecVar(
                    v.get("name"),
                    self.type_of(v),
                    kind,
                    self.at(v),
                    v.get("address").upper(),
                    init,
                    constant=section.flag("constant"),
                )
            )
        return out

    def literal(self, text: str, node: Node) -> SExpr | None:
        try:
            return parse_expression(text, self.file, (node.line, node.col), "initial value")
        except StSyntaxError:
            return SLiteral(text, node.line, node.col)

    def interface(self, pou: Node) -> list[IecVar]:
        out: list[IecVar] = []
        iface = pou.child("interface")
        for section in iface.children if iface is not None else []:
            kind = _SECTIONS.get(section.tag)
            if kind is None:
                continue
            for v in self.variables(section, kind):
                if kind == "external":
                    g = self.globals.get(v.name.upper())
                    if g is not None:
                        v.init = v.init or g.init
                        v.address = v.address or g.address
                        v.type = g.type if v.type == "BOOL" and g.type else v.type
                out.append(v)
        return out

    # ------------------------------------------------------------ bodies

    def st_text(self, node: Node) -> tuple[str, tuple[int, int]]:
        text, line, col = node.deep_text()
        return text, (line, col)

    def body_of(self, holder: Node) -> Node | None:
        """The language element of a ``body`` (or of an ``inline``)."""
        for lang in ("ST", "LD", "FBD", "IL", "SFC"):
            found = holder.child(lang)
            if found is not None:
                return found
        return None

    def statements(self, name: str, holder: Node, loc: SourceLocation) -> IecAction:
        """Action ``name`` of the body ``holder`` (a ``body`` or an ``inline``)."""
        lang = self.body_of(holder)
        if lang is None:
            return IecAction(name, Unsupported("an empty or unknown action body", loc), loc)
        if lang.tag == "ST":
            text, origin = self.st_text(lang)
            try:
                stmts = parse_statements(text, self.file, origin, f"action {name}")
                return IecAction(name, stmts, loc, origin, text)
            except StSyntaxError as exc:
                where = exc.where if isinstance(exc.where, SourceLocation) else self.at(lang)
                what = Unsupported(f"ST that does not parse ({exc.message})", where)
                return IecAction(name, what, loc, origin, text)
        if lang.tag in ("LD", "FBD"):
            try:
                return IecAction(name, Network(lang, self.file).statements(), loc)
            except ElementError as exc:
                what = Unsupported(f"a {lang.tag} network with {exc.message}", self.at(exc.node))
                return IecAction(name, what, loc)
        return IecAction(name, Unsupported(f"an {lang.tag} body", self.at(lang)), loc)

    def actions(self, pou: Node) -> dict[str, IecAction]:
        out: dict[str, IecAction] = {}
        holder = pou.child("actions")
        for a in holder.all("action") if holder is not None else []:
            body = a.child("body")
            name = a.get("name")
            if body is None or _sfc_of(a) is not None:
                continue  # an action's chart is a chart of its own
            out[name.upper()] = self.statements(name, body, self.at(a))
        return out

    def named_transitions(
        self, pou: Node
    ) -> dict[str, tuple[SExpr | Unsupported | StatementBody, tuple[int, int]]]:
        out: dict[str, tuple[SExpr | Unsupported | StatementBody, tuple[int, int]]] = {}
        holder = pou.child("transitions")
        for t in holder.all("transition") if holder is not None else []:
            name = t.get("name")
            body = t.child("body")
            lang = self.body_of(body) if body is not None else None
            if lang is None:
                out[name.upper()] = (
                    Unsupported(f"transition {name} without a body", self.at(t)),
                    (1, 1),
                )
            elif lang.tag == "ST":
                text, origin = self.st_text(lang)
                out[name.upper()] = (self.st_condition(text, origin, lang, name), origin)
            elif lang.tag in ("LD", "FBD"):
                try:
                    network = Network(lang, self.file)
                    value = network.output_named(name)
                    for call in network.calls:
                        self.p.warn(
                            "I022",
                            f"transition {name}: its {lang.tag} body calls {call.name}, "
                            "which is not imported (a condition calls no block); its "
                            "outputs keep the values the chart's own calls give them",
                            SourceLocation(self.file, call.line, call.col),
                        )
                except ElementError as exc:
                    value = None
                    out[name.upper()] = (
                        Unsupported(f"a network with {exc.message}", self.at(exc.node)),
                        (1, 1),
                    )
                    continue
                if value is None:
                    out[name.upper()] = (
                        Unsupported(
                            f"transition {name}: its {lang.tag} body writes no {name}",
                            self.at(lang),
                        ),
                        (1, 1),
                    )
                else:
                    out[name.upper()] = (value, (1, 1))
            else:
                out[name.upper()] = (
                    Unsupported(f"an {lang.tag} transition body", self.at(lang)),
                    (1, 1),
                )
        return out

    def st_condition(
        self, text: str, origin: tuple[int, int], node: Node, name: str = ""
    ) -> SExpr | Unsupported | StatementBody:
        """A condition in ST; a named transition's body may read ``:= expr;``, or be
        statements that assign the transition's name (CODESYS, TwinCAT)."""
        body = text.strip()
        lead = len(text) - len(text.lstrip())
        if body.startswith(":="):
            body = body[2:]
            lead += 2
        body = body.rstrip().rstrip(";")
        pad = " " * lead  # keep columns
        try:
            return parse_expression(pad + body, self.file, origin, "condition")
        except StSyntaxError as exc:
            try:
                stmts = parse_statements(text, self.file, origin, "transition")
            except StSyntaxError:
                stmts = []
            if stmts and name:
                return StatementBody(name, stmts, text, self.at(node), origin)
            where = exc.where if isinstance(exc.where, SourceLocation) else self.at(node)
            return Unsupported(f"a condition that does not parse ({exc.message})", where)

    # ------------------------------------------------------------ the chart

    def chart(self, pou: Node, sfc: Node, name: str = "") -> IecChart:
        """The chart of the SFC body ``sfc`` of ``pou`` (or of one of its actions: ``name``
        ``POU.action``), with the POU's variables, actions and transitions."""
        chart = IecChart(
            name or pou.get("name"),
            pou.get("pouType", "program"),
            self.at(pou),
            dialect=self.dialect,
        )
        chart.vars = self.interface(pou)
        chart.actions = self.actions(pou)
        holder = pou.child("actions")
        chart.sfc_actions = {
            a.get("name").upper()
            for a in (holder.all("action") if holder is not None else [])
            if _sfc_of(a) is not None
        }
        named = self.named_transitions(pou)
        net = Network(sfc, self.file)
        by_id = net.by_id
        refs: dict[str, list[Node]] = {}
        for el in sfc.children:
            for c in _connections(el):
                refs.setdefault(c.get("refLocalId"), []).append(el)
        for el in sfc.children:
            if el.tag == "step":
                chart.steps.append(self.step(el))
            elif el.tag == "macroStep":
                self.p.error(
                    "I013",
                    f"macro step {el.get('name')} is not imported (GRAPH has no macro steps)",
                    self.at(el),
                )
        steps = {s.name.upper(): s for s in chart.steps}
        for el in sfc.children:
            if el.tag == "actionBlock":
                self.action_block(el, by_id, steps, chart)
        for order, el in enumerate(e for e in sfc.children if e.tag == "transition"):
            t = self.transition(el, order, by_id, refs, named, net)
            if t is not None:
                chart.transitions.append(t)
        self.computed_blocks(chart, sfc, net)
        return chart

    def computed_blocks(self, chart: IecChart, sfc: Node, net: Network) -> None:
        """The function block instances of the chart's network that its conditions read
        are called every call, as Beremiz calls them: the action ``COMPUTE_FUNCTION_BLOCKS``
        stored (S) on the first initial step, in the order the conditions need them; an
        instance no condition reads is not computed by Beremiz either (reported)."""
        for el in sfc.children:
            if (
                el.tag == "block"
                and el.get("instanceName")
                and el.get("localId") not in net.computed
            ):
                self.p.warn(
                    "I024",
                    f"block {el.get('instanceName')} : {el.get('typeName')} of the chart's "
                    "network feeds no transition; Beremiz does not call it either: not "
                    "imported",
                    self.at(el),
                )
        if not net.calls:
            return
        first = next((s for s in chart.steps if s.initial), None)
        if first is None:
            return  # no chart anyway: the import says so
        name = "COMPUTE_FUNCTION_BLOCKS"
        while name.upper() in chart.actions:
            name += "_"
        loc = SourceLocation(self.file, net.calls[0].line, net.calls[0].col)
        chart.actions[name.upper()] = IecAction(name, list(net.calls), loc)
        first.associations.append(IecAssociation(name, "S", loc))

    def step(self, el: Node) -> IecStep:
        step = IecStep(el.get("name"), el.flag("initialStep"), self.at(el))
        if self.dialect == "s7graph" and el.get("localId").isdigit():
            number = int(el.get("localId"))  # s7graph's export: a step's localId is its number
            step.graph_number = number if 0 < number < TRANSITION_IDS else None
        for attr in el.iter("attribute"):
            phase = _CODESYS_STEP_ACTIONS.get(attr.get("guid").strip("{}"))
            name = attr.text.strip()
            if phase and name:
                step.associations.append(IecAssociation(name, "", self.at(attr), phase=phase))
            what = _CODESYS_TIMES.get(attr.get("guid").strip("{}"))
            if what and name and name not in ("0", "T#0s", "T#0S", "T#0ms"):
                self.p.warn(
                    "I020",
                    f"the step's {what} {name} is not imported (a GRAPH "
                    "supervision can check it: Sn.T)",
                    self.at(attr),
                )
        return step

    def action_block(
        self, el: Node, by_id: dict[str, Node], steps: dict[str, IecStep], chart: IecChart
    ) -> None:
        point = el.child("connectionPointIn")
        conn = point.child("connection") if point is not None else None
        owner = by_id.get(conn.get("refLocalId")) if conn is not None else None
        if owner is None or owner.tag != "step":
            self.p.warn(
                "I024", "an action block not connected to a step; not imported", self.at(el)
            )
            return
        step = steps[owner.get("name").upper()]
        for i, a in enumerate(el.all("action")):
            qualifier = a.get("qualifier", "N") or "N"
            assoc = IecAssociation(
                "", qualifier.upper(), self.at(a), a.get("duration"), a.get("indicator")
            )
            ref = a.child("reference")
            inline = a.child("inline")
            if ref is not None:
                assoc.action = ref.get("name")
            elif inline is not None:
                name = f"{step.name}_inline{i + 1}"
                assoc.action = name
                assoc.inline = self.statements(name, inline, self.at(inline))
            else:
                self.p.warn("I021", "an action without reference or body; not imported", self.at(a))
                continue
            step.associations.append(assoc)

    def previous(self, node: Node | None, by_id: dict[str, Node], at: Node) -> list[str]:
        """The steps before ``node`` (through selection divergences and simultaneous
        convergences)."""
        if node is None:
            raise ElementError("a connection to an element that does not exist", at)
        if node.tag == "step":
            return [node.get("name")]
        conns = _connections(node)
        if node.tag in ("selectionDivergence", "simultaneousConvergence") and conns:
            found: list[str] = []
            for c in conns:
                found += self.previous(by_id.get(c.get("refLocalId")), by_id, c)
            return found
        raise ElementError(f"a transition after a {node.tag}", node)

    def following(
        self, node: Node, refs: dict[str, list[Node]], by_id: dict[str, Node]
    ) -> list[tuple[str, bool]]:
        """The steps after ``node`` (name, reached by a jump)."""
        out: list[tuple[str, bool]] = []
        for nxt in refs.get(node.get("localId"), []):
            if nxt.tag == "step":
                out.append((nxt.get("name"), False))
            elif nxt.tag == "jumpStep":
                out.append((nxt.get("targetName"), True))
            elif nxt.tag in ("selectionConvergence", "simultaneousDivergence"):
                out += self.following(nxt, refs, by_id)
            elif nxt.tag == "macroStep":
                raise ElementError("a transition into a macro step", nxt)
        return out

    def transition(
        self,
        el: Node,
        order: int,
        by_id: dict[str, Node],
        refs: dict[str, list[Node]],
        named: dict[str, tuple[SExpr | Unsupported | StatementBody, tuple[int, int]]],
        net: Network,
    ) -> IecTransition | None:
        try:
            point = el.child("connectionPointIn")
            conns = point.all("connection") if point is not None else []
            sources: list[str] = []
            for c in conns:
                sources += self.previous(by_id.get(c.get("refLocalId")), by_id, c)
            targets = self.following(el, refs, by_id)
        except ElementError as exc:
            self.p.error("I011", exc.message, self.at(exc.node))
            return None
        if not sources:
            self.p.error("I011", "a transition without a preceding step", self.at(el))
            return None
        if not targets:
            self.p.error("I011", "a transition without a following step", self.at(el))
            return None
        cond, origin = self.condition(el, named, net)
        pos = el.child("position")
        priority = el.get("priority")
        for attr in el.iter("attribute"):
            if attr.get("guid").strip("{}") == _CODESYS_PRIORITY and attr.text.strip().isdigit():
                priority = priority or attr.text.strip()
        number = int(el.get("localId")) - TRANSITION_IDS if el.get("localId").isdigit() else 0
        x: float | None = None
        if pos is not None and pos.get("x"):
            try:
                x = float(pos.get("x"))
            except ValueError:  # it orders an alternative's paths: no guess
                self.p.error(
                    "I013",
                    f'a transition\'s position x="{pos.get("x")}" is not a number (it orders '
                    "the paths of an alternative branch, leftmost first)",
                    self.at(pos),
                )
                return None
        return IecTransition(
            sources,
            [n for n, _ in targets],
            cond,
            self.at(el),
            graph_number=number if self.dialect == "s7graph" and 0 < number < 100_000 else None,
            name=el.get("name"),
            priority=int(priority) if priority and priority.lstrip("-").isdigit() else None,
            x=x,
            order=order,
            cond_origin=origin,
            jumps={n for n, j in targets if j},
        )

    def condition(
        self,
        el: Node,
        named: dict[str, tuple[SExpr | Unsupported | StatementBody, tuple[int, int]]],
        net: Network,
    ) -> tuple[SExpr | Unsupported | StatementBody, tuple[int, int]]:
        cond = el.child("condition")
        if cond is None:
            return Unsupported("a transition without a condition", self.at(el)), (1, 1)
        inline = cond.child("inline")
        ref = cond.child("reference")
        point = cond.child("connectionPointIn") or (cond if cond.child("connection") else None)
        if inline is not None:
            lang = self.body_of(inline)
            if lang is not None and lang.tag == "ST":
                text, origin = self.st_text(lang)
                return self.st_condition(text, origin, lang), origin
            what = f"an inline {lang.tag} condition" if lang is not None else "an empty condition"
            return Unsupported(what, self.at(inline)), (1, 1)
        if ref is not None:
            found = named.get(ref.get("name").upper())
            if found is None:
                return Unsupported(
                    f"transition {ref.get('name')}, which the POU does not define", self.at(ref)
                ), (1, 1)
            return found
        if point is not None:
            try:
                return net.value_of(point), (1, 1)
            except ElementError as exc:
                return Unsupported(f"a wired condition with {exc.message}", self.at(exc.node)), (
                    1,
                    1,
                )
        return Unsupported("a condition the importer does not know", self.at(cond)), (1, 1)


def _connections(el: Node) -> list[Node]:
    """The connections into ``el`` (a convergence has one ``connectionPointIn`` per input)."""
    return [c for p in el.all("connectionPointIn") for c in p.all("connection")]


def _sfc_of(holder: Node) -> Node | None:
    """The SFC body of a POU or an action (``<body><SFC>``), or None."""
    return next((b.child("SFC") for b in holder.all("body") if b.child("SFC") is not None), None)


@dataclass(frozen=True, eq=False)
class Kept:
    """A POU s7graph exported: the `.s7g` source it keeps in its ``addData`` (``text`` at
    ``line``, ``col``), trusted only while the POU is what s7graph's export of it writes
    (``exchange.own_data``); else its charts are read from its SFC (``sfc``)."""

    text: str
    line: int
    col: int
    pou: Node
    reader: _Reader

    @property
    def name(self) -> str:
        return self.pou.get("name")

    @property
    def root(self) -> Node:
        """The document the POU is in."""
        return self.reader.root

    def sfc(self) -> list[IecChart]:
        """The POU's charts read from its SFC, as any other tool's."""
        return _pou_charts(self.reader, self.pou)


def _pou_charts(reader: _Reader, pou: Node) -> list[IecChart]:
    """The charts of a POU with an SFC body: its own, and one for each action drawn in
    SFC (``POU.action``)."""
    out: list[IecChart] = []
    sfc, in_actions = _sfc_bodies(pou)
    if sfc is not None:
        out.append(reader.chart(pou, sfc))
    elif pou.all("body"):
        charts = ", ".join(f"{pou.get('name')}.{a.get('name')}" for a, _ in in_actions)
        reader.p.warn(
            "I024",
            f"the {_languages(pou)} body of POU {pou.get('name')} is not "
            f"imported; the charts of its actions are, each on its own ({charts})",
            reader.at(pou),
        )
    for action, body in in_actions:
        chart = reader.chart(pou, body, f"{pou.get('name')}.{action.get('name')}")
        chart.loc = reader.at(action)
        out.append(chart)
    return out


def _languages(pou: Node) -> str:
    """The languages of a POU's bodies, as ``FBD/ST``."""
    return "/".join(sorted({c.tag for b in pou.all("body") for c in b.children}))


def _sfc_bodies(pou: Node) -> tuple[Node | None, list[tuple[Node, Node]]]:
    """A POU's SFC body and its actions' (each with the action)."""
    holder = pou.child("actions")
    in_actions = [
        (a, found)
        for a in (holder.all("action") if holder is not None else [])
        if (found := _sfc_of(a)) is not None
    ]
    return _sfc_of(pou), in_actions


def read_plcopen(root: Node, problems: Problems) -> list[IecChart | Kept]:
    """Every SFC body: a POU's (a chart named after the POU), an action's (TwinCAT and
    CODESYS draw charts in actions: one named ``POU.action``, with the POU's variables,
    actions and transitions) — an ``IecChart`` each — or, for a POU s7graph exported, the
    `.s7g` source it keeps (``Kept``: whether to trust it is decided for the chart picked
    alone, as it costs an export)."""
    reader = _Reader(root, problems)
    out: list[IecChart | Kept] = []
    for pou in root.iter("pou"):
        sfc, in_actions = _sfc_bodies(pou)
        if sfc is None and not in_actions:
            problems.warn(
                "I024",
                f"POU {pou.get('name')} ({_languages(pou) or 'no body'})"
                " has no SFC body; not imported",
                reader.at(pou),
            )
            continue
        source = s7graph_source(pou)
        if source is not None:
            out.append(Kept(*source, pou, reader))
        else:
            out.extend(_pou_charts(reader, pou))
    for conf in root.iter("configuration"):
        problems.warn(
            "I024",
            f"configuration {conf.get('name')} not imported: its tasks and "
            "instances call POUs; a GRAPH FB is called from OB1",
            reader.at(conf),
        )
    return out
