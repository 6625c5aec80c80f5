"""PLCopen LD and FBD networks read as ST: what a wire carries, and what a network writes.

A wire's value (``value_of``) follows ``connectionPointIn`` back to its source: a left power
rail is TRUE, a contact ANDs its variable (negated: NOT) with what feeds it, several
connections into one point are an OR (parallel branches), an ``inVariable`` is its ST
expression, a function block of the standard logic and comparison functions (AND OR XOR
NOT, GT GE EQ NE LE LT, ADD SUB MUL DIV MOD, MOVE) is the operator, an output of a function
block instance (``TON3.Q``) is that instance's member, a continuation is its connector's
input. A network's statements (``statements``) are its coils (set/reset coils as such),
output variables and inout variables, in execution order, and its calls of function
block instances with their wired inputs. ``SEL`` is the function call ``SEL(G, IN0, IN1)``
(the importer maps it on BOOLs).

The network of an SFC body: reading a condition wired from an output of a function block
instance (``TON3.Q``) computes that instance — its inputs first, depth first — as Beremiz
does (``PLCGenerator``: the blocks a condition needs become the action
``COMPUTE_FUNCTION_BLOCKS``, stored on the first initial step); ``calls`` holds those calls
in that order, each instance once, and an instance output read while the instance is being
computed is its stored value, not a feedback loop.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from s7graph.sequencer.exchange.st import (
    SAssign,
    SBinary,
    SCall,
    SCallStmt,
    SExpr,
    SLiteral,
    SName,
    SSetReset,
    SStmt,
    StSyntaxError,
    SUnary,
    absolute,
    parse_expression,
)
from s7graph.sequencer.exchange.xmltree import ElementError, Node, check_wire_depth

__all__ = ["Network"]

_OPERATORS = {
    "AND": "AND",
    "OR": "OR",
    "XOR": "XOR",
    "GT": ">",
    "GE": ">=",
    "EQ": "=",
    "NE": "<>",
    "LE": "<=",
    "LT": "<",
    "ADD": "+",
    "SUB": "-",
    "MUL": "*",
    "DIV": "/",
    "MOD": "MOD",
}


MAX_ELEMENTS = 20_000
"""The longest expression a network is read into, in elements written out."""


def _size(e: SExpr, known: dict[int, int]) -> int:
    """How many elements ``e`` is written out; a part already read counts its known size
    (``known``, by the part's identity: a shared part costs one look-up, not its whole
    length)."""
    total = 0
    stack = [e]
    while stack:
        x = stack.pop()
        n = known.get(id(x))
        if n is not None:
            total += n
            continue
        total += 1
        if isinstance(x, SBinary):
            stack += (x.left, x.right)
        elif isinstance(x, SUnary):
            stack.append(x.operand)
        elif isinstance(x, SCall):
            stack += [v for _, v in x.params]
        if total > MAX_ELEMENTS:
            return total
    return total


def _not(e: SExpr, node: Node) -> SExpr:
    return SUnary("NOT", e, node.line, node.col)


def _and(a: SExpr, b: SExpr, node: Node) -> SExpr:
    if isinstance(a, SLiteral) and a.text.upper() == "TRUE":
        return b
    return SBinary("AND", a, b, node.line, node.col)


@dataclass
class Network:
    """The elements of one LD/FBD body (or of an SFC body's networks), by ``localId``."""

    root: Node
    file: str
    by_id: dict[str, Node] = field(init=False)
    connectors: dict[str, Node] = field(init=False)
    calls: list[SCallStmt] = field(init=False, default_factory=list)
    computed: set[str] = field(init=False, default_factory=set)  # instance block localIds
    read: dict[tuple[str, str], SExpr] = field(init=False, default_factory=dict)
    """What flows out of an element's output — read once, whatever number of wires leave
    it (``source``)."""
    sizes: dict[int, int] = field(init=False, default_factory=dict)
    """How many elements each expression of ``read`` is written out, by its identity."""

    def __post_init__(self) -> None:
        self.by_id = {n.get("localId"): n for n in self.root.children if n.get("localId")}
        self.connectors = {n.get("name"): n for n in self.root.children if n.tag == "connector"}

    def expression(self, node: Node, text: str) -> SExpr:
        try:
            origin = (node.text_line or node.line, node.text_col or node.col)
            return absolute(parse_expression(text, self.file, origin, "expression"), origin)  # type: ignore[no-any-return]
        except StSyntaxError as exc:
            raise ElementError(exc.message, node) from None

    def value_of(self, point: Node | None, seen: frozenset[str] = frozenset()) -> SExpr:
        """What flows into ``point`` (a ``connectionPointIn``)."""
        if point is None:
            raise ElementError("an unconnected input", self.root)
        conns = point.all("connection")
        if not conns:
            raise ElementError("an unconnected input", point)
        values = [self.source(c, seen) for c in conns]
        out = values[0]
        for v in values[1:]:
            out = SBinary("OR", out, v, point.line, point.col)
        return out

    def source(self, conn: Node, seen: frozenset[str]) -> SExpr:
        """What flows out of the element ``conn`` names, read once per output; an
        expression that would be over ``MAX_ELEMENTS`` long written out (an output fanned
        out to several inputs at each of many levels) is an ElementError, not an import
        that never ends; one wired through more than ``MAX_WIRE_DEPTH`` elements one after
        another is too, at the element past it."""
        key = (conn.get("refLocalId"), conn.get("formalParameter"))
        if key in self.read:
            return self.read[key]
        out = self._source(conn, seen)
        size = _size(out, self.sizes)
        if size > MAX_ELEMENTS:
            raise ElementError(
                f"an expression over {MAX_ELEMENTS:,} elements long written out "
                "(outputs that feed several inputs, level after level)",
                self.by_id.get(key[0], conn),
            )
        self.read[key] = out
        self.sizes[id(out)] = size  # ``out`` lives on in ``read``: its id stays its own
        return out

    def _source(self, conn: Node, seen: frozenset[str]) -> SExpr:
        ref = conn.get("refLocalId")
        node = self.by_id.get(ref)
        if node is None:
            raise ElementError(f"a connection to element {ref}, which does not exist", conn)
        if node.tag == "block" and node.get("instanceName"):
            return self.instance_output(node, conn.get("formalParameter"), seen)
        if ref in seen:
            raise ElementError("a feedback loop in the network", node)
        check_wire_depth(len(seen), node)
        seen = seen | {ref}
        tag = node.tag
        if tag == "leftPowerRail":
            return SLiteral("TRUE", node.line, node.col)
        if tag == "contact":
            if node.get("edge", "none") not in ("none", ""):
                raise ElementError(
                    f"an edge contact ({node.get('edge')}) has no GRAPH condition form", node
                )
            var = self.variable(node)
            if node.flag("negated"):
                var = _not(var, node)
            return _and(self.value_of(node.child("connectionPointIn"), seen), var, node)
        if tag in ("inVariable", "inOutVariable"):
            e = self.expr_of(node)
            return _not(e, node) if node.flag("negated") else e
        if tag == "continuation":
            target = self.connectors.get(node.get("name"))
            if target is None:
                raise ElementError(f"continuation {node.get('name')} has no connector", node)
            return self.value_of(target.child("connectionPointIn"), seen)
        if tag == "block":
            return self.block(node, conn.get("formalParameter"), seen)
        if tag == "coil":  # a coil passes its input on (LD series)
            return self.value_of(node.child("connectionPointIn"), seen)
        raise ElementError(f"a {tag} element cannot feed a condition", node)

    def expr_of(self, node: Node) -> SExpr:
        """The ST expression of an in/out variable element."""
        child = node.child("expression")
        if child is None or not child.text.strip():
            raise ElementError(f"a {node.tag} without an expression", node)
        return self.expression(child, child.text.strip())

    def text(self, node: Node) -> str:
        expr = node.child("expression")
        return (expr.text if expr is not None else "").strip()

    def variable(self, node: Node) -> SExpr:
        var = node.child("variable")
        if var is None or not var.text.strip():
            raise ElementError(f"a {node.tag} without a variable", node)
        return self.expression(var, var.text.strip())

    def inputs(
        self, block: Node, seen: frozenset[str], *, optional: bool = False
    ) -> list[tuple[str, SExpr]]:
        """The wired inputs of ``block`` (``optional``: an unconnected one is left out, as
        an FB call leaves out a parameter; a function needs every input)."""
        out: list[tuple[str, SExpr]] = []
        holder = block.child("inputVariables")
        for v in holder.all("variable") if holder is not None else []:
            point = v.child("connectionPointIn")
            if optional and (point is None or not point.all("connection")):
                continue
            value = self.value_of(point, seen)
            if v.flag("negated"):
                value = _not(value, v)
            out.append((v.get("formalParameter"), value))
        return out

    def instance_output(self, node: Node, output: str, seen: frozenset[str]) -> SExpr:
        """An output of a function block instance: the instance is called first (once,
        its inputs computed depth first), then its output is read."""
        ref = node.get("localId")
        if ref not in self.computed:
            self.computed.add(ref)
            self.calls.append(self.call_of(node, seen | {ref}))
        return SName((node.get("instanceName"), output or "Q"), node.line, node.col)

    def call_of(self, node: Node, seen: frozenset[str]) -> SCallStmt:
        """The call of the instance block ``node`` with its wired inputs."""
        holder = node.child("inputVariables")
        for v in holder.all("variable") if holder is not None else []:
            point = v.child("connectionPointIn")
            if v.get("formalParameter").upper() == "EN" and point and point.all("connection"):
                raise ElementError(
                    f"block {node.get('instanceName')}: a wired EN input (a conditional call)", v
                )
        inputs = [
            (pin, value)
            for pin, value in self.inputs(node, seen, optional=True)
            if pin.upper() != "EN"
        ]
        return SCallStmt(node.get("instanceName"), tuple(inputs), (), node.line, node.col)

    def block(self, node: Node, output: str, seen: frozenset[str]) -> SExpr:
        type_name = node.get("typeName").upper()
        args = [v for _, v in self.inputs(node, seen)]
        if type_name == "NOT" and len(args) == 1:
            return _not(args[0], node)
        if type_name == "MOVE" and len(args) == 1:
            return args[0]
        if type_name == "SEL" and len(args) == 3:
            return SCall("SEL", tuple(("", a) for a in args), node.line, node.col)
        op = _OPERATORS.get(type_name)
        if op is None or len(args) < 2:
            raise ElementError(
                f"block {node.get('typeName')} has no GRAPH form in a condition or assignment", node
            )
        out = args[0]
        for a in args[1:]:
            out = SBinary(op, out, a, node.line, node.col)
        return out

    def statements(self) -> list[SStmt]:
        """What the network writes, in Beremiz's order: the elements with an execution order
        first (by it), then the coils and output variables, then the function block
        instances not called yet, each group top to bottom, then left to right; the calls
        of the instances an element reads go just before it."""
        ordered: list[tuple[tuple[int, int, int], Node]] = []
        for i, node in enumerate(self.root.children):
            if node.tag not in ("coil", "outVariable", "inOutVariable", "block"):
                continue
            order = int(node.get("executionOrderId", "0") or 0)
            group = 0 if order > 0 else (2 if node.tag == "block" else 1)
            ordered.append(((group, order or _top_left(node), i), node))
        out: list[SStmt] = []
        for _, node in sorted(ordered, key=lambda item: item[0]):
            start = len(self.calls)
            stmt = self.statement(node)
            out += self.calls[start:]
            if stmt is not None:
                out.append(stmt)
        return out

    def statement(self, node: Node) -> SStmt | None:
        tag = node.tag
        if tag == "coil":
            target = self.variable(node)
            value = self.value_of(node.child("connectionPointIn"))
            if not isinstance(target, SName):
                raise ElementError("a coil must write a variable", node)
            storage = node.get("storage", "none")
            if storage in ("set", "reset"):
                return SSetReset(
                    "S" if storage == "set" else "R", target, value, node.line, node.col
                )
            if node.flag("negated"):
                value = _not(value, node)
            return SAssign(target, value, node.line, node.col)
        if tag in ("outVariable", "inOutVariable") and node.child("connectionPointIn"):
            point = node.child("connectionPointIn")
            if point is None or not point.all("connection"):
                return None
            target = self.expr_of(node)
            if not isinstance(target, SName):
                raise ElementError("an output variable must be a variable", node)
            value = self.value_of(point)
            if node.flag("negatedIn") or node.flag("negated"):
                value = _not(value, node)
            return SAssign(target, value, node.line, node.col)
        if tag == "block" and node.get("instanceName"):
            if node.get("localId") in self.computed:
                return None
            self.computed.add(node.get("localId"))
            return self.call_of(node, frozenset({node.get("localId")}))
        return None

    def output_named(self, name: str) -> SExpr | None:
        """The value written to ``name`` (a named transition's LD/FBD body)."""
        for node in self.root.children:
            if node.tag in ("outVariable", "coil"):
                var = node.child("variable")
                label = (
                    self.text(node)
                    if node.tag == "outVariable"
                    else (var.text.strip() if var is not None else "")
                )
                if label.upper() == name.upper():
                    return self.value_of(node.child("connectionPointIn"))
        return None


def _top_left(node: Node) -> int:
    """A sort key: top to bottom, then left to right (Beremiz's order of unordered elements)."""
    pos = node.child("position")
    if pos is None:
        return 0
    x, y = pos.get("x", "0"), pos.get("y", "0")
    try:
        return int(float(y)) * 100_000 + int(float(x))
    except ValueError:
        return 0
