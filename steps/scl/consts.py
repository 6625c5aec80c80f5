"""Literals and constant expressions: the CONST section, array bounds, string lengths and
initial values are evaluated once, by the compiler (docs/scl.md, "Literals and constants").

A literal is read by ``engine.literals.parse_literal`` (typed forms ``INT#5``, ``T#1S``,
``W#16#FF``, ``DT#…`` and the rest); ``BYTE#'a'`` and ``B#'a'`` are the character's code
as a BYTE. A number written without a type prefix is *untyped*:
it becomes whatever type it is assigned or passed to when its value fits there
(``types.literal_fits``).
"""

from __future__ import annotations

import math
import operator
import re
from collections.abc import Callable
from dataclasses import dataclass, field

from s7graph.engine.datatypes import real32
from s7graph.engine.errors import LiteralError, SourceLocation
from s7graph.engine.literals import parse_literal, shorten
from s7graph.steps.scl import model as m
from s7graph.steps.scl import types as ty
from s7graph.steps.scl.diagnostics import Problem

_LITERAL_TYPE = {"TIME_OF_DAY": ty.TOD, "DATE_AND_TIME": ty.DT}
_BYTE_CHAR = re.compile(r"(?:BYTE|B)#('.*')", re.I | re.S)
"""``BYTE#'a'``: a character's code as a BYTE (S7-SCL V5.3, "Notation for Constants")."""


@dataclass(frozen=True, slots=True)
class Constant:
    """A value known to the compiler; ``untyped``: a number written without a type."""

    type: ty.SclType
    value: object
    untyped: bool = False


def literal(lit: m.Lit) -> Constant:
    """The type and value of a literal (E203 when it does not parse or fit)."""
    text = lit.text
    byte_char = _BYTE_CHAR.fullmatch(text)
    try:
        tname, value = parse_literal(f"CHAR#{byte_char[1]}" if byte_char else text)
    except LiteralError as exc:
        message = exc.message
        if byte_char:
            message = message.replace(f"CHAR#{byte_char[1]}", text)
            message = message.replace("a CHAR is one character", "it holds one character")
        raise Problem("E203", message, lit.loc) from None
    if byte_char:
        assert isinstance(value, str)
        if ord(value) > 0xFF:
            raise Problem("E203", f"{text}: a BYTE holds a character of code 0..255", lit.loc)
        return Constant(ty.BYTE, ord(value))
    body = text.lstrip("+-")
    untyped = body[:1].isdigit()
    if tname == "STRING":
        assert isinstance(value, str)
        if bad := [c for c in value if ord(c) > 0xFF]:
            why = f"{bad[0]!s} is not a character of S7's code page (latin-1); write it as $hh"
            raise Problem("E203", f"{shorten(text)}: {why}", lit.loc)
        return Constant(ty.string(max(len(value), 1)), value, untyped=len(value) == 1)
    if tname == "REAL":
        assert isinstance(value, float)
        value = real32(value)
    t = _LITERAL_TYPE.get(tname) or ty.by_name(tname) or ty.ERROR
    return Constant(t, value, untyped)


def adapt(c: Constant, t: ty.SclType) -> object | None:
    """``c``'s value as a constant of type ``t``, or None if it cannot be one."""
    if c.type == t or (c.type.kind == t.kind and t.kind == "STRING"):
        return c.value
    if c.untyped and c.type.kind == "STRING" and t.kind == "CHAR":
        return c.value
    if c.untyped and ty.literal_fits(t, c.value):
        if t.kind == "BOOL":
            return bool(c.value)
        return real32(float(c.value)) if t.kind == "REAL" else c.value  # type: ignore[arg-type]
    if c.type.kind == "TIME" and t.kind == "S5TIME" and isinstance(c.value, int):
        return c.value if 0 <= c.value <= 9_990_000 else None
    if ty.widens(c.type, t) and not t.aggregate and t.kind != "ANY":
        v = c.value
        if t.kind == "REAL" and isinstance(v, int):
            return real32(float(v))
        if t.kind in ty.MASK and isinstance(v, bool):
            return int(v)
        return v
    return None


_ARITH: dict[str, Callable[[int, int], int]] = {
    "+": operator.add,
    "-": operator.sub,
    "*": operator.mul,
}


@dataclass
class Consts:
    """The constants of one block (CONST section), by upper-case name."""

    values: dict[str, tuple[ty.SclType, object]] = field(default_factory=dict)
    untyped: set[str] = field(default_factory=set)

    def define(self, name: str, expr: m.Expr, loc: SourceLocation) -> None:
        c = self.evaluate(expr)
        self.values[name.upper()] = (c.type, c.value)
        if c.untyped:
            self.untyped.add(name.upper())

    def integer(self, expr: m.Expr) -> int:
        """An integer constant expression (array bounds, string lengths)."""
        c = self.evaluate(expr)
        if not isinstance(c.value, int) or isinstance(c.value, bool):
            raise Problem("E217", "an integer constant is needed here", expr.loc)
        return c.value

    def evaluate(self, expr: m.Expr) -> Constant:
        """A constant expression of literals, constants, ``+ - * / DIV MOD`` and parentheses."""
        if isinstance(expr, m.Lit):
            return literal(expr)
        if isinstance(expr, m.Path):
            key = expr.base.text.upper()
            if expr.base.kind == "name" and not expr.selectors and key in self.values:
                t, v = self.values[key]
                return Constant(t, v, key in self.untyped)
            raise Problem("E217", f"{expr.base.text!r} is not a constant", expr.loc)
        if isinstance(expr, m.Unary) and expr.op in ("-", "+"):
            c = self.evaluate(expr.operand)
            if isinstance(c.value, int | float) and not isinstance(c.value, bool):
                return Constant(c.type, -c.value if expr.op == "-" else c.value, c.untyped)
        if isinstance(expr, m.Binary):
            return self._binary(expr)
        raise Problem("E217", "not a constant expression", expr.loc)

    def _binary(self, expr: m.Binary) -> Constant:
        a, b = self.evaluate(expr.left), self.evaluate(expr.right)
        x, y = a.value, b.value
        if not all(isinstance(v, int | float) and not isinstance(v, bool) for v in (x, y)):
            raise Problem("E217", f"{expr.op} of non-numbers in a constant", expr.loc)
        assert isinstance(x, int | float) and isinstance(y, int | float)
        untyped = a.untyped and b.untyped
        t = ty.common(a.type, b.type) or ty.DINT
        if isinstance(x, int) and isinstance(y, int):
            if expr.op in _ARITH:
                n = _ARITH[expr.op](x, y)
            elif expr.op in ("/", "DIV", "MOD") and y != 0:
                q = abs(x) // abs(y) * (1 if (x >= 0) == (y >= 0) else -1)
                n = q if expr.op != "MOD" else x - q * y
            elif expr.op in ("/", "DIV", "MOD"):
                raise Problem("E217", f"{expr.op} by zero in a constant expression", expr.loc)
            else:
                raise Problem("E217", f"{expr.op} in a constant expression", expr.loc)
            if not -(2**31) <= n < 2**31:
                raise Problem("E217", f"constant {n} is outside DINT", expr.loc)
            t = ty.INT if -32768 <= n <= 32767 and t.kind == "INT" else t
            if untyped:
                t = ty.INT if -32768 <= n <= 32767 else ty.DINT
            return Constant(t, n, untyped)
        if expr.op in ("+", "-", "*", "/") and not (expr.op == "/" and y == 0):
            ops = {"+": operator.add, "-": operator.sub, "*": operator.mul}
            r = float(ops[expr.op](x, y) if expr.op != "/" else x / y)
            if math.isinf(v := real32(r)):  # as a DINT constant beyond DINT, above
                raise Problem("E217", f"constant {r:g} is outside REAL (±3.402823e+38)", expr.loc)
            return Constant(ty.REAL, v, untyped)
        if expr.op == "/" and y == 0:
            raise Problem("E217", "/ by zero in a constant expression", expr.loc)
        raise Problem("E217", f"{expr.op} in a constant expression", expr.loc)


def initial(
    consts: Consts, t: ty.SclType, items: tuple[m.InitItem, ...], loc: SourceLocation
) -> object:
    """An initial value for type ``t`` from ``:= …`` (an ARRAY takes a list with ``n(v)``
    repetitions; elements left out stay zero). E216 if a value does not fit."""
    if t.kind == "ARRAY":
        assert t.element is not None
        values = _flatten(consts, t.element, items)
        if len(values) > t.count:
            raise Problem("E216", f"{len(values)} initial values for {t.count} elements", loc)
        rest = ty.zero_factory(t)()
        assert isinstance(rest, list)
        rest[: len(values)] = values
        return rest
    if t.aggregate or len(items) != 1 or isinstance(items[0], m.Repeated):
        raise Problem("E216", f"an initial value of {t} is one constant", loc)
    return _one(consts, t, items[0])


def _one(consts: Consts, t: ty.SclType, expr: m.Expr) -> object:
    c = consts.evaluate(expr)
    value = adapt(c, t)
    if value is None:
        raise Problem("E216", f"{c.type} {c.value!r} is not a value of {t}", expr.loc)
    if t.kind == "STRING" and isinstance(value, str) and len(value) > t.length:
        raise Problem("E216", f"{len(value)} characters do not fit {t}", expr.loc)
    return value


def _flatten(consts: Consts, elem: ty.SclType, items: tuple[m.InitItem, ...]) -> list[object]:
    out: list[object] = []
    for item in items:
        if isinstance(item, m.Repeated):
            n = consts.integer(item.count)
            if not 0 <= n <= 65536:
                raise Problem("E216", f"repetition {n} out of range", item.loc)
            out.extend(_flatten(consts, elem, item.items) * n)
        else:
            out.append(_one(consts, elem, item))
    return out
