"""IEC 61131-3 structured text as an importer reads it: a small syntax tree with places.

``parse_expression`` (a transition condition), ``parse_statements`` (an action body) and
``parse_iec_file`` (textual SFC, in ``exchange.iec_text``) use one grammar, ``iec.lark``.
Every node carries the line and column where it was written *in the text given*; an XML
importer passes the place of that text in its file (``origin``) so that every problem is
located in the file itself. A syntax error raises ``StSyntaxError`` with that place, as
does text nested deeper than ``MAX_TREE_DEPTH`` (at the first element past it).
"""

from __future__ import annotations

import dataclasses
import re
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from typing import Any

from lark import Lark, Token, Transformer, Tree, v_args
from lark.exceptions import UnexpectedCharacters, UnexpectedInput, UnexpectedToken, VisitError

from s7graph.engine.errors import S7Error, SourceLocation
from s7graph.engine.grammars import lark_parser
from s7graph.engine.literals import shorten

__all__ = [
    "SAssign",
    "SBinary",
    "SCall",
    "SCallStmt",
    "SDirect",
    "SExpr",
    "SLiteral",
    "SName",
    "SOther",
    "SSetReset",
    "SStmt",
    "SUnary",
    "StSyntaxError",
    "parse_expression",
    "parse_statements",
    "shift",
]

GRAMMAR = Path(__file__).with_name("iec.lark")


@dataclass(frozen=True, slots=True)
class SLiteral:
    text: str
    line: int = 0
    col: int = 0


@dataclass(frozen=True, slots=True)
class SName:
    """A variable: ``parts`` of a dotted name (``STEP1.X``, ``TON3.Q``); ``index`` the
    literal indexes of an array element (``A[0, 1]`` → ("0", "1"); "?" for one that is
    not a literal)."""

    parts: tuple[str, ...]
    line: int = 0
    col: int = 0
    index: tuple[str, ...] = ()

    @property
    def indexed(self) -> bool:
        return bool(self.index)

    @property
    def text(self) -> str:
        return ".".join(self.parts)


@dataclass(frozen=True, slots=True)
class SDirect:
    """A directly represented variable ``%IX0.1``."""

    text: str
    line: int = 0
    col: int = 0


@dataclass(frozen=True, slots=True)
class SCall:
    """A function call in an expression; ``params`` are (formal name or "", value)."""

    name: str
    params: tuple[tuple[str, SExpr], ...]
    line: int = 0
    col: int = 0


@dataclass(frozen=True, slots=True)
class SUnary:
    op: str  # NOT or -
    operand: SExpr
    line: int = 0
    col: int = 0


@dataclass(frozen=True, slots=True)
class SBinary:
    op: str  # OR XOR AND = <> < > <= >= + - * / MOD **
    left: SExpr
    right: SExpr
    line: int = 0
    col: int = 0


SExpr = SLiteral | SName | SDirect | SCall | SUnary | SBinary


@dataclass(frozen=True, slots=True)
class SAssign:
    target: SName | SDirect
    expr: SExpr
    line: int = 0
    col: int = 0


@dataclass(frozen=True, slots=True)
class SSetReset:
    """A set or reset coil of a network: ``kind`` S sets ``target`` when ``expr`` holds, R
    resets it."""

    kind: str
    target: SName | SDirect
    expr: SExpr
    line: int = 0
    col: int = 0


@dataclass(frozen=True, slots=True)
class SCallStmt:
    """A function block call ``TON1(IN := x, PT := T#1S)`` (``outputs``: ``Q => y``)."""

    name: str
    inputs: tuple[tuple[str, SExpr], ...]
    outputs: tuple[tuple[str, SName | SDirect], ...]
    line: int = 0
    col: int = 0


@dataclass(frozen=True, slots=True)
class SOther:
    """A statement a GRAPH row cannot hold (``IF``, ``CASE``, ``FOR`` ...); ``writes``: the
    variables it assigns (the first name of each target, FB instances it calls included),
    ``end_line``/``end_col`` where it ends."""

    keyword: str
    line: int = 0
    col: int = 0
    writes: tuple[str, ...] = ()
    end_line: int = 0
    end_col: int = 0


SStmt = SAssign | SSetReset | SCallStmt | SOther


class StSyntaxError(S7Error):
    """Text that is not ST (or textual SFC); ``where`` is the place, in the file."""


def shift(line: int, col: int, origin: tuple[int, int]) -> tuple[int, int]:
    """A place in a text that starts at ``origin`` (line, col) of its file."""
    if line <= 1:
        return origin[0], origin[1] + max(col, 1) - 1
    return origin[0] + line - 1, col


def absolute(node: Any, origin: tuple[int, int]) -> Any:
    """``node`` (and its children) with places in the file, for text that starts at
    ``origin``; such nodes are then read with origin (1, 1)."""
    if isinstance(node, tuple):
        return tuple(absolute(x, origin) for x in node)
    if not dataclasses.is_dataclass(node) or isinstance(node, type):
        return node
    changes: dict[str, Any] = {}
    for f in dataclasses.fields(node):
        value = getattr(node, f.name)
        if f.name in ("line", "col"):
            continue
        changes[f.name] = absolute(value, origin)
    line, col = shift(getattr(node, "line", 1) or 1, getattr(node, "col", 1) or 1, origin)
    return dataclasses.replace(node, line=line, col=col, **changes)


@cache
def _parser(start: str) -> Lark:
    return lark_parser(
        GRAMMAR,
        parser="lalr",
        lexer="contextual",
        start=start,
        propagate_positions=True,
        maybe_placeholders=True,
    )


def _pos(x: Any) -> tuple[int, int]:
    if isinstance(x, Token):
        return x.line or 0, x.column or 0
    return getattr(x, "line", 0), getattr(x, "col", 0)


@v_args(meta=True)
class _Build(Transformer[Token, Any]):
    """Parse tree → ST nodes (places relative to the parsed text)."""

    def literal(self, meta: Any, ch: list[Token]) -> SLiteral:
        return SLiteral(str(ch[0]), *_pos(ch[0]))

    def direct(self, meta: Any, ch: list[Token]) -> SDirect:
        return SDirect(str(ch[0]).upper(), *_pos(ch[0]))

    def variable(self, meta: Any, ch: list[Any]) -> SName:
        names = tuple(str(c) for c in ch if isinstance(c, Token) and c.type == "NAME")
        index = tuple(
            c.text if isinstance(c, SLiteral) and c.text.isdigit() else "?"
            for c in ch
            if not (isinstance(c, Token) and c.type == "NAME")
        )
        return SName(names, *_pos(ch[0]), index=index)

    def func_call(self, meta: Any, ch: list[Any]) -> SCall:
        params = tuple(p for p in ch[1:] if p is not None)
        flat = tuple((p[1], p[2]) for p in params)
        return SCall(str(ch[0]).upper(), flat, *_pos(ch[0]))

    def in_param(self, meta: Any, ch: list[Any]) -> tuple[str, str, Any]:
        return ("in", str(ch[0]), ch[1])

    def out_param(self, meta: Any, ch: list[Any]) -> tuple[str, str, Any]:
        return ("out", str(ch[0]), ch[1])

    def positional_param(self, meta: Any, ch: list[Any]) -> tuple[str, str, Any]:
        return ("in", "", ch[0])

    def binary(self, meta: Any, ch: list[Any]) -> SBinary:
        op = str(ch[1]).upper()
        return SBinary("AND" if op == "&" else op, ch[0], ch[2], *_pos(ch[0]))

    def not_expr(self, meta: Any, ch: list[Any]) -> SUnary:
        return SUnary("NOT", ch[1], *_pos(ch[0]))

    def neg_expr(self, meta: Any, ch: list[Any]) -> SExpr:
        inner = ch[1]
        if isinstance(inner, SLiteral) and inner.text[:1].isdigit():
            return SLiteral("-" + inner.text, *_pos(ch[0]))
        return SUnary("-", inner, *_pos(ch[0]))

    def unary(self, meta: Any, ch: list[Any]) -> Any:  # unary plus
        return ch[1]

    def expression(self, meta: Any, ch: list[Any]) -> Any:
        return ch[0]

    def assignment(self, meta: Any, ch: list[Any]) -> SAssign:
        return SAssign(ch[0], ch[1], *_pos(ch[0]))

    def call_statement(self, meta: Any, ch: list[Any]) -> SCallStmt:
        params = [p for p in ch[1:] if p is not None]
        ins = tuple((n, v) for d, n, v in params if d == "in")
        outs = tuple((n, v) for d, n, v in params if d == "out")
        return SCallStmt(str(ch[0]), ins, outs, *_pos(ch[0]))

    def other_statement(self, meta: Any, ch: list[Any]) -> SOther:
        first = ch[0]
        tok = first if isinstance(first, Token) else None
        if tok is None and hasattr(first, "children"):
            tok = next((c for c in first.children if isinstance(c, Token)), None)
        word = str(tok).upper() if tok is not None else "statement"
        writes = tuple(dict.fromkeys(_writes(ch)))
        return SOther(word, meta.line, meta.column, writes, meta.end_line, meta.end_column)

    def empty_statement(self, meta: Any, ch: list[Any]) -> None:
        return None

    def statements(self, meta: Any, ch: list[Any]) -> list[SStmt]:
        return [c for c in ch if c is not None]


def _writes(node: Any) -> list[str]:
    """The variables the statements in ``node`` (a parse subtree, its statements already
    built) assign, in order: targets, ``=>`` outputs, called instances, FOR counters."""
    if isinstance(node, list | tuple):
        return [w for n in node for w in _writes(n)]
    if isinstance(node, SAssign | SSetReset):
        return [node.target.parts[0] if isinstance(node.target, SName) else node.target.text]
    if isinstance(node, SCallStmt):
        outs = [t.parts[0] if isinstance(t, SName) else t.text for _, t in node.outputs]
        return [node.name, *outs]
    if isinstance(node, SOther):
        return list(node.writes)
    if isinstance(node, Tree):
        out: list[str] = []
        if node.data == "for_statement":
            out += [str(c) for c in node.children if isinstance(c, Token) and c.type == "NAME"][:1]
        return out + _writes(node.children)
    return []


def _fail(exc: UnexpectedInput, file: str, origin: tuple[int, int], what: str) -> StSyntaxError:
    line, col = shift(exc.line or 1, exc.column or 1, origin)
    if isinstance(exc, UnexpectedToken):
        if exc.token.type == "$END":
            msg = f"{what} does not parse: it ends too early"
        else:
            msg = f"{what} does not parse: unexpected {shorten(str(exc.token))!r}"
    elif isinstance(exc, UnexpectedCharacters):
        msg = f"{what} does not parse: unexpected character {exc.char!r}"
    else:
        msg = f"{what} does not parse"
    return StSyntaxError(msg, SourceLocation(file, line, col))


_NEXT = re.compile(r"['\"]|//|\(\*|/\*|\{")
_STRING = {q: re.compile(rf"(?:[^{q}$\n]|\$.)*{q}") for q in "'\""}
_BLANK = re.compile(r"[^\n]")
_NEST = {"(*": re.compile(r"\(\*|\*\)"), "/*": re.compile(r"/\*|\*/")}


def _comment_end(text: str, start: int) -> tuple[int, bool] | None:
    """Where the comment opening at ``start`` ends, and whether it holds another (IEC
    61131-3 ed.3 nests them); None when it never ends."""
    opener = text[start : start + 2]
    depth, nested, pos = 0, False, start
    while (m := _NEST[opener].search(text, pos)) is not None:
        depth += 1 if m.group() == opener else -1
        nested = nested or depth > 1
        pos = m.end()
        if depth == 0:
            return pos, nested
    return None


def blank_comments(text: str, *, keep_flat: bool = False) -> str:
    """``text`` with its comments — ``(* *)`` and ``/* */`` nested as IEC 61131-3 ed.3
    allows, ``//`` — and its pragmas (``{attribute 'x'}``, which a reader may ignore) as
    blanks, lines and columns kept; strings untouched. ``keep_flat`` keeps the ``(* *)``
    and ``//`` comments that hold no other (S7-SCL reads them). What never ends stays."""
    out: list[str] = []
    done = pos = 0
    while (m := _NEXT.search(text, pos)) is not None:
        start, token = m.start(), m.group()
        if token in "'\"":  # a string: to its closing quote ($' escapes one)
            end = _STRING[token].match(text, m.end())
            pos = end.end() if end is not None else m.end()
            continue
        if token == "//":
            stop, keep = text.find("\n", start), keep_flat
            stop = len(text) if stop < 0 else stop
        elif token == "{":
            stop, keep = text.find("}", start) + 1, False
            if stop == 0:
                break
        else:
            ends = _comment_end(text, start)
            if ends is None:
                break
            stop, keep = ends[0], keep_flat and token == "(*" and not ends[1]
        if not keep:
            out += [text[done:start], _BLANK.sub(" ", text[start:stop])]
            done = stop
        pos = stop
    return "".join(out) + text[done:] if out else text


MAX_TREE_DEPTH = 200
"""Rules nested in one parsed text, at most (some 190 NOTs or 95 IFs inside each other):
the tree is turned into nodes recursively, two or three Python calls a level, and Python
stops at about 1,000."""


def _too_deep(tree: Tree[Any]) -> tuple[Tree[Any], Tree[Any] | None] | None:
    """The first node of ``tree``, in reading order, deeper than ``MAX_TREE_DEPTH``, and the
    chain of binary operators it is a left operand of (``a AND b AND c …`` nests one level a
    term; None when it is in none) — None when no node is that deep; found without
    recursion."""
    stack: list[tuple[Tree[Any], int, Tree[Any] | None]] = [(tree, 1, None)]
    while stack:
        node, depth, chain = stack.pop()
        if depth > MAX_TREE_DEPTH:
            return node, chain
        binary = node.data == "binary"
        for k in range(len(node.children) - 1, -1, -1):
            c = node.children[k]
            if isinstance(c, Tree):
                left = binary and k == 0 and c.data == "binary"
                stack.append((c, depth + 1, (chain or node) if left else None))
    return None


def _chain(top: Tree[Any]) -> tuple[int, str]:
    """The terms of the chain of binary operators starting at ``top`` (its left operands,
    one inside the other) and its operator (``AND``; "operators" when they differ)."""
    terms, ops, node = 1, set(), top
    while isinstance(node, Tree) and node.data == "binary":
        op = str(node.children[1]).upper()
        ops.add("AND" if op == "&" else op)
        terms, node = terms + 1, node.children[0]
    return terms, ops.pop() if len(ops) == 1 else "operators"


def parse_tree(text: str, start: str, file: str, origin: tuple[int, int], what: str) -> Any:
    """The lark tree of ``text`` from rule ``start`` (raises ``StSyntaxError``, also for a
    tree deeper than ``MAX_TREE_DEPTH``, at its first element past it); its comments and
    pragmas read as blanks (``blank_comments``)."""
    text = blank_comments(text)
    try:
        tree = _parser(start).parse(text)
    except UnexpectedInput as exc:
        raise _fail(exc, file, origin, what) from None
    found = _too_deep(tree) if isinstance(tree, Tree) else None
    if found is not None:
        deep, chain = found
        said = (
            f"{what} nests deeper than {MAX_TREE_DEPTH} levels here (an import reads at "
            f"most {MAX_TREE_DEPTH})"
        )
        if chain is not None:  # a long flat chain, not nesting: say so, where it starts
            terms, op = _chain(chain)
            said = (
                f"{what} has an expression of {terms:,} terms joined by {op} here: each is "
                f"a level, and an import reads at most {MAX_TREE_DEPTH} (split the expression)"
            )
            deep = chain
        line, col = shift(getattr(deep.meta, "line", 1), getattr(deep.meta, "column", 1), origin)
        raise StSyntaxError(said, SourceLocation(file, line, col))
    return tree


def build(tree: Any) -> Any:
    try:
        return _Build().transform(tree)
    except VisitError as exc:  # a bug in a transformer method, never bad input
        raise exc.orig_exc from None


def parse_expression(
    text: str, file: str = "<input>", origin: tuple[int, int] = (1, 1), what: str = "condition"
) -> SExpr:
    """An ST expression (places relative to ``text``)."""
    return build(parse_tree(text, "expression", file, origin, what))  # type: ignore[no-any-return]


def parse_statements(
    text: str, file: str = "<input>", origin: tuple[int, int] = (1, 1), what: str = "action"
) -> list[SStmt]:
    """ST statements (places relative to ``text``)."""
    return build(parse_tree(text, "statements", file, origin, what))  # type: ignore[no-any-return]
