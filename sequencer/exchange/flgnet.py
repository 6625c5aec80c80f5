"""TIA Portal LAD/FBD networks (``FlgNet``) ↔ GRAPH conditions, for SimaticML GRAPH blocks.

Reading (``condition``): a wire connects its first end (the power rail, a part's output
pin or an operand) to its other ends; a value is followed back from the network's coil
(``TrCoil`` ``IlCoil`` ``SvCoil``, or ``Coil`` ``SCoil`` ``RCoil`` of a permanent
operation): the power rail is TRUE, a ``Contact`` ANDs its operand (``Negated`` on the
``operand`` pin: NOT) with its ``in``, ``O`` ORs its inputs, ``A``/``X`` (FBD) AND/XOR them,
``Not`` negates, a comparison box (``Eq Ne Gt Ge Lt Le``, ``SrcType`` its type) compares
``in1`` with ``in2`` and ANDs ``pre`` (LAD); a comparison with a step's time (``T``,
``U``) reads the other side as a TIME, as TIA compiles it (an untyped tag or a DInt, an
integer as milliseconds). A coil fed by the rail alone carries no
condition: an empty transition (holds), no interlock, no supervision.

Writing (``network``): the inverse, in LAD — a sum of products as contacts in series
(AND) and ``O`` boxes (OR), comparisons as boxes, ``NOT x`` as a negated contact,
other NOTs as a ``Not`` part, which in LAD inverts all the power flow before it (so
``a AND NOT (b OR c)`` is drawn NOT (NOT a OR b OR c)), ``a XOR b`` as (a AND NOT b) OR
(NOT a AND b) — ending in the coil given. Operands are written by the
caller (``Operands``): symbols as global ``Access`` es, FB variables and step/transition
attributes as local ones, constants as literals.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

from s7graph.engine.errors import SourceLocation
from s7graph.sequencer.exchange.xmltree import ElementError, Node, check_wire_depth
from s7graph.sequencer.text.model import Binary, Const, Expr, StepAttr, Unary
from s7graph.steps.syntax import CHAIN_OPS, chain

__all__ = ["COMPARE_PARTS", "Box", "read_boxes", "read_network", "write_call", "write_move"]

COMPARE_PARTS = {"Eq": "=", "Ne": "<>", "Gt": ">", "Ge": ">=", "Lt": "<", "Le": "<="}
_PART_OF = {v: k for k, v in COMPARE_PARTS.items()}
COILS = {"TrCoil", "IlCoil", "SvCoil", "Coil", "SCoil", "RCoil"}
_READ_PARTS = COILS | set(COMPARE_PARTS) | {"Contact", "O", "A", "X", "Not", "Move"}


Operand = Callable[[Node, str | None], Expr]  # an Access element (and the type it needs)


@dataclass
class _Net:
    root: Node
    operand: Operand
    file: str
    parts: dict[str, Node] = field(default_factory=dict)
    sources: dict[tuple[str, str], list[tuple[str, str]]] = field(default_factory=dict)
    done: dict[tuple[tuple[str, str], str | None], Expr | None] = field(default_factory=dict)
    busy: set[tuple[tuple[str, str], str | None]] = field(default_factory=set)

    def __post_init__(self) -> None:
        holder = self.root.child("Parts")
        for p in holder.children if holder is not None else []:
            self.parts[p.get("UId")] = p
        wires = self.root.child("Wires")
        for w in wires.children if wires is not None else []:
            ends = [(e.tag, e.get("UId"), e.get("Name")) for e in w.children]
            if not ends:
                continue
            tag, uid, name = ends[0]
            src = ("rail", "") if tag == "Powerrail" else (uid, name or "")
            if tag == "IdentCon":
                src = (uid, "@")
            for t, u, n in ends[1:]:
                if t in ("NameCon", "IdentCon"):
                    self.sources.setdefault((u, n or ""), []).append(src)

    def loc(self, node: Node) -> SourceLocation:
        return node.loc(self.file)

    def pin(self, uid: str, name: str, want: str | None = None) -> Expr | None:
        """What flows into pin ``name`` of part ``uid`` (None: the power rail alone)."""
        part = self.parts[uid]
        srcs = self.sources.get((uid, name), [])
        if not srcs:
            raise ElementError(f"pin {name} of {part.get('Name')} is not connected", part)
        out = self.parallel(srcs, want, self.loc(part))
        if any(n.get("Name") == name for n in part.all("Negated")):
            if out is None:
                raise ElementError(f"a negated {name} on the power rail", part)
            out = Unary("NOT", out, self.loc(part))
        return out

    def parallel(
        self, srcs: list[tuple[str, str]], want: str | None, loc: SourceLocation
    ) -> Expr | None:
        """The OR of what flows from ``srcs``, a LAD parallel branch read as it is drawn:
        branches of contacts in series that open at one place give ``before AND (b1 OR
        b2 …)`` — what flows to that place read once, not once per branch (a network of
        nested branches stays as long as its drawing, never doubles per level)."""
        walks = [self.series(src) for src in srcs]
        if len({base for base, _ in walks}) > 1:  # branches from several places
            values = [self.value(src, want) for src in srcs]
            if any(v is None for v in values):  # the rail: TRUE in parallel
                return None if len(values) == 1 else Const(True, "BOOL", "TRUE", loc)
            return _joined("OR", values, loc)  # type: ignore[arg-type]
        base = walks[0][0]
        head = self.value(base, want) if base is not None else None
        # the contacts every branch passes (one part, a wire fanning out after it) are
        # read once, before the OR: ``a AND (b OR c)``, as drawn
        shared = _shared_prefix([ops for _, ops in walks]) if len(walks) > 1 else 0
        if shared:
            head = _and(head, _joined("AND", [op for _, op in walks[0][1][:shared]], loc), loc)
        branches = [[op for _, op in ops[shared:]] for _, ops in walks]
        if any(not ops for ops in branches):  # a branch of no contact: the flow itself
            if head is None and len(walks) > 1:
                return Const(True, "BOOL", "TRUE", loc)
            return head
        alt = _joined("OR", [_joined("AND", ops, loc) for ops in branches], loc)
        return _and(head, alt, loc)

    def series(self, src: tuple[str, str]) -> tuple[tuple[str, str] | None, list[tuple[str, Expr]]]:
        """Walk back from ``src`` through contacts in series (each fed by one wire): where
        the chain starts (None: the power rail) and the contacts (UId, operand) in drawing
        order; a loop of wires is an ElementError."""
        ops: list[tuple[str, Expr]] = []
        for _ in range(len(self.parts) + 1):
            uid, pin = src
            if uid == "rail":
                return None, ops[::-1]
            part = self.parts.get(uid)
            if part is None or pin == "@" or part.tag == "Access":
                return src, ops[::-1]
            ins = self.sources.get((uid, "in"), [])
            negated = any(n.get("Name") == "in" for n in part.all("Negated"))
            if part.get("Name") != "Contact" or len(ins) != 1 or negated:
                return src, ops[::-1]
            op = self.pin(uid, "operand", "BOOL")
            assert op is not None
            ops.append((uid, op))
            src = ins[0]
        raise ElementError("a loop of wires: a contact feeds itself", self.parts[src[0]])

    def value(self, src: tuple[str, str], want: str | None) -> Expr | None:
        """What flows out of ``src`` (read once: the same value for every wire from it);
        a part whose value needs its own is a loop of wires, an ElementError, as is one
        reached through more than ``MAX_WIRE_DEPTH`` parts one after another."""
        key = (src, want)
        if key in self.done:
            return self.done[key]
        if key in self.busy:
            part = self.parts.get(src[0])
            raise ElementError("a loop of wires: an element feeds itself", part or self.root)
        check_wire_depth(len(self.busy), self.parts.get(src[0]) or self.root)
        self.busy.add(key)
        out = self._value(src, want)
        self.busy.discard(key)
        self.done[key] = out
        return out

    def _value(self, src: tuple[str, str], want: str | None) -> Expr | None:
        uid, pin = src
        if uid == "rail":
            return None
        part = self.parts.get(uid)
        if part is None:
            raise ElementError(f"a wire from element {uid}, which does not exist", self.root)
        if pin == "@" or part.tag == "Access":
            return self.operand(part, want)
        kind = part.get("Name")
        loc = self.loc(part)
        if kind == "Contact":
            base, ops = self.series(src)
            head = self.value(base, want) if base is not None else None
            return _and(head, _joined("AND", [op for _, op in ops], loc), loc)
        if kind in ("O", "A", "X"):
            n = _cardinality(part)
            logic = {"O": "OR", "A": "AND", "X": "XOR"}[kind]
            feeds = [self.sources.get((uid, f"in{i}"), []) for i in range(1, n + 1)]
            plain = not any(n.get("Name", "").startswith("in") for n in part.all("Negated"))
            if logic == "OR" and plain and all(len(f) == 1 for f in feeds):
                return self.parallel([f[0] for f in feeds], None, loc)
            ins = [self.pin(uid, f"in{i}") for i in range(1, n + 1)]
            if logic == "OR" and any(v is None for v in ins):
                return None
            vals = [v if v is not None else Const(True, "BOOL", "TRUE", loc) for v in ins]
            return _joined(logic, vals, loc)
        if kind == "Not":
            inner = self.pin(uid, "in")
            if inner is None:
                raise ElementError("NOT of the power rail", part)
            return Unary("NOT", inner, loc)
        if kind in COMPARE_PARTS:
            src_type = next(
                (
                    t.text.strip().upper()
                    for t in part.all("TemplateValue")
                    if t.get("Name") == "SrcType"
                ),
                None,
            )
            left, right = self.pin(uid, "in1", src_type), self.pin(uid, "in2", src_type)
            if left is None or right is None:
                raise ElementError("a comparison of the power rail", part)
            # a step's time (T, U) is a TIME: the other side is read as one, as TIA does
            if _is_time(left) and not _is_time(right):
                right = self.pin(uid, "in2", "TIME")
            elif _is_time(right) and not _is_time(left):
                left = self.pin(uid, "in1", "TIME")
            assert left is not None and right is not None
            cmp = Binary(COMPARE_PARTS[kind], left, right, loc)
            pre = self.pin(uid, "pre") if (uid, "pre") in self.sources else None
            return _and(pre, cmp, loc)
        raise ElementError(f"part {kind} has no GRAPH condition form", part)


def _is_time(e: Expr | None) -> bool:
    return isinstance(e, StepAttr) and e.attr in ("T", "U")


def _shared_prefix(walks: list[list[tuple[str, Expr]]]) -> int:
    """How many contacts, from the start, all ``walks`` pass through (the same parts)."""
    n = 0
    for parts in zip(*walks, strict=False):
        if len({uid for uid, _ in parts}) != 1:
            break
        n += 1
    return n


def _cardinality(part: Node) -> int:
    for t in part.all("TemplateValue"):
        if t.get("Name") == "Card" and t.text.strip().isdigit():
            return int(t.text.strip())
    return 2


def _and(a: Expr | None, b: Expr, loc: SourceLocation) -> Expr:
    return b if a is None else Binary("AND", a, b, loc)


def _joined(op: str, values: list[Expr], loc: SourceLocation) -> Expr:
    """``values`` joined by ``op``, left to right (one value: itself), in the shape the
    parser gives a written chain (``steps.syntax.chain``: a rung of 500 contacts in series
    is some 9 levels deep, not 500)."""
    if len(values) > 2 and op in CHAIN_OPS:
        return chain(op, values)
    out = values[0]
    for v in values[1:]:
        out = Binary(op, out, v, loc)
    return out


def read_network(net: Node, operand: Operand, file: str) -> list[tuple[Node, Expr | None]]:
    """Every coil of ``net`` (a ``FlgNet``) with the condition flowing into it."""
    n = _Net(net, operand, file)
    out: list[tuple[Node, Expr | None]] = []
    for uid, part in n.parts.items():
        if part.tag == "Part" and part.get("Name") in COILS:
            out.append((part, n.pin(uid, "in")))
    return out


@dataclass(frozen=True)
class Box:
    """A ``Call`` (``CallInfo`` ``Name``, ``BlockType``, the instance's name) or ``Move``
    box fed by the power rail: what flows into its inputs, the operands its outputs feed."""

    node: Node
    name: str  # the block's name; "Move" for a move
    block_type: str
    instance: str | None
    inputs: tuple[tuple[str, Expr], ...]
    outputs: tuple[tuple[str, Expr], ...]


def read_boxes(net: Node, operand: Operand, file: str) -> list[Box]:
    """Every call and move box of ``net``; ``ElementError`` for one whose ``en`` is not the
    power rail alone (a conditional call has no GRAPH permanent form) and for a part no
    condition, coil or box here reads (an ADD box …)."""
    n = _Net(net, operand, file)
    out: list[Box] = []
    for uid, part in n.parts.items():
        info = part.child("CallInfo") if part.tag == "Call" else None
        kind = part.get("Name")
        if part.tag == "Part" and kind not in _READ_PARTS:
            raise ElementError(f"part {kind} has no GRAPH permanent form", part)
        if info is None and not (part.tag == "Part" and kind == "Move"):
            continue
        if n.sources.get((uid, "en"), [("rail", "")]) != [("rail", "")]:
            raise ElementError("a box whose EN is not the power rail alone", part)
        ins: list[tuple[str, Expr]] = []
        for (sink, pin), srcs in n.sources.items():
            if sink == uid and pin != "en":
                value = n.value(srcs[0], None)
                if value is None:
                    raise ElementError(f"input {pin} on the power rail", part)
                ins.append((pin, value))
        outs = [
            (pin, n.operand(n.parts[sink], None))
            for (sink, _), srcs in n.sources.items()
            for src, pin in srcs
            if src == uid and n.parts.get(sink) is not None and n.parts[sink].tag == "Access"
        ]
        if info is None:
            out.append(Box(part, "Move", "", None, tuple(ins), tuple(outs)))
            continue
        inst = info.find("Instance", "Component")
        instance = inst.get("Name") if inst is not None else None
        name, kind = info.get("Name"), info.get("BlockType")
        out.append(Box(part, name, kind, instance, tuple(ins), tuple(outs)))
    return out


# ---------------------------------------------------------------- writing


_RAIL = "<Powerrail />"


class _Writer:
    def __init__(self, access: Callable[[Expr, str], str], start: int = 21) -> None:
        self.access = access  # writes an operand's <Access UId=…> element, returns it
        self.uid = start
        self.parts: list[str] = []
        self.wires: dict[str, list[str]] = {}  # one wire per source, to all its sinks

    def next(self) -> str:
        self.uid += 1
        return str(self.uid - 1)

    def wire(self, src: str, *sinks: str) -> None:
        self.wires.setdefault(src, []).extend(sinks)

    def wires_xml(self) -> str:
        out = []
        for src, sinks in self.wires.items():
            out.append(f'<Wire UId="{self.next()}">{src}{"".join(sinks)}</Wire>')
        return "".join(out)

    def operand(self, e: Expr) -> str:
        uid = self.next()
        self.parts.append(self.access(e, uid))
        return uid

    def flow(self, e: Expr, into: list[str]) -> None:
        """Wire the power flow of ``e`` into the pins ``into`` (NameCon elements)."""
        self._flow(e, _RAIL, into)

    def _flow(self, e: Expr, src: str, into: list[str]) -> None:
        if isinstance(e, Binary) and e.op == "AND":
            mid = self._series(e.left, src)
            self._flow(e.right, mid, into)
            return
        out = self._series(e, src)
        self.wire(out, *into)

    def _series(self, e: Expr, src: str) -> str:
        """Element(s) for ``e`` fed by ``src``; returns the NameCon of their output."""
        if isinstance(e, Binary) and e.op == "AND":
            return self._series(e.right, self._series(e.left, src))
        if isinstance(e, Binary) and e.op == "OR":
            terms = _or_terms(e)
            box = self._o_part(len(terms))
            for i, t in enumerate(terms, 1):
                self._flow(t, src, [f'<NameCon UId="{box}" Name="in{i}" />'])
            return f'<NameCon UId="{box}" Name="out" />'
        if isinstance(e, Binary) and e.op in _PART_OF:
            box = self.next()
            self.parts.append(f'<Part Name="{_PART_OF[e.op]}" UId="{box}" />')
            self.wire(src, f'<NameCon UId="{box}" Name="pre" />')
            for pin, side in (("in1", e.left), ("in2", e.right)):
                op = self.operand(side)
                self.wire(f'<IdentCon UId="{op}" />', f'<NameCon UId="{box}" Name="{pin}" />')
            return f'<NameCon UId="{box}" Name="out" />'
        if isinstance(e, Unary) and e.op == "NOT" and not isinstance(e.operand, Binary | Unary):
            return self._contact(e.operand, src, negated=True)
        if isinstance(e, Unary) and e.op == "NOT":
            if src == _RAIL:
                return self._not(self._series(e.operand, _RAIL))
            # LAD's NOT inverts all the power flow before it, so ``src AND NOT x`` is
            # drawn as NOT (NOT src OR x), x fed from the rail (De Morgan)
            box = self._or([self._not(src), self._series(e.operand, _RAIL)])
            return self._not(box)
        if isinstance(e, Binary) and e.op == "XOR":
            a, b = e.left, e.right  # LAD has no XOR: (a AND NOT b) OR (NOT a AND b)
            one = Binary("AND", a, Unary("NOT", b, e.loc), e.loc)
            other = Binary("AND", Unary("NOT", a, e.loc), b, e.loc)
            return self._series(Binary("OR", one, other, e.loc), src)
        if isinstance(e, Binary):
            raise ValueError(f"{e.loc}: {e.op} has no LAD form: a SimaticML network cannot hold it")
        return self._contact(e, src, negated=False)

    def _not(self, src: str) -> str:
        """A ``Not`` part inverting the power flow ``src``; returns its output."""
        box = self.next()
        self.parts.append(f'<Part Name="Not" UId="{box}" />')
        self.wire(src, f'<NameCon UId="{box}" Name="in" />')
        return f'<NameCon UId="{box}" Name="out" />'

    def _o_part(self, inputs: int) -> str:
        """A new ``O`` box of ``inputs`` inputs (``in1``…); returns its UId."""
        box = self.next()
        self.parts.append(
            f'<Part Name="O" UId="{box}"><TemplateValue Name="Card" '
            f'Type="Cardinality">{inputs}</TemplateValue></Part>'
        )
        return box

    def _or(self, outputs: list[str]) -> str:
        """An ``O`` box ORing the power flows ``outputs``; returns its output."""
        box = self._o_part(len(outputs))
        for i, out in enumerate(outputs, 1):
            self.wire(out, f'<NameCon UId="{box}" Name="in{i}" />')
        return f'<NameCon UId="{box}" Name="out" />'

    def _contact(self, e: Expr, src: str, *, negated: bool) -> str:
        op = self.operand(e)
        box = self.next()
        neg = '<Negated Name="operand" />' if negated else ""
        self.parts.append(f'<Part Name="Contact" UId="{box}">{neg}</Part>')
        self.wire(src, f'<NameCon UId="{box}" Name="in" />')
        self.wire(f'<IdentCon UId="{op}" />', f'<NameCon UId="{box}" Name="operand" />')
        return f'<NameCon UId="{box}" Name="out" />'


def _or_terms(e: Expr) -> list[Expr]:
    if isinstance(e, Binary) and e.op == "OR":
        return _or_terms(e.left) + _or_terms(e.right)
    return [e]


def write_network(
    cond: Expr | None,
    coil: str,
    access: Callable[[Expr, str], str],
    coil_operand: Expr | None = None,
) -> str:
    """A ``FlgNet`` computing ``cond`` (None: the rail alone) into part ``coil``; raises
    ValueError naming the place for what LAD cannot draw (an operand that is an
    expression)."""
    w = _Writer(access)
    target = ""
    if coil_operand is not None:
        target = w.operand(coil_operand)
    box = w.next()
    w.parts.append(f'<Part Name="{coil}" UId="{box}" />')
    into = [f'<NameCon UId="{box}" Name="in" />']
    if cond is None:
        w.wire(_RAIL, *into)
    else:
        w.flow(cond, into)
    if target:
        w.wire(f'<IdentCon UId="{target}" />', f'<NameCon UId="{box}" Name="operand" />')
    return f"<FlgNet><Parts>{''.join(w.parts)}</Parts><Wires>{w.wires_xml()}</Wires></FlgNet>"


def write_call(
    info: Callable[[str], str],
    inputs: tuple[tuple[str, Expr], ...],
    outputs: tuple[tuple[str, Expr], ...],
    access: Callable[[Expr, str], str],
) -> str:
    """A ``FlgNet`` of one ``Call`` box fed by the power rail, ``inputs`` wired from their
    operands, ``outputs`` to theirs; ``info(uid)`` writes its ``CallInfo`` (an instance's
    ``Access``-like element takes UId ``uid``)."""
    w = _Writer(access)
    box, inst = w.next(), w.next()
    w.parts.append(f'<Call UId="{box}">{info(inst)}</Call>')
    w.wire(_RAIL, f'<NameCon UId="{box}" Name="en" />')
    for pin, e in inputs:
        w.wire(f'<IdentCon UId="{w.operand(e)}" />', f'<NameCon UId="{box}" Name="{pin}" />')
    for pin, e in outputs:
        w.wire(f'<NameCon UId="{box}" Name="{pin}" />', f'<IdentCon UId="{w.operand(e)}" />')
    return f"<FlgNet><Parts>{''.join(w.parts)}</Parts><Wires>{w.wires_xml()}</Wires></FlgNet>"


def write_move(source: Expr, target: Expr, access: Callable[[Expr, str], str]) -> str:
    """A ``FlgNet`` of one ``Move`` box fed by the power rail: ``source`` to ``target``."""
    w = _Writer(access)
    box = w.next()
    w.parts.append(
        f'<Part Name="Move" UId="{box}"><TemplateValue Name="Card" '
        'Type="Cardinality">1</TemplateValue></Part>'
    )
    w.wire(_RAIL, f'<NameCon UId="{box}" Name="en" />')
    w.wire(f'<IdentCon UId="{w.operand(source)}" />', f'<NameCon UId="{box}" Name="in" />')
    w.wire(f'<NameCon UId="{box}" Name="out1" />', f'<IdentCon UId="{w.operand(target)}" />')
    return f"<FlgNet><Parts>{''.join(w.parts)}</Parts><Wires>{w.wires_xml()}</Wires></FlgNet>"
