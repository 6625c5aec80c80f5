"""Parse `.s7g` source text into the chart model (SPEC.md §3).

``parse_chart(text, file)`` returns a :class:`~sequencer.model.Chart` or raises
:class:`ChartSyntaxError` carrying every syntax diagnostic found: the parser recovers at the
next ``;`` (or the next step / transition / END_ keyword) and goes on, so one run shows all
syntax errors, each with ``file:line:col`` and what was expected there.

Decisions the format leaves open (documented for chart writers):

* The interlock mark may be joined (``NC``, ``SC``, ``RC``, ``CALLC``, ``ONC``, ``OFFC``,
  ``CSC`` ...) or apart (``N C Q0.0``). ``CS CU CD CR`` are the counter qualifiers, never
  S/U/D/R with a mark. A lone ``C`` followed by a number is counter ``C n``
  (``CU C 5``); ``CU C C 5`` is CU with the mark.
* Absolute addresses may hold blanks (``I 0.0``); the model stores them without blanks.
* In permanent instructions ``x := cond`` is a :class:`Coil` when ``x`` is an absolute bit
  address, else an :class:`Assignment` (an assignment to a BOOL symbol or variable is a coil
  in effect; the validator checks types either way).
* ``CALL "Name", "Inst" (...)`` / ``CALL FB 5, DB 5 (...)``: the instance follows the comma.
* Literals are read by ``engine.literals.parse_literal``; ``-`` before a numeric literal is
  folded into the constant.
"""

from __future__ import annotations

import contextlib
import re
from collections.abc import Callable
from contextvars import ContextVar
from copy import copy
from functools import cache, lru_cache
from pathlib import Path
from typing import Any

from lark import Lark, Token, Tree
from lark.exceptions import UnexpectedCharacters, UnexpectedInput, UnexpectedToken
from lark.lexer import LexerThread
from lark.parse_tree_builder import ParseTreeBuilder
from lark.parsers.lalr_parser import _Parser

from engine.errors import LiteralError, S7Error, SourceLocation
from sequencer.diagnostics import Diagnostic, error, format_diagnostic
from sequencer.model import (
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
from sequencer.parse_fast import _fast_parse, _GiveUp, _Tables
from steps.qualifiers import QUALIFIERS

GRAMMAR = Path(__file__).with_name("grammar.lark")
MAX_SYNTAX_ERRORS = 20


class ChartSyntaxError(S7Error):
    """The source does not parse; ``diagnostics`` lists every syntax error found."""

    def __init__(self, diagnostics: list[Diagnostic]) -> None:
        self.diagnostics = diagnostics
        first = diagnostics[0]
        more = f" (and {len(diagnostics) - 1} more)" if len(diagnostics) > 1 else ""
        super().__init__(f"{format_diagnostic(first)}{more}")


@cache
def _parser() -> Lark:
    return Lark(
        GRAMMAR.read_text(encoding="utf-8"),
        parser="lalr",
        lexer="contextual",
        maybe_placeholders=True,
        lexer_callbacks={"LINE_COMMENT": _on_comment},
    )


_COMMENTS: ContextVar[dict[int, tuple[int, str]] | None] = ContextVar("_COMMENTS", default=None)


def _on_comment(tok: Token) -> Token:
    """Remember ``// comments`` by line (a symbol's trailing comment is its comment)."""
    sink = _COMMENTS.get()
    if sink is not None:
        sink[tok.line or 0] = (tok.column or 0, str(tok)[2:].strip())
    return tok


# ---------------------------------------------------------------- error messages

_TERMINAL_WORDS = {
    "DQSTRING": 'a quoted name like "Start_button"',
    "NAME": "a name",
    "NUMBER": "a number",
    "LITERAL": "a constant like 5, TRUE or T#2S",
    "ADDRESS": "an address like I0.0 or MW10",
    "STEP_REF": "a step like S3",
    "TRANS_REF": "a transition like T2",
    "STEP_ATTR": "S3.X, S3.T or S3.U",
    "TRANS_ATTR": "T2.TT",
    "EVENT": "an event (S1 S0 V1 V0 L1 L0 A1 R1)",
    "QUAL": "a qualifier (N S R D L CALL ON OFF CS CU CD CR TL TD TF TR)",
    "CMARK": "the interlock mark C",
    "BLOCK": "a block like FB 5 or FC 1",
    "DBREF": "a data block like DB 5",
    "STEP_KW": "STEP or INITIAL_STEP",
    "PLACE": "BEFORE or AFTER",
    "CMPOP": "a comparison (= <> < > <= >=)",
    "ADDOP": "+ or -",
    "MULOP": "* / or MOD",
    "SHIFTOP": "SHL SHR SSR ROL ROR",
    "MINUS": "'-'",
    "S_ALL": "S_ALL",
    "STOP": "STOP",
    "INTERLOCK": "INTERLOCK",
    "SUPERVISION": "SUPERVISION",
    "SEMICOLON": "';'",
    "$END": "the end of the file",
}
# Tokens after which a statement is complete, and tokens that start the next one.
_STATEMENT_END = {"SEMICOLON"}
_BOUNDARY = {
    "END_STEP", "END_SEQUENCE", "END_PERMANENT", "END_VAR", "END_SYMBOLS",
    "END_FUNCTION_BLOCK", "STEP_KW", "TRANSITION", "SEQUENCE", "PERMANENT", "VAR", "SYMBOLS",
}  # fmt: skip
# Terminals accepted only where the parser waits between statements (recovery points).
_SYNC = _BOUNDARY | {"QUAL", "EVENT", "INTERLOCK", "SUPERVISION"}


def _describe(name: str) -> str:
    if name in _TERMINAL_WORDS:
        return _TERMINAL_WORDS[name]
    try:
        term = _parser().get_terminal(name)
    except KeyError:
        return name
    if term.pattern.type == "str":
        return f"'{term.pattern.value}'"
    return name.replace("_", " ").lower()


def _expected(names: set[str]) -> str:
    words = sorted({_describe(n) for n in names})
    if not words:
        return "something else"
    if len(words) > 7:
        words = [*words[:7], "..."]
    return " or ".join(words) if len(words) <= 2 else ", ".join(words[:-1]) + " or " + words[-1]


def _shown(tok: Token) -> str:
    if tok.type == "$END":
        return "the end of the file"
    text = str(tok)
    return f"'{text}'" if len(text) < 40 else f"'{text[:37]}...'"


def _end_of(text: str) -> tuple[int, int]:
    """The place just after the last non-blank character."""
    text = text.rstrip()
    line = text.count("\n") + 1
    return line, len(text) - (text.rfind("\n") + 1) + 1


def _syntax_diagnostic(e: UnexpectedInput, file: str, text: str) -> Diagnostic:
    """Phrase a lark error for a PLC programmer: what was found, what was expected."""
    loc = SourceLocation(file, e.line if e.line and e.line > 0 else 1, max(e.column or 1, 1))
    if isinstance(e, UnexpectedToken):
        tok = e.token
        expected = set(e.expected)
        if tok.type == "$END":
            line, col = _end_of(text)
            return error(
                "E002",
                f"the file ends too early; expected {_expected(expected)}",
                SourceLocation(file, line, col),
            )
        history = list(getattr(e, "token_history", None) or ())
        if "SEMICOLON" in expected and (
            tok.type in _SYNC
            or tok.line != getattr(history[-1] if history else None, "end_line", tok.line)
        ):
            prev = history[-1] if history else None
            if prev is not None and prev.end_line is not None and prev.end_column is not None:
                loc = SourceLocation(file, prev.end_line, prev.end_column)
                return error("E001", f"missing ';' after {_shown(prev)}", loc)
            return error("E001", f"missing ';' before {_shown(tok)}", loc)
        closers = sorted(n for n in expected if n.startswith("END_"))
        if tok.type in _BOUNDARY and closers:
            return error("E001", f"missing {closers[0]} before {_shown(tok)}", loc)
        return error("E001", f"unexpected {_shown(tok)}; expected {_expected(expected)}", loc)
    if isinstance(e, UnexpectedCharacters):
        allowed = set(e.allowed or ())
        hint = f"; expected {_expected(allowed)}" if 0 < len(allowed) <= 7 else ""
        return error("E001", f"unexpected character {e.char!r}{hint}", loc)
    return error("E001", str(e), loc)


def _recover(e: UnexpectedToken) -> None:
    """Panic-mode recovery: unwind the parser to where it waits between statements, then
    resume at the offending token if it starts a statement, else after the next ``;``."""
    ip = e.interactive_parser
    state = ip.parser_state
    states = state.parse_conf.parse_table.states
    while len(state.state_stack) > 1 and not (set(states[state.state_stack[-1]]) & _SYNC):
        state.state_stack.pop()
        state.value_stack.pop()
    tok = e.token
    if tok.type in states[state.state_stack[-1]]:
        with contextlib.suppress(UnexpectedInput):
            ip.feed_token(tok)
        return
    if tok.type in _STATEMENT_END:
        return
    lex_state = ip.lexer_thread.state
    if lex_state is None:
        return
    text = str(lex_state.text.text) if hasattr(lex_state.text, "text") else str(lex_state.text)
    pos = lex_state.line_ctr.char_pos
    m = _RESYNC.search(text, pos)
    if m is None:
        return
    end = m.end() if m.group(0) == ";" else m.start()
    lex_state.line_ctr.feed(text[pos:end])


_RESYNC = re.compile(
    r";|(?<![\w\"])(?:END_STEP|END_SEQUENCE|END_PERMANENT|END_VAR|END_SYMBOLS|END_FUNCTION_BLOCK"
    r"|INITIAL_STEP|STEP|TRANSITION)(?![\w])",
    re.IGNORECASE,
)


# ---------------------------------------------------------------- tree → model


_NON_DIGITS = re.compile(r"\D")
_BLANKS = re.compile(r"\s+")


def _int(tok: Token | str) -> int:
    return int(_NON_DIGITS.sub("", str(tok)))


@lru_cache(maxsize=4096)
def _literal(text: str) -> tuple[str, object]:
    """``engine.literals.parse_literal`` of a literal's text (values are immutable; a chart
    repeats its constants, T#20MS 500 times in the benchmark's)."""
    from engine.literals import parse_literal

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
            self._err("E003", f"bad constant {str(tok)!r}: {exc.message}", loc)
            return Const(0, "INT", str(tok), loc)
        return Const(value, type_name, str(tok), loc)

    def address(self, ch: list[Token]) -> Operand:
        return Operand(_BLANKS.sub("", str(ch[0])), False, self._loc(ch[0]))

    def symbol(self, ch: list[Token]) -> Operand:
        return Operand(_unquote(ch[0]), True, self._loc(ch[0]))

    def name(self, ch: list[Token]) -> Operand:
        return Operand(str(ch[0]), False, self._loc(ch[0]))

    def step_attr(self, ch: list[Token]) -> StepAttr:
        num, attr = str(ch[0]).split(".")
        return StepAttr(_int(num), attr.upper(), self._loc(ch[0]))  # type: ignore[arg-type]

    def trans_attr(self, ch: list[Token]) -> TransAttr:
        num, _ = str(ch[0]).split(".")
        return TransAttr(_int(num), "TT", self._loc(ch[0]))

    def func_call(self, ch: list[Any]) -> FuncCall:
        args = tuple(a for a in ch[1:] if a is not None)
        return FuncCall(str(ch[0]).upper(), args, self._loc(ch[0]))

    def not_expr(self, ch: list[Any]) -> Unary:
        return Unary("NOT", ch[1], self._loc(ch[0]))

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
            return Const(value, type_name, "-" + inner.text, loc)
        return Unary("-", inner, loc)

    def _binary(self, ch: list[Any]) -> Binary:
        op = str(ch[1]).upper()
        op = "AND" if op == "&" else op
        return Binary(op, ch[0], ch[2], self._expr_loc(ch[0]))

    or_expr = xor_expr = and_expr = cmp_expr = shift_expr = add_expr = mul_expr = _binary

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


@cache
def _tree_builder() -> ParseTreeBuilder:
    """lark's child filtering / ``?rule`` inlining / placeholders, without positions."""
    return ParseTreeBuilder(_parser().rules, Tree, maybe_placeholders=True)  # type: ignore[no-untyped-call]


def _callbacks(builder: _Build) -> dict[Any, Callable[[list[Any]], Any]]:
    """The LALR reduce callbacks calling ``builder``'s methods (see :class:`_Build`)."""
    callbacks: dict[Any, Callable[[list[Any]], Any]]
    callbacks = _tree_builder().create_callback(builder)  # type: ignore[no-untyped-call]
    for rule, f in list(callbacks.items()):
        name = rule.origin.name
        if name in _NEEDS_FIRST:
            callbacks[rule] = _with_first(builder, f)
        elif name in _NEEDS_LAST:
            callbacks[rule] = _with_last(builder, f)
    return callbacks


def _with_first(builder: _Build, f: Callable[[list[Any]], Any]) -> Callable[[list[Any]], Any]:
    def callback(children: list[Any]) -> Any:
        builder.first = children[0]
        return f(children)

    return callback


def _with_last(builder: _Build, f: Callable[[list[Any]], Any]) -> Callable[[list[Any]], Any]:
    def callback(children: list[Any]) -> Any:
        builder.last = children[-1]
        return f(children)

    return callback


# ---------------------------------------------------------------- fast path
# (the loop itself: sequencer/parse_fast.py)


@cache
def _tables() -> _Tables:
    return _Tables(_parser())


# ---------------------------------------------------------------- entry point


def parse_chart(text: str, file: str = "<input>") -> Chart:
    """Parse one `.s7g` chart (SPEC §3). Raises :class:`ChartSyntaxError` with all syntax
    diagnostics (file:line:col, what was found and what was expected)."""
    diags: list[Diagnostic] = []
    comments: dict[int, tuple[int, str]] = {}
    seen: set[tuple[int, int]] = set()

    def on_error(e: UnexpectedInput) -> bool:
        d = _syntax_diagnostic(e, file, text)
        key = (d.loc.line, d.loc.col)
        if key not in seen:
            seen.add(key)
            diags.append(d)
        if len(diags) >= MAX_SYNTAX_ERRORS:
            return False
        if isinstance(e, UnexpectedToken):
            if e.token.type == "$END":
                return False
            _recover(e)
        return True

    # The model is built while parsing; after a syntax error it is thrown away.
    builder = _Build(file, comments)
    token = _COMMENTS.set(comments)
    try:
        chart = _fast_parse(text, _callbacks(builder), _tables())
    except _GiveUp:
        pass
    except (AttributeError, KeyError, TypeError, RuntimeError):  # lark internals changed:
        pass  # the fast path is only a shortcut; lark's own parser below is the reference
    else:
        if builder.diags:
            raise ChartSyntaxError(builder.diags)
        return chart  # type: ignore[no-any-return]
    finally:
        _COMMENTS.reset(token)

    # A syntax error: parse again with lark, reporting and recovering.
    comments = {}
    builder = _Build(file, comments)
    frontend = _parser().parser
    lalr = copy(frontend.parser)
    lalr.parser = _Parser(lalr.parser.parse_table, _callbacks(builder))
    token = _COMMENTS.set(comments)
    try:
        chart = lalr.parse(LexerThread.from_text(frontend.lexer, text), "start", on_error=on_error)
    except UnexpectedInput as e:
        d = _syntax_diagnostic(e, file, text)
        if (d.loc.line, d.loc.col) not in seen:
            diags.append(d)
        raise ChartSyntaxError(diags) from None
    finally:
        _COMMENTS.reset(token)
    if diags:
        raise ChartSyntaxError(diags)
    if builder.diags:
        raise ChartSyntaxError(builder.diags)
    return chart  # type: ignore[no-any-return]


def parse_file(path: Path) -> Chart:
    """Read and parse a chart file (UTF-8)."""
    return parse_chart(path.read_text(encoding="utf-8"), str(path))
