"""Parse S7-SCL source text into the syntax tree of ``model`` (docs/scl.md, "Diagnostics").

lark's LALR parser reads the whole text without recursion; before the tree is turned into
the model (which recurses), an iterative walk refuses sources nested deeper than
``MAX_STATEMENT_NESTING`` control statements, ``MAX_EXPRESSION_NESTING`` operators or
calls, or ``MAX_TREE_DEPTH`` grammar levels in all (E204), so that no source can exhaust
the interpreter's stack. A number of 40 or more digits is refused before anything reads
it (E203). Each syntax error, up to ``recover.MAX_SYNTAX_ERRORS``, is reported at the
token where it was found, with what was expected there; a block left open names its
opening keyword's line.
"""

from __future__ import annotations

import re
from functools import cache
from pathlib import Path
from typing import Any

from lark import Lark, Token, Transformer, Tree, v_args
from lark.exceptions import UnexpectedCharacters, UnexpectedInput, UnexpectedToken, VisitError

from s7graph.engine.errors import SourceLocation
from s7graph.engine.grammars import lark_parser
from s7graph.engine.literals import shorten
from s7graph.steps.scl import model as m
from s7graph.steps.scl.comments import blank_comments
from s7graph.steps.scl.diagnostics import Diagnostic, Problem, SclError, error
from s7graph.steps.scl.recover import parse_all
from s7graph.steps.scl.tia import syntax_hint

GRAMMAR = Path(__file__).with_name("grammar.lark")
MAX_STATEMENT_NESTING = 16
"""Control statements (IF, CASE, FOR, WHILE, REPEAT) inside each other, at most."""
MAX_EXPRESSION_NESTING = 32
"""Operators, parentheses and calls inside each other in one expression, at most."""
MAX_TREE_DEPTH = 200
"""Grammar levels of the parse tree, at most (declarations included)."""

_STATEMENTS = frozenset({"if_stmt", "case_stmt", "for_stmt", "while_stmt", "repeat_stmt"})
_EXPRESSIONS = frozenset({"binary", "unary", "operand"})


@cache
def _parser() -> Lark:
    return lark_parser(
        GRAMMAR,
        parser="lalr",
        lexer="contextual",
        propagate_positions=True,
        maybe_placeholders=True,
    )


MAX_SOURCE = 1_000_000
"""The longest source compiled, in characters — as much as a download carries per source
(a 50 MB file would hold the parser for many minutes)."""


def parse_source(text: str, file: str = "<input>") -> m.Source:
    """Parse an SCL source; raise :class:`SclError` with a located diagnostic (E201–E205).
    A source over ``MAX_SOURCE`` characters is E204 before anything reads it."""
    if len(text) > MAX_SOURCE:
        said = f"the source has {len(text):,} characters; at most {MAX_SOURCE:,} are compiled"
        raise SclError(
            [error("E204", f"{said} (split it into several sources)", SourceLocation(file, 1, 1))]
        )
    text, unclosed = blank_comments(text, file)
    if unclosed is not None:
        raise SclError([unclosed])
    if long := _long_numbers(text, file):
        raise SclError(long)
    tree, syntax = parse_all(_parser(), text, lambda exc: _syntax(exc, file, text))
    if syntax:
        raise SclError(syntax)
    if deep := _too_deep(tree, file):
        raise SclError([deep])
    try:
        source = _Build(file).transform(tree)
    except VisitError as exc:
        if isinstance(exc.orig_exc, Problem):
            p = exc.orig_exc
            raise SclError([error(p.code, p.message, p.loc)]) from None
        raise
    assert isinstance(source, m.Source)
    return source


# ---------------------------------------------------------------- hostile text

_CODE_OR_NUMBER = re.compile(r"'(?:[^'$\n]|\$.)*'|\"(?:[^\"\n]|\"\")*\"|([0-9A-Fa-f_]{40,})")


def _long_numbers(text: str, file: str) -> list[Diagnostic]:
    """E203 at each run of 40 or more digits outside strings and comments."""
    out = []
    for found in _CODE_OR_NUMBER.finditer(text):
        run = found[1]
        if run is not None and sum(c.isdigit() for c in run) >= 40:
            out.append(
                error(
                    "E203",
                    f"a number of {len(run)} digits is beyond every type",
                    _place(file, text, found.start()),
                )
            )
            if len(out) >= 20:
                break
    return out


def _place(file: str, text: str, pos: int) -> SourceLocation:
    line = text.count("\n", 0, pos) + 1
    return SourceLocation(file, line, pos - (text.rfind("\n", 0, pos) + 1) + 1)


def _too_deep(tree: Tree[Any], file: str) -> Diagnostic | None:
    """E204 at the first construct nested beyond a limit (an iterative walk): a statement
    at its own place, an expression at the place where it starts."""
    todo: list[tuple[Tree[Any], int, int, int, Tree[Any] | None]] = [(tree, 0, 0, 0, None)]
    while todo:
        node, depth, stmts, exprs, outer = todo.pop()
        inside = outer  # the expression this node is part of, if any
        name = str(node.data)
        stmts += name in _STATEMENTS
        if name in _EXPRESSIONS:
            exprs += 1
            outer = outer or node
        elif name != "args":
            outer = None if name not in ("positional_arg", "named_arg", "index") else outer
        what, at = "", node
        if stmts > MAX_STATEMENT_NESTING:
            what = f"more than {MAX_STATEMENT_NESTING} control statements inside each other"
        elif exprs > MAX_EXPRESSION_NESTING:
            what = f"an expression nested more than {MAX_EXPRESSION_NESTING} levels deep"
            at = outer or node
        elif depth > MAX_TREE_DEPTH:
            what = f"a source nested more than {MAX_TREE_DEPTH} levels deep"
            if inside is not None:  # a long chain of operators: where its expression starts
                what = f"an expression deeper than {MAX_TREE_DEPTH} levels (split the chain)"
                at = inside
        if what:
            meta = at.meta
            line = meta.line if not meta.empty else 1
            col = meta.column if not meta.empty else 1
            return error("E204", what, SourceLocation(file, line, col))
        todo.extend(
            (c, depth + 1, stmts, exprs - _chained(node, c), outer)
            for c in node.children
            if isinstance(c, Tree)
        )
    return None


def _chained(node: Tree[Any], child: Tree[Any]) -> int:
    """1 when ``child`` is the left operand of ``node`` and the same operator (``a AND b AND
    c`` is a chain of one level, not nested: 40 contacts ANDed are no deeper than 2), else 0."""
    kids = node.children
    if node.data != "binary" or child.data != "binary" or not kids or kids[0] is not child:
        return 0
    op, inner = kids[1], child.children[1] if len(child.children) > 1 else None
    return int(isinstance(op, Token) and isinstance(inner, Token) and op.upper() == inner.upper())


# ---------------------------------------------------------------- syntax errors

_WORDS = {
    "NAME": "a name",
    "LITERAL": "a constant",
    "ADDRESS": "an address like M0.0 or MW10",
    "DBADDR": "an address like DB1.DBW0",
    "DBBIT": "a bit like .DX0.1",
    "BLOCKREF": "a block like FB17 or DB10",
    "CELL": "a timer or counter like T10",
    "DQSTRING": 'a quoted symbol like "Motor"',
    "SEMICOLON": "';'",
    "$END": "the end of the source",
}
_CLOSERS = {
    "IF": "END_IF",
    "CASE": "END_CASE",
    "FOR": "END_FOR",
    "WHILE": "END_WHILE",
    "REPEAT": "END_REPEAT",
    "STRUCT": "END_STRUCT",
    "VAR_KW": "END_VAR",
    "CONST": "END_CONST",
    "LABEL": "END_LABEL",
    "FB_KW": "END_FUNCTION_BLOCK",
    "FUNCTION": "END_FUNCTION",
    "ORGANIZATION_BLOCK": "END_ORGANIZATION_BLOCK",
    "DATA_BLOCK": "END_DATA_BLOCK",
    "TYPE": "END_TYPE",
}
"""The keyword that closes each construct the parser may hold open."""


def _describe(name: str) -> str:
    if name in _WORDS:
        return _WORDS[name]
    try:
        term = _parser().get_terminal(name)
    except KeyError:
        return name
    if term.pattern.type == "str":
        return f"'{term.pattern.value}'"
    return name.replace("_KW", "").replace("_", " ").lower()


def _expected(names: set[str]) -> str:
    words = sorted({_describe(n) for n in names})
    if len(words) > 6:
        words = [*words[:6], "…"]
    return " or ".join(words) if len(words) <= 2 else ", ".join(words[:-1]) + " or " + words[-1]


def _syntax(exc: UnexpectedInput, file: str, text: str) -> Diagnostic:
    """Phrase lark's error for an SCL programmer: what was found, what was expected."""
    loc = SourceLocation(file, max(exc.line or 1, 1), max(exc.column or 1, 1))
    if isinstance(exc, UnexpectedCharacters):
        pos = exc.pos_in_stream
        hint = syntax_hint(exc.char, None, text[pos + 1 :] if pos is not None else "")
        if hint is None and exc.char.isalpha():  # `ä`: a letter, but not one of a name
            hint = f"{exc.char!r} cannot be in a name: S7-SCL names have letters A-Z, digits and _"
        elif hint is None and exc.char.isdigit():  # `١٢`, `１２`: a digit, but not one of S7's
            hint = f"{exc.char!r} is not a digit of S7-SCL: numbers have the digits 0-9 only"
        return error("E201", hint or f"unexpected character {exc.char!r}", loc)
    if not isinstance(exc, UnexpectedToken):
        return error("E201", str(exc), loc)
    tok, expected = exc.token, set(exc.expected)
    history = list(getattr(exc, "token_history", None) or ())
    prev = history[-1] if history else None
    hint = syntax_hint(str(tok), None if prev is None else str(prev), "")
    if hint is not None and prev is not None:  # at the TIA Portal token itself
        return error(
            "E201", hint, SourceLocation(file, prev.line or loc.line, prev.column or loc.col)
        )
    if "SEMICOLON" in expected and prev is not None and str(prev).upper().startswith("END_"):
        return _missing_semicolon(file, prev, loc)
    if prev is not None and str(prev).upper() in _MISSPELT:
        where = SourceLocation(file, prev.line or loc.line, prev.column or loc.col)
        return error("E201", _MISSPELT[str(prev).upper()], where)
    closing = tok.type == "$END" or str(tok).upper().startswith("END_")
    follows = closing or str(tok).upper() in ("UNTIL", "ELSE", "ELSIF")
    if follows and tok.type != "$END" and "SEMICOLON" in expected and prev is not None:
        return _missing_semicolon(file, prev, loc)  # `x := x + 1 END_WHILE`: the ';' lacks
    opener = _open_construct(exc) if closing else None
    if opener is not None:
        keyword, line, closer = opener
        if tok.type == "$END":
            return error(
                "E202", f"missing {closer} for the {keyword} at line {line}", _end_of(file, text)
            )
        return error("E201", f"missing {closer} for the {keyword} at line {line}", loc)
    if tok.type == "$END":
        return error("E202", f"the source ends too early; expected {_expected(expected)}", loc)
    if "SEMICOLON" in expected and prev is not None and tok.line != prev.end_line:
        return _missing_semicolon(file, prev, loc)
    return error("E201", f"unexpected '{shorten(str(tok))}'; expected {_expected(expected)}", loc)


_MISSPELT = {
    "ELSEIF": "ELSEIF is no keyword: S7-SCL writes ELSIF",
    "ELSE_IF": "ELSE_IF is no keyword: S7-SCL writes ELSIF",
    "ENDIF": "ENDIF is no keyword: S7-SCL writes END_IF",
}
"""Words programmers bring from other languages, read as names, and what S7-SCL writes."""


def _missing_semicolon(file: str, prev: Token, loc: SourceLocation) -> Diagnostic:
    if prev.end_line is not None and prev.end_column is not None:
        loc = SourceLocation(file, prev.end_line, prev.end_column)
    return error("E201", f"missing ';' after '{shorten(str(prev))}'", loc)


def _end_of(file: str, text: str) -> SourceLocation:
    body = text.rstrip()
    return SourceLocation(file, body.count("\n") + 1, len(body) - (body.rfind("\n") + 1) + 1)


def _open_construct(exc: UnexpectedToken) -> tuple[str, int, str] | None:
    """The keyword, line and closing keyword of the innermost construct the parser holds
    open (its opening token is still on the parser's stack)."""
    stack = getattr(exc.state, "value_stack", None) or []
    for value in reversed(stack):
        if isinstance(value, Token) and value.type in _CLOSERS:
            return str(value).upper(), value.line or 0, _CLOSERS[value.type]
    return None


# ---------------------------------------------------------------- tree → model


def _loc(file: str, item: Token | Tree[Any] | Any) -> SourceLocation:
    if isinstance(item, Token):
        return SourceLocation(file, item.line or 1, item.column or 1)
    meta = getattr(item, "meta", None)
    if meta is None or meta.empty:
        return SourceLocation(file, 1, 1)
    return SourceLocation(file, meta.line, meta.column)


_ATTRIBUTE = re.compile(r"(\w+)\s*(?::|=)?\s*(.*)", re.S)


class _Build(Transformer[Token, Any]):
    """lark's tree → ``model`` nodes, with places (lark calls a method per rule)."""

    def __init__(self, file: str) -> None:
        super().__init__(visit_tokens=False)
        self.file = file

    def __default__(self, data: Any, children: list[Any], meta: Any) -> Any:
        raise AssertionError(f"no builder for {data}")  # pragma: no cover - grammar bug

    def _at(self, item: Any) -> SourceLocation:
        return _loc(self.file, item)

    # -- units
    def start(self, units: list[m.Unit]) -> m.Source:
        return m.Source(tuple(units), self.file)

    def _unit(self, kind: m.UnitKind, kw: Any, name: m.Base, rest: list[Any]) -> m.Unit:
        decls: tuple[m.Declaration, ...] = tuple(
            x for x in rest if isinstance(x, m.VarSection | m.ConstSection | m.LabelSection)
        )
        attributes = tuple(x for x in rest if type(x) is tuple)
        body: tuple[m.Stmt, ...] = next((x for x in rest if isinstance(x, _Stmts)), _Stmts())
        end = next((x for x in reversed(rest) if isinstance(x, Token)), kw)
        return m.Unit(
            kind,
            name.text,
            decls,
            tuple(body),
            attributes=attributes,
            loc=self._at(kw) if kw is not None else name.loc,
            end=self._at(end),
        )

    def fb_unit(self, c: list[Any]) -> m.Unit:
        return self._unit("FUNCTION_BLOCK", c[0], c[1], c[2:])

    def ob_unit(self, c: list[Any]) -> m.Unit:
        return self._unit("ORGANIZATION_BLOCK", None, c[0], c[1:])

    def fc_unit(self, c: list[Any]) -> m.Unit:
        unit = self._unit("FUNCTION", None, c[0], c[2:])
        ret = c[1]
        if isinstance(ret, m.NamedType) and ret.name.upper() == "VOID":
            ret = None
        return _replace(unit, ret=ret)

    def db_unit(self, c: list[Any]) -> m.Unit:
        return self._typed_unit("DATA_BLOCK", c)

    def type_unit(self, c: list[Any]) -> m.Unit:
        return self._typed_unit("TYPE", c)

    def _typed_unit(self, kind: m.UnitKind, c: list[Any]) -> m.Unit:
        name: m.Base = c[0]
        of = next(x for x in c[1:] if isinstance(x, m.TypeSpec))
        attrs = tuple(x for x in c[1:] if type(x) is tuple)
        body = tuple(x for x in c[1:] if isinstance(x, m.Assign))
        end = next((x for x in reversed(c) if isinstance(x, Token)), None)
        return m.Unit(
            kind,
            name.text,
            (),
            body,
            of=of,
            attributes=attrs,
            loc=name.loc,
            end=self._at(end) if end is not None else name.loc,
        )

    def block_name(self, c: list[Token]) -> m.Base:
        tok = c[0]
        text = str(tok)
        if tok.type == "DQSTRING":
            text = text[1:-1].replace('""', '"')
        elif tok.type == "BLOCKREF":
            text = "".join(text.split()).upper()
        return m.Base("name", text, self._at(tok))

    def attribute(self, c: list[Token]) -> tuple[str, str]:
        found = _ATTRIBUTE.fullmatch(str(c[0]).strip())
        assert found is not None
        return found[1].upper(), found[2].strip().strip("'")

    def db_assign(self, c: list[Any]) -> m.Assign:
        return m.Assign(c[0], c[1], c[0].loc)

    # -- declarations
    def var_section(self, c: list[Any]) -> m.VarSection:
        kind = str(c[0]).upper()
        decls = tuple(x for x in c[1:] if isinstance(x, m.VarDecl))
        return m.VarSection(kind, decls, self._at(c[0]))  # type: ignore[arg-type]

    def decl(self, c: list[Any]) -> m.VarDecl:
        names = tuple((str(t), self._at(t)) for t in c if isinstance(t, Token))
        spec = next(x for x in c if isinstance(x, m.TypeSpec))
        init = c[-1] if isinstance(c[-1], tuple) else None
        return m.VarDecl(names, spec, init, names[0][1])

    def init_list(self, c: list[Any]) -> tuple[Any, ...]:
        return tuple(c)

    def repeated(self, c: list[Any]) -> m.Repeated:
        return m.Repeated(m.Lit(str(c[0]), self._at(c[0])), c[1], self._at(c[0]))

    def const_section(self, c: list[Any]) -> m.ConstSection:
        return m.ConstSection(tuple(c), c[0][2] if c else SourceLocation(self.file))

    def const_item(self, c: list[Any]) -> tuple[str, m.Expr, SourceLocation]:
        return str(c[0]), c[1], self._at(c[0])

    def label_section(self, c: list[Token]) -> m.LabelSection:
        names = tuple((str(t), self._at(t)) for t in c if isinstance(t, Token))
        return m.LabelSection(names, names[0][1] if names else SourceLocation(self.file))

    def type_name(self, c: list[Token]) -> m.NamedType:
        text = str(c[0])
        if c[0].type == "DQSTRING":
            text = text[1:-1]
        elif c[0].type == "BLOCKREF":
            text = "".join(text.split()).upper()
        return m.NamedType(text, self._at(c[0]))

    def string_type(self, c: list[Any]) -> m.StringType:
        return m.StringType(c[0], c[0].loc if c[0] is not None else SourceLocation(self.file))

    def array_type(self, c: list[Any]) -> m.ArrayType:
        return m.ArrayType(tuple(c[:-1]), c[-1], c[0][0].loc)

    def bounds(self, c: list[Any]) -> tuple[m.Expr, m.Expr]:
        return c[0], c[1]

    def struct_type(self, c: list[m.VarDecl]) -> m.StructType:
        return m.StructType(tuple(c), c[0].loc if c else SourceLocation(self.file))

    # -- statements
    def stmts(self, c: list[Any]) -> _Stmts:
        return _Stmts(c)

    @v_args(meta=True)
    def empty(self, meta: Any, c: list[Any]) -> m.Empty:
        return m.Empty(self._at(_Meta(meta)))

    def labeled(self, c: list[Any]) -> m.Labeled:
        return m.Labeled(str(c[0]), c[1], self._at(c[0]))

    def assign(self, c: list[Any]) -> m.Assign:
        return m.Assign(c[0], c[1], c[0].loc)

    def call_stmt(self, c: list[m.Path]) -> m.CallStmt:
        return m.CallStmt(c[0], c[0].loc)

    def jump(self, c: list[Token]) -> m.Jump:
        kind = str(c[0]).upper()
        label = str(c[1]) if len(c) > 1 else ""
        return m.Jump(kind, label, self._at(c[0]))  # type: ignore[arg-type]

    def if_stmt(self, c: list[Any]) -> m.If:
        branches = [(c[0], tuple(c[1]))] + [b for b in c[2:-1]]
        orelse = tuple(c[-1]) if c[-1] is not None else None
        return m.If(tuple(branches), orelse, c[0].loc)

    def elsif(self, c: list[Any]) -> tuple[m.Expr, tuple[m.Stmt, ...]]:
        return c[0], tuple(c[1])

    def else_part(self, c: list[Any]) -> _Stmts:
        return c[0]  # type: ignore[no-any-return]

    def case_stmt(self, c: list[Any]) -> m.Case:
        arms = tuple(x for x in c[1:] if isinstance(x, m.CaseArm))
        orelse = tuple(c[-1]) if isinstance(c[-1], _Stmts) else None
        return m.Case(c[0], arms, orelse, c[0].loc)

    def case_head(self, c: list[Any]) -> m.CaseHead:
        first = m.Path(self._base("name", c[0]), (), self._at(c[0]))
        more: list[Any] = list(c[1])
        values: list[tuple[m.CaseValue, m.CaseValue]] = [(first, first)]
        if more and not isinstance(more[0], tuple):
            values = [(first, more.pop(0))]
        return m.CaseHead((*values, *more), c[2], self._at(c[0]))

    def case_tail(self, c: list[Any]) -> list[Any]:
        return c

    def case_name(self, c: list[Token]) -> m.Path:
        return m.Path(self._base("name", c[0]), (), self._at(c[0]))

    def case_arm(self, c: list[Any]) -> m.CaseArm:
        values = tuple(x for x in c[:-1])
        return m.CaseArm(values, tuple(c[-1]), values[0][0].loc)

    def case_value(self, c: list[Any]) -> tuple[m.CaseValue, m.CaseValue]:
        return (c[0], c[1] if c[1] is not None else c[0])

    def case_int(self, c: list[Any]) -> m.Lit:
        sign = "-" if c[0] is not None else ""
        tok = c[1]
        return m.Lit(sign + str(tok), self._at(c[0] if c[0] is not None else tok))

    def case_else(self, c: list[Any]) -> _Stmts:
        return c[-1]  # type: ignore[no-any-return]

    def for_stmt(self, c: list[Any]) -> m.For:
        return m.For(c[0], c[1], c[2], c[3], tuple(c[4]), c[0].loc)

    def while_stmt(self, c: list[Any]) -> m.While:
        return m.While(c[0], tuple(c[1]), c[0].loc)

    def repeat_stmt(self, c: list[Any]) -> m.Repeat:
        return m.Repeat(tuple(c[0]), c[1], c[1].loc)

    # -- expressions
    def literal(self, c: list[Token]) -> m.Lit:
        return m.Lit(str(c[0]), self._at(c[0]))

    def binary(self, c: list[Any]) -> m.Binary:
        op = str(c[1]).upper()
        return m.Binary("AND" if op == "&" else op, c[0], c[2], self._at(c[1]))

    def unary(self, c: list[Any]) -> m.Expr:
        op, operand = str(c[0]).upper(), c[1]
        if op == "-" and isinstance(operand, m.Lit) and _untyped_number(operand.text):
            return m.Lit("-" + operand.text, self._at(c[0]))
        return m.Unary(op, operand, self._at(c[0]))

    def operand(self, c: list[Any]) -> m.Path:
        base: m.Base = c[0]
        return m.Path(base, tuple(c[1:]), base.loc)

    def _base(self, kind: m.BaseKind, tok: Token) -> m.Base:
        text = str(tok)
        if kind == "symbol":
            text = text[1:-1].replace('""', '"')
        elif kind in ("block", "db_address", "address", "cell"):
            text = "".join(text.split()).upper().lstrip("%")
        return m.Base(kind, text, self._at(tok))

    def name_base(self, c: list[Token]) -> m.Base:
        return self._base("name", c[0])

    def address_base(self, c: list[Token]) -> m.Base:
        return self._base("address", c[0])

    def db_address_base(self, c: list[Token]) -> m.Base:
        return self._base("db_address", c[0])

    def block_base(self, c: list[Token]) -> m.Base:
        return self._base("block", c[0])

    def symbol_base(self, c: list[Token]) -> m.Base:
        return self._base("symbol", c[0])

    def cell_base(self, c: list[Token]) -> m.Base:
        return self._base("cell", c[0])

    def member(self, c: list[Token]) -> m.Member:
        return m.Member(str(c[0]), self._at(c[0]))

    def bit_member(self, c: list[Token]) -> m.Member:
        tok = c[0]
        at = SourceLocation(self.file, tok.line or 1, (tok.column or 1) + 1)  # after the '.'
        return m.Member(str(tok)[1:].upper(), at)

    def block_member(self, c: list[Token]) -> m.Member:
        return m.Member("".join(str(c[0]).split()).upper(), self._at(c[0]), block=True)

    def index(self, c: list[Any]) -> m.Index:
        return m.Index(tuple(c), c[0].loc)

    def args(self, c: list[Any]) -> m.Args:
        items = tuple(x for x in c if x is not None)
        return m.Args(items, items[0].loc if items else SourceLocation(self.file))

    def named_arg(self, c: list[Any]) -> m.Arg:
        return m.Arg(str(c[0]), c[1], self._at(c[0]))

    def positional_arg(self, c: list[Any]) -> m.Arg:
        return m.Arg("", c[0], c[0].loc)


class _Meta:
    """A rule's place, for ``_loc`` (lark hands it to ``v_args(meta=True)`` methods)."""

    def __init__(self, meta: Any) -> None:
        self.meta = meta


class _Stmts(tuple):  # type: ignore[type-arg]
    """A statement list while building (told apart from other tuples)."""

    __slots__ = ()


def _untyped_number(text: str) -> bool:
    return text[:1].isdigit() and "#" not in text


def _replace(unit: m.Unit, **changes: Any) -> m.Unit:
    from dataclasses import replace

    return replace(unit, **changes)
