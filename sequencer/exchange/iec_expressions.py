"""The variables and ST expressions of an IEC 61131-3 POU as GRAPH operands and expressions,
by the rules of ``exchange.mapping``: the first half of ``exchange.iec_to_chart``.

Variables become FB variables; a located one a symbol at its S7 address, unless that would
change what it does. An instance of an IEC timer or counter (TON TOF TP CTU CTD CTUD)
called in an action is ``CALL SFB n`` with an instance DB of its own (``SFB_OF``), its
outputs written to FB variables: ``INST.Q`` reads ``INST_Q``.
"""

from __future__ import annotations

import dataclasses
import re
from functools import cache

from s7graph.engine.errors import LiteralError, S7Error, SourceLocation
from s7graph.engine.literals import format_literal, parse_literal
from s7graph.sequencer.exchange.body_fc import PendingBodies
from s7graph.sequencer.exchange.iec_blocks import EDGE_AND_LATCH, bistable_body
from s7graph.sequencer.exchange.iec_model import IecChart
from s7graph.sequencer.exchange.mapping import FUNCTIONS, TYPES
from s7graph.sequencer.exchange.naming import iec_address, safe_name
from s7graph.sequencer.exchange.problems import Problems
from s7graph.sequencer.exchange.st import (
    SBinary,
    SCall,
    SCallStmt,
    SDirect,
    SExpr,
    SLiteral,
    SName,
    SUnary,
    shift,
)
from s7graph.sequencer.text.model import (
    NOWHERE,
    ActionRow,
    Binary,
    BlockCall,
    Const,
    Expr,
    Operand,
    PermanentInstruction,
    Step,
    StepAttr,
    SymbolDecl,
    Unary,
    VarDecl,
)
from s7graph.sfb import catalogue

__all__ = ["S7_PIN", "SFB_OF", "IecExpressions", "const", "iec_literal"]

# FB types whose instances the importer knows the outputs of (for ``INST.Q`` reads).
_FB_MEMBERS: dict[str, dict[str, str]] = {
    "TON": {"Q": "BOOL", "ET": "TIME"},
    "TOF": {"Q": "BOOL", "ET": "TIME"},
    "TP": {"Q": "BOOL", "ET": "TIME"},
    "CTU": {"Q": "BOOL", "CV": "INT"},
    "CTD": {"Q": "BOOL", "CV": "INT"},
    "CTUD": {"QU": "BOOL", "QD": "BOOL", "CV": "INT"},
    "R_TRIG": {"Q": "BOOL"},
    "F_TRIG": {"Q": "BOOL"},
    "SR": {"Q1": "BOOL"},
    "RS": {"Q1": "BOOL"},
}

# The IEC standard FBs the CPU has as system blocks (``sfb.catalogue``): an instance called
# in an action or the POU body is ``CALL SFB n, DB m``, each instance with a DB of its own
# from ``_FIRST_DB`` on, every output written to the FB variable ``INST_OUT``.
SFB_OF: dict[str, int] = {"CTU": 0, "CTD": 1, "CTUD": 2, "TP": 3, "TON": 4, "TOF": 5}

S7_PIN: dict[str, str] = {"LD": "LOAD"}  # IEC's name of a counter's load input → S7's

_FIRST_DB = 100

_COMPARE = {"=", "<>", "<", ">", "<=", ">="}


class _NoMap(Exception):
    """A construct without an exact GRAPH equivalent, at ``loc``."""

    def __init__(self, message: str, loc: SourceLocation) -> None:
        super().__init__(message)
        self.message = message
        self.loc = loc


_TYPED = re.compile(
    r"(?i)(SINT|USINT|UINT|UDINT|LINT|ULINT|INT|DINT|LREAL|REAL|BOOL|BYTE|"
    r"WORD|DWORD|LWORD)#(.+)"
)


def iec_literal(text: str) -> str:
    """An IEC typed literal in S7 spelling: ``UINT#5`` → ``5``, ``BOOL#1`` → ``TRUE``,
    ``WORD#16#FF`` → ``W#16#FF`` (the type follows from the value and its use)."""
    m = _TYPED.fullmatch(text.strip().replace("_", "") if "#" in text else text.strip())
    if m is None:
        return text
    kind, body = m.group(1).upper(), m.group(2)
    if kind == "BOOL":
        return "TRUE" if body.upper() in ("1", "TRUE") else "FALSE"
    if kind in ("BYTE", "WORD", "DWORD", "LWORD"):
        return ("B#" if kind == "BYTE" else "DW#" if kind in ("DWORD", "LWORD") else "W#") + (
            body if "#" in body else f"16#{int(body):X}"
        )
    return body


@cache
def _s7g_literal() -> re.Pattern[str]:
    """The `.s7g` grammar's LITERAL terminal (a constant written so reads back as one)."""
    from s7graph.sequencer.text.parse import _parser

    return re.compile(_parser().get_terminal("LITERAL").pattern.to_regexp())


def const(text: str, loc: SourceLocation = NOWHERE) -> Const:
    """The GRAPH constant of a literal: as written when the chart format reads it so,
    else in canonical S7 spelling."""
    text = iec_literal(text)
    type_name, value = parse_literal(text)
    if _s7g_literal().fullmatch(text) and not text.startswith("-"):
        return Const(value, type_name, text, loc)
    canonical = format_literal(type_name, value)
    type_name, value = parse_literal(canonical)
    return Const(value, type_name, canonical, loc)


@dataclasses.dataclass
class _Var:
    graph: str  # the FB variable's or the symbol's name
    type: str
    symbol: bool = False


def _typed(text: str, type_name: str | None) -> str:
    """An IEC literal as the constant of ``type_name`` it stands for: ``1``/``0`` for a
    BOOL, an integer for a REAL (IEC converts them; GRAPH's constants are typed)."""
    if type_name == "BOOL" and text in ("0", "1"):
        return "TRUE" if text == "1" else "FALSE"
    if type_name == "REAL" and text.lstrip("-").isdigit():
        return text + ".0"
    return text


def _bool_literals(e: SExpr) -> SExpr:
    """``e`` (an expression a BOOL is expected of) with its 1 and 0 in BOOL positions as
    TRUE and FALSE (IEC 61131-3 §6.3.3: 1 and 0 are BOOL literals too)."""
    if isinstance(e, SLiteral) and e.text in ("0", "1"):
        return SLiteral("TRUE" if e.text == "1" else "FALSE", e.line, e.col)
    if isinstance(e, SUnary) and e.op == "NOT":
        return SUnary("NOT", _bool_literals(e.operand), e.line, e.col)
    if isinstance(e, SBinary) and e.op in ("AND", "OR", "XOR"):
        return SBinary(e.op, _bool_literals(e.left), _bool_literals(e.right), e.line, e.col)
    return e


def _bool_literal(e: Expr) -> Expr:
    """``e``, or the BOOL constant an IEC 0/1 stands for where a BOOL is expected."""
    if isinstance(e, Const) and e.type in ("INT", "DINT") and e.value in (0, 1):
        return Const(e.value == 1, "BOOL", "TRUE" if e.value == 1 else "FALSE", e.loc)
    return e


def _bool_compare(op: str, left: Expr, right: Expr, loc: SourceLocation) -> Expr:
    """``x = TRUE`` → ``x``; ``x = FALSE`` → ``NOT x``; ``a = b`` → ``NOT (a XOR b)``."""
    for const_side, other in ((right, left), (left, right)):
        if isinstance(const_side, Const) and isinstance(const_side.value, bool):
            holds = const_side.value == (op == "=")
            return other if holds else Unary("NOT", other, loc)
    xor = Binary("XOR", left, right, loc)
    return Unary("NOT", xor, loc) if op == "=" else xor


class IecExpressions:
    """A conversion's names, variables and expressions (``_Convert`` builds on it)."""

    written: set[str]
    """What the chart writes: ``_Convert.scan_writes`` fills it before ``variables``."""

    def __init__(self, src: IecChart, problems: Problems) -> None:
        self.src = src
        self.p = problems
        self.file = problems.file
        self.vars: dict[str, _Var] = {}
        self.decls: list[VarDecl] = []
        self.symbols: list[SymbolDecl] = []
        self.instances: dict[str, tuple[str, str, SourceLocation]] = {}
        self.instance_dbs: dict[str, int] = {}  # called instances: name → instance DB
        self.called: set[str] = set()  # bistables and edge detectors computed (upper case)
        self.members_read: dict[str, tuple[str, str]] = {}  # instance → (member, variable)
        self.taken: set[str] = set()
        self.steps: dict[str, Step] = {}
        self.step_numbers: dict[str, int] = {}
        self.before: list[PermanentInstruction] = []
        self.after: list[PermanentInstruction] = []
        self.rows: dict[int, list[ActionRow]] = {}
        self.warned: set[tuple[str, str]] = set()
        self.bool_actions: set[str] = set()
        self.body_writes: dict[str, SourceLocation] = {}
        self.pending = PendingBodies(problems, self.vars)
        self.result_calls: list[PermanentInstruction] = []  # FCs computing transitions
        self.helpers: set[str] = set()  # the FB variables the importer added

    def loc(self, node: object, origin: tuple[int, int]) -> SourceLocation:
        line, col = shift(getattr(node, "line", 0) or 1, getattr(node, "col", 0) or 1, origin)
        return SourceLocation(self.file, line, col)

    def warn_once(self, key: tuple[str, str], code: str, msg: str, loc: SourceLocation) -> None:
        if key not in self.warned:
            self.warned.add(key)
            self.p.warn(code, msg, loc)

    def declare(
        self, name: str, type_name: str, loc: SourceLocation, init: Const | None = None
    ) -> str:
        graph = safe_name(name, self.taken)
        if graph != name:
            self.p.warn(
                "I030",
                f"{name} is named {graph} in the chart ({name} is not a valid GRAPH variable name)",
                loc,
            )
        self.taken.add(graph.upper())
        self.decls.append(VarDecl(graph, type_name, init, loc))
        self.vars[name.upper()] = _Var(graph, type_name)
        return graph

    def helper(self, name: str, type_name: str) -> str:
        """An FB variable the importer adds (instance outputs, step pulses)."""
        key = name.upper()
        if key in self.vars:
            return self.vars[key].graph
        graph = safe_name(name, self.taken)
        self.taken.add(graph.upper())
        self.decls.append(VarDecl(graph, type_name))
        self.vars[key] = _Var(graph, type_name)
        self.helpers.add(graph)
        return graph

    def variables(self) -> None:
        for v in self.src.vars:
            base = v.type.split("[")[0]
            if v.type.startswith("ARRAY"):
                self.instances[v.name.upper()] = (v.name, v.type, v.loc)
                continue
            if base in _FB_MEMBERS or base not in TYPES:
                self.instances[v.name.upper()] = (v.name, base, v.loc)
                if base not in _FB_MEMBERS:
                    self.p.warn(
                        "I023",
                        f"{v.name} : {v.type} not imported: GRAPH FB "
                        "variables are of elementary types",
                        v.loc,
                    )
                continue
            graph_type, exact = TYPES[base]
            if "[" in v.type and base == "STRING":
                graph_type = "STRING" + v.type[len(base) :]
            if not exact:
                self.p.warn(
                    "I023",
                    f"{v.name} : {v.type} is declared {graph_type}: S7 has no {v.type}",
                    v.loc,
                )
            init = self.initial(v.init, graph_type, v.loc)
            if v.address and self.located(v.name, v.address, graph_type, init, v.kind, v.loc):
                continue
            if v.kind == "external" and v.init is None:
                self.p.warn(
                    "I023",
                    f"external {v.name} has no value in the file: it starts "
                    f"at the default of {graph_type}",
                    v.loc,
                )
            self.declare(v.name, graph_type, v.loc, init)

    def initial(self, e: SExpr | None, type_name: str, loc: SourceLocation) -> Const | None:
        if e is None:
            return None
        if isinstance(e, SLiteral):
            try:
                return const(_typed(e.text, type_name), loc)
            except (LiteralError, S7Error):
                pass
        self.p.warn("I023", "initial value not imported (not a literal GRAPH reads)", loc)
        return None

    def located(
        self,
        name: str,
        address: str,
        type_name: str,
        init: Const | None,
        kind: str,
        loc: SourceLocation,
    ) -> bool:
        """Make a located variable a symbol; False when it stays an FB variable."""
        s7 = iec_address(address)
        why = ""
        if s7 is None:
            why = f"{address} has no S7 form"
        elif init is not None and init.value not in (0, False, 0.0) and s7[0] in "IQ":
            why = f"S7 {'inputs' if s7[0] == 'I' else 'outputs'} have no initial value"
        elif s7[0] == "I" and name.upper() in self.written:
            why = "the chart writes it, and S7 reads inputs again every cycle"
        if why:
            self.p.warn("I023", f"{name} AT {address} is an FB variable, not a symbol: {why}", loc)
            return False
        assert s7 is not None
        self.symbols.append(SymbolDecl(name, s7, type_name, f"IEC {address}", loc))
        self.vars[name.upper()] = _Var(name, type_name, symbol=True)
        return True

    def operand(self, n: SName | SDirect, origin: tuple[int, int]) -> Expr:
        loc = self.loc(n, origin)
        if isinstance(n, SDirect):
            s7 = iec_address(n.text)
            if s7 is None:
                raise _NoMap(f"{n.text} has no S7 address", loc)
            return Operand(s7, False, loc)
        head = n.parts[0].upper()
        if n.indexed:
            return self.element(n, head, loc)
        if len(n.parts) == 1:
            v = self.vars.get(head)
            if v is None:
                if head in self.instances:
                    kind = self.instances[head][1]
                    what = (
                        "a function block instance"
                        if kind in _FB_MEMBERS
                        else f"of type {kind}, which has no GRAPH form"
                    )
                    raise _NoMap(f"{n.parts[0]} is {what}", loc)
                raise _NoMap(f"unknown variable {n.parts[0]}", loc)
            return Operand(v.graph, v.symbol, loc)
        if len(n.parts) == 2:
            member = n.parts[1].upper()
            if head in self.step_numbers and member in ("X", "T"):
                return StepAttr(self.step_numbers[head], member, loc)  # type: ignore[arg-type]
            if head in self.instances:
                return self.instance_member(head, member, loc)
        raise _NoMap(f"{n.text} is not a variable, step attribute or instance output", loc)

    def element(self, n: SName, head: str, loc: SourceLocation) -> Operand:
        """An array element ``A[0, 1]``: GRAPH FB variables are not arrays, so it reads the
        FB variable ``A_0_1`` (reported once per array)."""
        found = self.instances.get(head)
        if found is None or not found[1].startswith("ARRAY") or "?" in n.index or len(n.parts) > 1:
            raise _NoMap(f"{n.text}[…]: only elements of an array with constant indexes map", loc)
        name, type_name, decl_loc = found
        elem = type_name.removeprefix("ARRAY OF ").strip()
        graph_type = TYPES.get(elem, ("INT", False))[0]
        graph = self.helper(f"{name}_{'_'.join(n.index)}", graph_type)
        self.warn_once(
            (name, "array"),
            "I023",
            f"{name} is an array, which a GRAPH FB does "
            f"not hold; each element it uses is an FB variable ({graph} …)",
            decl_loc,
        )
        return Operand(graph, False, loc)

    def instance_member(self, head: str, member: str, loc: SourceLocation) -> Operand:
        name, fb_type, _ = self.instances[head]
        members = _FB_MEMBERS.get(fb_type, {})
        if member not in members:
            raise _NoMap(f"{name}.{member} is not an output of {fb_type}", loc)
        graph = self.helper(f"{name}_{member}", members[member])
        self.members_read.setdefault(head, (member, graph))
        return Operand(graph, False, loc)

    def fb_call(
        self, st: SCallStmt, origin: tuple[int, int], *, action: bool
    ) -> BlockCall | list[tuple[Operand, Expr]]:
        """``TON1(IN := x, PT := T#2S)`` as ``CALL SFB 4, DB 100 (IN := x, PT := T#2S,
        Q => TON1_Q, ET => TON1_ET)`` (``SFB_OF``); a call of R_TRIG, F_TRIG, SR or RS as
        the bit assignments of its body (``iec_blocks``), for the caller to place; the call
        of any other block is not mapped."""
        loc = self.loc(st, origin)
        found = self.instances.get(st.name.upper())
        if found is None:
            raise _NoMap(f"call of {st.name} not imported: not an FB instance of the POU", loc)
        name, fb_type, decl_loc = found
        if fb_type in EDGE_AND_LATCH:
            return self.bistable_call(st, origin, found)
        number = SFB_OF.get(fb_type)
        if number is None:
            known = ", ".join([*SFB_OF, *EDGE_AND_LATCH])
            raise _NoMap(
                f"call of {name} : {fb_type} not imported: GRAPH calls the CPU's system "
                f"blocks; the importer maps the IEC FBs {known}",
                loc,
            )
        ins = [(S7_PIN.get(pin.upper(), pin.upper()), e) for pin, e in st.inputs]
        pins = [pin for pin, _ in ins], [pin for pin, _ in st.outputs]
        problems = catalogue.lookup(f"SFB{number}").check_call(*pins, has_instance=True)
        if problems:
            raise _NoMap(f"call of {name} not imported: {problems[0]}", loc)
        inputs = tuple((pin, self.expr(e, origin)) for pin, e in ins)
        given = {pin.upper() for pin, _ in st.outputs}
        outputs: list[tuple[str, Operand]] = []
        for pin, target in st.outputs:
            op = self.operand(target, origin)
            assert isinstance(op, Operand)
            outputs.append((pin.upper(), op))
        helpers: list[str] = []
        for member, type_name in _FB_MEMBERS[fb_type].items():
            if member not in given:
                helpers.append(self.helper(f"{name}_{member}", type_name))
                outputs.append((member, Operand(helpers[-1])))
        db = self.instance_db(st.name)
        into = f"; its outputs go to the FB variables {', '.join(helpers)}" if helpers else ""
        final = (
            " (in an IEC action it is called once more when the step ends, in GRAPH only "
            "while the step is active)"
        )
        self.warn_once(
            (name, "called"),
            "I031",
            f"{name} : {fb_type} is called as SFB {number} with instance DB {db}{into}"
            + (final if action else ""),
            decl_loc,
        )
        return BlockCall("SFB", number, db, inputs, tuple(outputs), loc)

    def bistable_call(
        self,
        st: SCallStmt,
        origin: tuple[int, int],
        found: tuple[str, str, SourceLocation],
    ) -> list[tuple[Operand, Expr]]:
        """The assignments of a call of an R_TRIG, F_TRIG, SR or RS instance, its ``=>``
        outputs copied after them."""
        loc = self.loc(st, origin)
        name, fb_type, decl_loc = found
        pins, outs = EDGE_AND_LATCH[fb_type]
        known = {p for spellings in pins for p in spellings}
        given: dict[str, Expr] = {}
        for pin, e in st.inputs:
            if pin.upper() not in known:
                raise _NoMap(f"call of {name} : {fb_type}: no input {pin or '(positional)'}", loc)
            given[pin.upper()] = self.expr(e, origin)
        body = bistable_body(fb_type, name, given, self.helper, loc)
        for pin, target in st.outputs:
            if pin.upper() not in outs:
                raise _NoMap(f"call of {name} : {fb_type}: no output {pin}", loc)
            op = self.operand(target, origin)
            assert isinstance(op, Operand)
            body.append((op, Operand(self.helper(f"{name}_{pin.upper()}", "BOOL"), False, loc)))
        self.called.add(name.upper())
        states = ", ".join(dict.fromkeys(t.name for t, _ in body if t.name.startswith(name)))
        self.warn_once(
            (name, "called"),
            "I031",
            f"{name} : {fb_type} is computed by bit assignments in the permanent "
            f"instructions (IEC's body of {fb_type}); its state is in the FB variables "
            f"{states}",
            decl_loc,
        )
        return body

    def instance_db(self, name: str) -> int:
        """The instance DB of FB instance ``name``: the number its name ends in when it is
        ``…_DB<n>`` (s7graph's PLCopen export names them so) and free, else the next free
        one from ``_FIRST_DB``."""
        head = name.upper()
        if head not in self.instance_dbs:
            used = set(self.instance_dbs.values())
            m = re.fullmatch(r"\w+_DB(\d{1,5})", name, re.I)
            number = int(m.group(1)) if m else 0
            if not 0 < number < 65536 or number in used:
                number = next(n for n in range(_FIRST_DB, _FIRST_DB + 65536) if n not in used)
            self.instance_dbs[head] = number
        return self.instance_dbs[head]

    def uncalled_instances(self) -> None:
        """An instance whose outputs the chart reads but which it never calls: reported."""
        for head, (member, graph) in self.members_read.items():
            if head in self.instance_dbs or head in self.called:
                continue
            name, fb_type, decl_loc = self.instances[head]
            self.p.warn(
                "I022",
                f"{name} : {fb_type} is not called by the chart; {name}.{member} reads the "
                f"FB variable {graph}, which nothing in the chart writes",
                decl_loc,
            )

    def type_of(self, e: Expr) -> str | None:
        if isinstance(e, Const):
            return e.type
        if isinstance(e, Operand):
            key = e.name.upper()
            v = next((x for x in self.vars.values() if x.graph.upper() == key), None)
            return v.type if v is not None else ("BOOL" if "." in e.name else None)
        if isinstance(e, StepAttr):
            return "BOOL" if e.attr == "X" else "TIME"
        if isinstance(e, Unary):
            return self.type_of(e.operand)
        if isinstance(e, Binary):
            if e.op in _COMPARE:
                return "BOOL"
            return self.type_of(e.left) or self.type_of(e.right)
        return None

    def condition(self, e: SExpr, origin: tuple[int, int]) -> Expr:
        """A transition condition: IEC's literals 1 and 0 are TRUE and FALSE where a BOOL is
        expected — the condition itself, and the operands of NOT, AND, OR, XOR in it."""
        return self.expr(_bool_literals(e), origin)

    def expr(self, e: SExpr, origin: tuple[int, int]) -> Expr:
        loc = self.loc(e, origin)
        if isinstance(e, SLiteral):
            try:
                return const(e.text, loc)
            except (LiteralError, S7Error) as exc:
                raise _NoMap(f"constant {e.text} has no GRAPH form ({exc.message})", loc) from None
        if isinstance(e, SName | SDirect):
            return self.operand(e, origin)
        if isinstance(e, SUnary):
            return Unary(e.op, self.expr(e.operand, origin), loc)  # type: ignore[arg-type]
        if isinstance(e, SCall):
            return self.call(e, origin, loc)
        if e.op == "**":
            raise _NoMap("** (power) has no GRAPH operator", loc)
        left, right = self.expr(e.left, origin), self.expr(e.right, origin)
        if e.op in ("=", "<>") and "BOOL" in (self.type_of(left), self.type_of(right)):
            return _bool_compare(e.op, left, right, loc)
        return Binary(e.op, left, right, left.loc if hasattr(left, "loc") else loc)

    def call(self, e: SCall, origin: tuple[int, int], loc: SourceLocation) -> Expr:
        args = [self.expr(v, origin) for _, v in e.params]
        if e.name in ("AND", "OR", "XOR") and len(args) >= 2:
            out = args[0]
            for a in args[1:]:
                out = Binary(e.name, out, a, loc)
            return out
        if e.name == "NOT" and len(args) == 1:
            return Unary("NOT", args[0], loc)
        if e.name == "SEL" and len(args) == 3:
            return self.select(args, loc)
        if e.name in FUNCTIONS and len(args) == 1:
            from s7graph.sequencer.text.model import FuncCall

            return FuncCall(FUNCTIONS[e.name], (args[0],), loc)
        raise _NoMap(f"function {e.name} has no exact GRAPH equivalent", loc)

    def select(self, args: list[Expr], loc: SourceLocation) -> Expr:
        """``SEL(G, IN0, IN1)`` on BOOLs: ``NOT G AND IN0 OR G AND IN1`` (IEC 61131-3
        §6.6.2.5.9); GRAPH has no selection of other values."""
        g, in0, in1 = (_bool_literal(a) for a in args)
        types = {self.type_of(g), self.type_of(in0), self.type_of(in1)}
        if types != {"BOOL"}:
            what = ", ".join(sorted(t or "?" for t in types - {"BOOL"}))
            raise _NoMap(
                f"SEL of {what} has no GRAPH form (GRAPH expressions select no values; "
                "SEL on BOOLs is a condition)",
                loc,
            )
        return Binary(
            "OR",
            Binary("AND", Unary("NOT", g, loc), in0, loc),
            Binary("AND", g, in1, loc),
            loc,
        )
