"""Parse `.s7g` source text into the chart model (docs/chart-format.md).

``parse_chart(text, file)`` returns a :class:`~sequencer.text.model.Chart` or raises
:class:`ChartSyntaxError` carrying every syntax diagnostic found: the parser recovers at the
next ``;`` (or the next step / transition / END_ keyword) and goes on, so one run shows all
syntax errors, each with ``file:line:col`` and what was expected there. The model is built
while the parser reduces, by ``sequencer.text.build._Build``.

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
from dataclasses import replace
from functools import cache
from pathlib import Path
from typing import Any, Final

from lark import Lark, Token, Tree
from lark.exceptions import UnexpectedCharacters, UnexpectedInput, UnexpectedToken
from lark.lexer import LexerThread
from lark.parse_tree_builder import ParseTreeBuilder
from lark.parsers.lalr_parser import _Parser

from s7graph.engine.errors import S7Error, SourceLocation
from s7graph.engine.grammars import lark_parser
from s7graph.engine.text import NotUtf8, decode_utf8
from s7graph.sequencer.checks.diagnostics import Diagnostic, error, format_diagnostic
from s7graph.sequencer.collector import collector_paused
from s7graph.sequencer.text.build import _NEEDS_FIRST, _NEEDS_LAST, _Build
from s7graph.sequencer.text.comments import attach_comments
from s7graph.sequencer.text.enclosing import enclosing_element
from s7graph.sequencer.text.lalr import _fast_parse, _GiveUp, _Tables
from s7graph.sequencer.text.model import Chart

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
    return lark_parser(
        GRAMMAR,
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
    "END_STEP",
    "END_SEQUENCE",
    "END_PERMANENT",
    "END_VAR",
    "END_SYMBOLS",
    "END_FUNCTION_BLOCK",
    "STEP_KW",
    "TRANSITION",
    "SEQUENCE",
    "PERMANENT",
    "VAR",
    "SYMBOLS",
}
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
    """Phrase a lark error for a PLC programmer: what was found, what was expected, and
    the step or transition it lies in."""
    return _placed([_phrased(e, file, text)], text)[0]


def _placed(diags: list[Diagnostic], text: str) -> list[Diagnostic]:
    """``diags``, each naming the step or transition of ``text`` it lies in."""
    return [
        d if d.element else replace(d, element=enclosing_element(text, d.loc.line, d.loc.col))
        for d in diags
    ]


def _phrased(e: UnexpectedInput, file: str, text: str) -> Diagnostic:
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
        last = history[-1] if history else None
        if last is not None and last.type == "NAME" and str(last).upper() == "CALL":
            where = SourceLocation(file, last.line or loc.line, last.column or loc.col)
            return error(  # `N CALL FB 17, DB 10 (…)`: CALL read as an operand of N
                "E001",
                f"a block call is an action of its own: write CALL {tok!s}, … with no "
                "qualifier before CALL (CALL is the qualifier, as in S7-GRAPH)",
                where,
            )
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
        if e.char.isdigit():  # `١٢`, `１２`: a digit, but not one S7 writes
            hint = " (S7 numbers have the digits 0-9 only)"
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
# (the builder itself: sequencer/text/build.py)


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
# (the loop itself: sequencer/text/lalr.py)


@cache
def _tables() -> _Tables:
    return _Tables(_parser())


# ---------------------------------------------------------------- entry point


_CODE_OR_NUMBER = re.compile(
    r"'(?:[^'$\n]|\$.)*'|\"(?:[^\"\n]|\"\")*\"|\(\*.*?\*\)|//[^\n]*|([0-9]{40,})", re.S
)


def _long_numbers(text: str, file: str) -> list[Diagnostic]:
    """E003 for each run of 40 or more digits outside strings and comments: a number beyond
    every type (and beyond what Python turns into an int without a limit)."""
    out = []
    for m in _CODE_OR_NUMBER.finditer(text):
        if m[1] is not None:
            line = text.count("\n", 0, m.start()) + 1
            col = m.start() - (text.rfind("\n", 0, m.start()) + 1) + 1
            where = SourceLocation(file, line, col)
            out.append(error("E003", f"a number of {len(m[1])} digits is beyond every type", where))
    return out


_UNCLOSED = re.compile(
    r"'(?:[^'$\n]|\$.)*'|\"(?:[^\"\n]|\"\")*\"|\(\*.*?\*\)|//[^\n]*|(\(\*)", re.S
)


def _unclosed_comment(diags: list[Diagnostic], text: str, file: str) -> list[Diagnostic]:
    """``diags`` of a chart whose ``(*`` comment is never closed: those before it, then one
    E002 at the ``(*`` (the file ends in the comment) instead of an error for every word of
    it; ``diags`` as they are otherwise."""
    opened = next((m for m in _UNCLOSED.finditer(text) if m[1] is not None), None)
    if opened is None:
        return diags
    line = text.count("\n", 0, opened.start()) + 1
    col = opened.start() - (text.rfind("\n", 0, opened.start()) + 1) + 1
    said = f"the comment opened at line {line} is never closed (missing '*)')"  # as S7-SCL's
    before = [d for d in diags if (d.loc.line, d.loc.col) < (line, col)]
    return [*before, error("E002", said, SourceLocation(file, line, col))]


def parse_chart(text: str, file: str = "<input>") -> Chart:
    """Parse one `.s7g` chart (docs/chart-format.md). Raises :class:`ChartSyntaxError` with all
    syntax diagnostics (file:line:col, what was found and what was expected); a ``(*`` never
    closed is one E002 where it opens. The garbage collector is paused meanwhile
    (``sequencer.collector``)."""
    if long := _long_numbers(text, file):
        raise ChartSyntaxError(_placed(long, text))
    with collector_paused():
        try:
            return attach_comments(_parse_chart(text, file), text)
        except ChartSyntaxError as exc:
            raise ChartSyntaxError(_unclosed_comment(exc.diagnostics, text, file)) from None


def _parse_chart(text: str, file: str) -> Chart:
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
            raise ChartSyntaxError(_placed(builder.diags, text))
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
        raise ChartSyntaxError(_placed(builder.diags, text))
    return chart  # type: ignore[no-any-return]


MAX_CHART_BYTES: Final = 10_000_000
"""A chart file is at most this large (ten times the largest chart the editor sends; a
1,000-step chart with 30,000 action rows is under 1 MB): parsing more would hold a shell
for minutes."""


def chart_text(data: bytes, file: str) -> str:
    """A chart file's bytes as text; ChartSyntaxError (E001) if larger than
    :data:`MAX_CHART_BYTES`, or not UTF-8 (at the byte)."""
    if len(data) > MAX_CHART_BYTES:
        why = f"the file has {len(data):,} bytes: a chart file has at most {MAX_CHART_BYTES:,}"
        raise ChartSyntaxError([error("E001", why, SourceLocation(file, 1, 1))])
    try:
        return decode_utf8(data, file)
    except NotUtf8 as exc:
        where = exc.where if isinstance(exc.where, SourceLocation) else SourceLocation(file)
        raise ChartSyntaxError([error("E001", exc.message, where)]) from None


def parse_file(path: Path) -> Chart:
    """Read and parse a chart file (UTF-8; not UTF-8 is a located E001)."""
    return parse_chart(chart_text(Path(path).read_bytes(), str(path)), str(path))
