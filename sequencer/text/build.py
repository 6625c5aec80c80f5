"""Build the chart model while the LALR parser reduces (docs/chart-format.md): :class:`_Build` has
one method per grammar rule; ``sequencer.text.parse`` wires it into the parser (``_callbacks``).

Decisions the format leaves open are listed in ``sequencer.text.parse``.
"""

from __future__ import annotations

import re
from functools import lru_cache
from typing import Any, TypeVar

from lark import Token

from s7graph.engine.errors import LiteralError, S7Error, SourceLocation
from s7graph.engine.literals import clip
from s7graph.sequencer.checks.diagnostics import Diagnostic, error
from s7graph.sequencer.text.model import (
    ActionRow,
    Assignment,
    Binary,
    BlockCall,
    Chart,
    ChartOptions,
    Coil,
    Const,
    Expr,
    FuncCall,
    Operand,
    PermanentInstruction,
    Sequence,
    Step,
    StepAttr,
    StepTarget,
    SymbolDecl,
    TransAttr,
    Transition,
    Unary,
    VarDecl,
)
from s7graph.steps.qualifiers import QUALIFIERS

_NON_DIGITS = re.compile(r"\D")
_E = TypeVar("_E", Binary, Unary, FuncCall)
MAX_EXPR_DEPTH = 32
"""Operators nested in one expression (an AND/OR/XOR chain counts about log2 of its
length): what the generated code and the validator handle without deep recursion."""
_BLANKS = re.compile(r"\s+")
_BARE_DECIMAL = re.compile(r"\d(?:_?\d)*")


def _bare_decimal(text: str) -> bool:
    """Whether ``text`` is an integer literal without prefix (``32768``, not ``L#32768``)."""
    return _BARE_DECIMAL.fullmatch(text) is not None


def _int(tok: Token | str) -> int:
    return int(_NON_DIGITS.sub("", str(tok)))


@lru_cache(maxsize=4096)
def _literal(text: str) -> tuple[str, object]:
    """``engine.literals.parse_literal`` of a literal's text (values are immutable; a chart
    repeats its constants, T#20MS 500 times in the benchmark's)."""
    from s7graph.engine.literals import parse_literal

    return parse_literal(text)


def _unquote(tok: Token | str) -> str:
    return str(tok)[1:-1].replace('""', '"')


_QUAL_BASE = frozenset(QUALIFIERS)
_BIT_ADDRESS = re.compile(r"(?i)(DB\d+\.DBX|P?[IQEAML]X?)\d+\.\d+")


def _split_qualifier(text: str) -> tuple[str, bool]:
    """``NC`` → (``N``, True); ``CS`` → (``CS``, False) — CS CU CD CR are counters."""
    q = text.upper()
    if q in _QUAL_BASE:
        return q, False
    if q.endswith("C") and q[:-1] in _QUAL_BASE:
        return q[:-1], True
    return q, False


_OPTIONS: dict[str, tuple[str, tuple[str, ...]]] = {
    "PARAMETERS": ("parameters", ("MINIMUM", "STANDARD", "MAXIMUM", "USER")),
    "SKIP_STEPS": ("skip_steps", ("TRUE", "FALSE")),
    "ACK_REQUIRED": ("ack_required", ("TRUE", "FALSE")),
    "MESSAGES": ("messages", ("TRUE", "FALSE")),
    "ACK_FORCES_SWITCH": ("ack_forces_switch", ("TRUE", "FALSE")),
    "ORDER": ("order", ("GRAPH", "CODESYS")),
}


class _Build:
    """Builds the model while the LALR parser reduces (no parse tree is built): one method
    per grammar rule, called with the rule's children as lark's tree builder would give
    them (anonymous tokens filtered out, ``None`` for a missing ``[optional]``, ``?rules``
    with one child inlined). Shape errors go to ``diags``.

    A few rules need the place of a keyword the filter drops (``TRANSITION``, ``SEQUENCE``,
    ``CALL``, ``S``/``R`` of a coil, ``FUNCTION_BLOCK``) or of the closing ``;`` (a symbol's
    trailing comment): their callbacks store the first and last raw child in ``first`` and
    ``last`` just before the method runs (see :func:`_callbacks`)."""

    def __init__(self, file: str, comments: dict[int, tuple[int, str]]) -> None:
        self.file = file
        self.comments = comments
        self.diags: list[Diagnostic] = []
        self.chains: dict[int, tuple[Binary, str, tuple[tuple[int, Any, int], ...]]] = {}
        """Open AND/OR/XOR chains: node id → (node, op, its balanced parts)."""
        self.depths: dict[int, tuple[Any, int]] = {}
        """Expressions not yet taken by a parent: node id → (node, nesting depth)."""
        self.first: Token = Token("$START", "")
        self.last: Token = self.first

    # -- helpers
    def _loc(self, tok: Token) -> SourceLocation:
        return SourceLocation(self.file, tok.line or 0, tok.column or 0)

    def _err(self, code: str, message: str, loc: SourceLocation, element: str = "") -> None:
        self.diags.append(error(code, message, loc, element))

    # -- expressions
    def literal(self, ch: list[Token]) -> Const:
        tok = ch[0]
        loc = self._loc(tok)
        try:
            type_name, value = _literal(str(tok))
        except (LiteralError, S7Error) as exc:
            self._err("E003", f"bad constant {clip(str(tok))}: {exc.message}", loc)
            return Const(0, "INT", str(tok), loc)
        return Const(value, type_name, str(tok), loc)

    def address(self, ch: list[Token]) -> Operand:
        return Operand(_BLANKS.sub("", str(ch[0])), False, self._loc(ch[0]))

    def symbol(self, ch: list[Token]) -> Operand:
        return Operand(_unquote(ch[0]), True, self._loc(ch[0]))

    def name(self, ch: list[Token]) -> Operand:
        return Operand(str(ch[0]), False, self._loc(ch[0]))

    def member(self, ch: list[Token]) -> Operand:
        """``DB10.Q`` / ``"T_S2".Q``: a variable of an instance DB, read by name."""
        if len(ch) == 2:
            return Operand(_unquote(ch[0]), True, self._loc(ch[0]), member=str(ch[1]))
        db, _, member = _BLANKS.sub("", str(ch[0])).partition(".")
        return Operand(f"DB{_int(db)}", False, self._loc(ch[0]), member=member)

    def step_attr(self, ch: list[Token]) -> StepAttr:
        num, attr = str(ch[0]).split(".")
        return StepAttr(_int(num), attr.upper(), self._loc(ch[0]))  # type: ignore[arg-type]

    def trans_attr(self, ch: list[Token]) -> TransAttr:
        num, _ = str(ch[0]).split(".")
        return TransAttr(_int(num), "TT", self._loc(ch[0]))

    def func_call(self, ch: list[Any]) -> FuncCall:
        args = tuple(a for a in ch[1:] if a is not None)
        return self._nested(FuncCall(str(ch[0]).upper(), args, self._loc(ch[0])), *args)

    def not_expr(self, ch: list[Any]) -> Unary:
        return self._nested(Unary("NOT", ch[1], self._loc(ch[0])), ch[1])

    def neg_expr(self, ch: list[Any]) -> Expr:
        inner = ch[1]
        loc = self._loc(ch[0])
        if (
            isinstance(inner, Const)
            and isinstance(inner.value, int | float)
            and not isinstance(inner.value, bool)
            and inner.type in ("INT", "DINT", "REAL", "TIME")
        ):
            value = -inner.value
            type_name = inner.type
            if type_name == "INT" and value < -32768:
                type_name = "DINT"
            elif type_name == "DINT" and value == -32768 and _bare_decimal(inner.text):
                type_name = "INT"  # -32768 is the least INT (its 32768 alone is a DINT)
            return Const(value, type_name, "-" + inner.text, loc)
        return self._nested(Unary("-", inner, loc), inner)

    def _binary(self, ch: list[Any]) -> Binary:
        op = str(ch[1]).upper()
        op = "AND" if op == "&" else op
        return self._nested(Binary(op, ch[0], ch[2], self._expr_loc(ch[0])), ch[0], ch[2])

    def _chain(self, ch: list[Any]) -> Binary:
        """``a AND b AND c …`` (also OR, XOR): associative, so built balanced — a chain of
        n contacts is about log2(n) deep, not n, and nothing walking it recurses deeply.
        The contacts stay in source order (the order of the criteria bits)."""
        op = str(ch[1]).upper()
        op = "AND" if op == "&" else op
        left, right = ch[0], ch[2]
        known = self.chains.pop(id(left), None)
        if known is not None and known[0] is left and known[1] == op:
            parts = list(known[2])
            self.depths.pop(id(left), None)
        else:
            parts = [(1, left, self._depth_of(left))]
        parts.append((1, right, self._depth_of(right)))
        while len(parts) > 1 and parts[-1][0] == parts[-2][0]:  # a binary counter
            (n, a, da), (m, b, db) = parts[-2], parts[-1]
            parts[-2:] = [(n + m, Binary(op, a, b, self._expr_loc(a)), 1 + max(da, db))]
        _, last, depth = parts[-1]
        tree: Binary = last  # the right end of the fold (a lone part is a merged Binary)
        for _, part, d in reversed(parts[:-1]):
            tree, depth = Binary(op, part, tree, self._expr_loc(part)), 1 + max(d, depth)
        self.chains[id(tree)] = (tree, op, tuple(parts))
        return self._deep(tree, depth)

    or_expr = xor_expr = and_expr = _chain
    cmp_expr = shift_expr = add_expr = mul_expr = _binary

    def _depth_of(self, e: object) -> int:
        """The nesting depth of a finished child expression (taken once, by its parent)."""
        known = self.depths.pop(id(e), None)
        return known[1] if known is not None and known[0] is e else 0

    def _nested(self, node: _E, *children: object) -> _E:
        return self._deep(node, 1 + max((self._depth_of(c) for c in children), default=0))

    def _deep(self, node: _E, depth: int) -> _E:
        """Remember ``node``'s depth for its parent; past ``MAX_EXPR_DEPTH`` it is an error
        (E006, once per expression: where it crosses the limit)."""
        self.depths[id(node)] = (node, depth)
        if depth == MAX_EXPR_DEPTH + 1:
            self._err(
                "E006",
                f"expression nested deeper than {MAX_EXPR_DEPTH} levels; "
                "split it into several assignments or transitions",
                node.loc,
            )
        return node

    @staticmethod
    def _expr_loc(e: Any) -> SourceLocation:
        return getattr(e, "loc", SourceLocation())

    # -- declarations
    def type_name(self, ch: list[Any]) -> str:
        base = str(ch[0]).upper()
        return f"{base}[{int(ch[1])}]" if len(ch) > 1 and ch[1] is not None else base

    def init(self, ch: list[Any]) -> Const:
        if len(ch) == 2:
            return self.neg_expr([ch[0], self.literal([ch[1]])])  # type: ignore[return-value]
        return self.literal(ch)

    def var_decl(self, ch: list[Any]) -> VarDecl:
        return VarDecl(str(ch[0]), ch[1], ch[2], self._loc(ch[0]))

    def var_section(self, ch: list[Any]) -> tuple[str, list[VarDecl]]:
        return ("vars", ch)

    def symbol_decl(self, ch: list[Any]) -> SymbolDecl:
        comment = ""
        end = self.last  # the closing ';'
        if end.end_line in self.comments:
            col, text = self.comments[end.end_line]
            if col >= (end.end_column or 0):
                comment = text
        return SymbolDecl(
            _unquote(ch[0]), _BLANKS.sub("", str(ch[1])), ch[2], comment, self._loc(ch[0])
        )

    def symbols_section(self, ch: list[SymbolDecl]) -> tuple[str, list[SymbolDecl]]:
        # a trailing comment belongs to the last declaration on its line only
        out: list[SymbolDecl] = []
        for i, s in enumerate(ch):
            later_same_line = any(t.loc.line == s.loc.line for t in ch[i + 1 :])
            if s.comment and later_same_line:
                s = SymbolDecl(s.name, s.address, s.type, "", s.loc)
            out.append(s)
        return ("symbols", out)

    def option(self, ch: list[Token]) -> tuple[str, tuple[str, str, SourceLocation]]:
        return ("option", (str(ch[0]).upper(), str(ch[1]).upper(), self._loc(ch[0])))

    def block_ref(self, ch: list[Token]) -> tuple[str, int, SourceLocation]:
        text = str(ch[0]).upper()
        kind = re.match(r"[A-Z]+", text)
        return (kind.group(0) if kind else "", _int(text), self._loc(ch[0]))

    def db_ref(self, ch: list[Token]) -> tuple[str, int, SourceLocation]:
        return ("DB", _int(ch[0]), self._loc(ch[0]))

    # -- calls and permanent instructions
    def in_param(self, ch: list[Any]) -> tuple[str, str, Any]:
        return ("in", str(ch[0]), ch[1])

    def out_param(self, ch: list[Any]) -> tuple[str, str, Any]:
        return ("out", str(ch[0]), ch[1])

    def call_params(self, ch: list[Any]) -> list[tuple[str, str, Any]]:
        return [p for p in ch if p is not None]

    def _block_call(
        self, block: Any, instance: Any, params: list[Any] | None, loc: SourceLocation
    ) -> BlockCall:
        if isinstance(block, Operand):
            kind, number_or_name = "", block.name
        else:
            kind, number_or_name = block[0], block[1]
        inst: int | str | None = None
        if isinstance(instance, Operand):
            inst = instance.name
        elif isinstance(instance, tuple):
            inst = instance[1]
        ins = tuple((n, v) for d, n, v in params or () if d == "in")
        outs = tuple((n, v) for d, n, v in params or () if d == "out")
        return BlockCall(kind, number_or_name, inst, ins, outs, loc)

    def call(self, ch: list[Any]) -> BlockCall:
        return self._block_call(ch[0], ch[1], ch[2], _first_loc(ch[0]))

    def perm_call(self, ch: list[Any]) -> BlockCall:
        c: BlockCall = ch[0]
        return BlockCall(c.kind, c.block, c.instance, c.inputs, c.outputs, self._loc(self.first))

    def coil(self, ch: list[Any]) -> PermanentInstruction:
        target, expr = ch
        if not target.quoted and re.fullmatch(
            r"(?i)(DB\d+\.DBX|P?[IQEAML]X?)\d+\.\d+", target.name
        ):
            return Coil("=", target, expr, target.loc)
        return Assignment(target, expr, target.loc)

    def set_coil(self, ch: list[Any]) -> Coil:
        return Coil("S", ch[0], ch[1], self._loc(self.first))

    def reset_coil(self, ch: list[Any]) -> Coil:
        return Coil("R", ch[0], ch[1], self._loc(self.first))

    def permanent(self, ch: list[Any]) -> tuple[str, list[Any]]:
        return ("perm_" + str(ch[0]).lower(), ch[1:])

    # -- action rows
    def row_operand(self, ch: list[Any]) -> tuple[str, Any, Any, Any]:
        return ("operand", ch[0], ch[1], ch[2])

    def row_assign(self, ch: list[Any]) -> tuple[str, Any]:
        return ("assign", Assignment(ch[0], ch[1], ch[0].loc))

    def row_call_block(self, ch: list[Any]) -> tuple[str, Any, Any, Any]:
        return ("block", ch[0], ch[1], ch[2])

    def row_step(self, ch: list[Token]) -> tuple[str, StepTarget]:
        return ("step", StepTarget(_int(ch[0]), self._loc(ch[0])))

    def row_s_all(self, ch: list[Token]) -> tuple[str, StepTarget]:
        return ("step", StepTarget(None, self._loc(ch[0])))

    def row(self, ch: list[Any]) -> ActionRow | None:
        event_tok, qual_tok, cmark, body = ch
        qualifier, joined = _split_qualifier(str(qual_tok))
        interlocked = joined or cmark is not None
        event = str(event_tok).upper() if event_tok is not None else None
        loc = self._loc(event_tok if event_tok is not None else qual_tok)
        kind = body[0]
        where = f"{qualifier}{'C' if interlocked else ''}"
        operand: Any
        value: Expr | None = None
        if qualifier == "CALL":
            if kind == "block" or (
                kind == "operand" and body[1].quoted and (body[2] is None or _is_instance(body[2]))
            ):
                operand = self._block_call(body[1], body[2], body[3], self._loc(qual_tok))
            else:
                self._err(
                    "E005",
                    'CALL needs a block: CALL FB 5, DB 5 (...), CALL FC 1 or CALL "Name"',
                    loc,
                )
                return None
        elif qualifier in ("ON", "OFF"):
            if kind != "step":
                self._err("E005", f"{qualifier} needs a step (like S4) or S_ALL", loc)
                return None
            operand = body[1]
        elif kind == "assign":
            if qualifier != "N":
                self._err("E005", f"only N may assign a value, not {where}", loc)
                return None
            operand = body[1]
        elif kind == "operand":
            operand = body[1]
            if body[3] is not None:
                self._err("E005", f"{where} takes no call parameters", loc)
                return None
            if isinstance(body[2], tuple):
                self._err("E005", f"{where} takes a value, not a data block", loc)
                return None
            value = body[2]
        else:
            what = "a step" if kind == "step" else "a block"
            self._err(
                "E005",
                f"{where} cannot take {what}; only ON/OFF take steps and CALL takes blocks",
                loc,
            )
            return None
        return ActionRow(qualifier, operand, event, interlocked, value, loc)

    def interlock(self, ch: list[Any]) -> tuple[str, Any, SourceLocation]:
        return ("interlock", ch[1], self._loc(ch[0]))

    def supervision(self, ch: list[Any]) -> tuple[str, Any, SourceLocation]:
        return ("supervision", ch[1], self._loc(ch[0]))

    def step(self, ch: list[Any]) -> Step:
        kw, ref, name, message, *items = ch
        interlock = supervision = None
        il_loc = sv_loc = None
        rows: list[ActionRow] = []
        for it in items:
            if isinstance(it, ActionRow):
                rows.append(it)
            elif isinstance(it, tuple) and it[0] == "interlock":
                interlock, il_loc = it[1], it[2]
            elif isinstance(it, tuple) and it[0] == "supervision":
                supervision, sv_loc = it[1], it[2]
        return Step(
            number=_int(ref),
            name=_unquote(name) if name is not None else "",
            initial=str(kw).upper().startswith("INITIAL"),
            message=_unquote(message) if message is not None else "",
            interlock=interlock,
            supervision=supervision,
            actions=tuple(rows),
            loc=self._loc(kw),
            interlock_loc=il_loc,
            supervision_loc=sv_loc,
        )

    def step_set(self, ch: list[Token]) -> list[tuple[int, SourceLocation]]:
        return [(_int(t), self._loc(t)) for t in ch]

    def stop(self, ch: list[Token]) -> list[tuple[int, SourceLocation]]:
        return []

    def transition(self, ch: list[Any]) -> Transition:
        ref, name, sources, targets, cond = ch
        return Transition(
            number=_int(ref),
            name=_unquote(name) if name is not None else "",
            sources=tuple(n for n, _ in sources),
            targets=tuple(n for n, _ in targets),
            condition=cond,
            loc=self._loc(self.first),
            source_locs=tuple(loc for _, loc in sources),
            target_locs=tuple(loc for _, loc in targets),
        )

    def sequence(self, ch: list[Any]) -> Sequence:
        number, name, *items = ch
        return Sequence(
            number=int(number),
            name=_unquote(name) if name is not None else "",
            steps=tuple(i for i in items if isinstance(i, Step)),
            transitions=tuple(i for i in items if isinstance(i, Transition)),
            loc=self._loc(self.first),
        )

    def start(self, ch: list[Any]) -> Chart:
        name, fb, db, *items = ch
        opts: dict[str, object] = {}
        option_locs: list[tuple[str, SourceLocation]] = []
        vars_: list[VarDecl] = []
        symbols: list[SymbolDecl] = []
        before: list[Any] = []
        after: list[Any] = []
        sequences: list[Sequence] = []
        for it in items:
            if isinstance(it, Sequence):
                sequences.append(it)
                continue
            tag, payload = it
            if tag == "option":
                self._option(payload, opts, option_locs)
            elif tag == "vars":
                vars_.extend(payload)
            elif tag == "symbols":
                symbols.extend(payload)
            elif tag == "perm_before":
                before.extend(payload)
            elif tag == "perm_after":
                after.extend(payload)
        if fb is not None and fb[0] != "FB":
            self._err("E001", f"a GRAPH block is an FB, not {fb[0]}", fb[2])
        return Chart(
            name=_unquote(name),
            fb_number=fb[1] if fb is not None else None,
            db_number=db[1] if db is not None else None,
            options=ChartOptions(**opts),  # type: ignore[arg-type]
            option_locs=tuple(option_locs),
            vars=tuple(vars_),
            symbols=tuple(symbols),
            before=tuple(before),
            sequences=tuple(sequences),
            after=tuple(after),
            file=self.file,
            loc=self._loc(self.first),
        )

    def _option(
        self,
        payload: tuple[str, str, SourceLocation],
        opts: dict[str, object],
        locs: list[tuple[str, SourceLocation]],
    ) -> None:
        key, value, loc = payload
        if key not in _OPTIONS:
            known = " ".join(_OPTIONS)
            self._err("E004", f"unknown option {key}; known options: {known}", loc)
            return
        field_name, allowed = _OPTIONS[key]
        if value not in allowed:
            self._err("E004", f"{key} must be {' or '.join(allowed)}, not {value}", loc)
            return
        if allowed == ("TRUE", "FALSE"):
            opts[field_name] = value == "TRUE"
        elif field_name == "order":
            opts[field_name] = value.lower()
        else:
            opts[field_name] = value
        locs.append((field_name, loc))


def _is_instance(x: Any) -> bool:
    """A CALL instance: ``DB 5`` (a tuple from ``db_ref``) or a quoted name."""
    return isinstance(x, tuple) or (isinstance(x, Operand) and x.quoted)


def _first_loc(block: Any) -> SourceLocation:
    """Where a ``call`` starts: at its block (``block_ref`` tuple) or symbol (operand)."""
    return block[2] if isinstance(block, tuple) else block.loc  # type: ignore[no-any-return]


# Rules whose method reads ``first`` (the rule's first raw token, usually a keyword the
# child filter drops) or ``last`` (its last raw token).
_NEEDS_FIRST = frozenset({"perm_call", "set_coil", "reset_coil", "transition", "sequence", "start"})
_NEEDS_LAST = frozenset({"symbol_decl"})
