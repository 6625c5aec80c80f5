"""Expressions → Python source, with S7-SCL's type rules (docs/scl.md, "Expressions";
Siemens' S7-SCL V5.3 for S7-300/400, "Expressions"; the guide ch. 13, the tables of
arithmetic, logic and comparison).

Arithmetic: ``**`` of numbers is REAL; ``* / + -`` of numbers take the wider operand type
(INT < DINT < REAL); ``DIV`` and ``MOD`` take integers; TIME ± TIME, TIME * / DIV ANY_INT,
TOD ± TIME, DT ± TIME, DATE − DATE, TOD − TOD, DT − DT as the S7-SCL table. Logic ``AND &
XOR OR NOT`` on BOOL, BYTE, WORD, DWORD. Comparisons of numbers, of bit strings (``=`` and
``<>`` only), of CHAR and STRING, of times and dates; the result is BOOL. Every operand is
evaluated — no short circuit, as the CPU's code evaluates them.
"""

from __future__ import annotations

from s7graph.engine.errors import SourceLocation
from s7graph.steps.scl import model as m
from s7graph.steps.scl import types as ty
from s7graph.steps.scl.consts import Constant, adapt, literal
from s7graph.steps.scl.diagnostics import Problem
from s7graph.steps.scl.gen import Block, Place, Target, X

COMPARE = {"=": "==", "<>": "!=", "<": "<", ">": ">", "<=": "<=", ">=": ">="}
_LOGIC = {"AND": "&", "OR": "|", "XOR": "^"}
_BITS = {"INT": 16, "DINT": 32, "TIME": 32}
_ORDERED = frozenset({"CHAR", "STRING", "TIME", "S5TIME", "DATE", "TIME_OF_DAY"})
_ORDERED |= {"DATE_AND_TIME", "INT", "DINT", "REAL"}
ERROR = X(ty.ERROR, "0")


def checked(src: str, kind: str) -> str:
    """``src`` (an INT, DINT or TIME result) wrapped to its range, OK := FALSE if it left it."""
    bits = _BITS[kind]
    lo, hi = -(1 << (bits - 1)), (1 << (bits - 1)) - 1
    return f"(_v if {lo} <= (_v := {src}) <= {hi} else _ovf(_ok, _v, {bits}))"


class Exprs:
    """The expression translator of one block."""

    def __init__(self, b: Block) -> None:
        self.b = b

    def expr(self, e: m.Expr) -> X:
        if isinstance(e, m.Lit):
            c = literal(e)
            return X(c.type, self.b.literal_src(c.value), c)
        if isinstance(e, m.Path):
            got = self.b.places.resolve(e)
            if isinstance(got, Target):
                return self.b.calls.value(got)
            if isinstance(got, Place):
                return X(got.type, got.get)
            return got
        if isinstance(e, m.Unary):
            return self.unary(e)
        return self.binary(e)

    def cond(self, e: m.Expr) -> str:
        """A condition: an expression that must be a BOOL (E222)."""
        x = self.expr(e)
        if x.type.kind not in ("BOOL", "ERROR"):
            raise Problem("E222", f"a condition is a BOOL, not {x.type}", e.loc)
        return x.src

    def convert(self, x: X, t: ty.SclType, loc: SourceLocation, what: str) -> str:
        """Python source of ``x`` as a value of ``t`` — implicit conversions only (E220)."""
        if t.kind in ("ERROR", "ANY") or x.type.kind == "ERROR":
            return x.src
        if x.const is not None:
            value = adapt(x.const, t)
            if value is not None:
                if t.kind == "STRING" and isinstance(value, str) and len(value) > t.length:
                    raise Problem("E220", f"'{value}' is longer than {t}", loc)
                return self.b.literal_src(value)
        if not ty.widens(x.type, t):
            a = "an" if str(x.type)[:1] in "AEIOU" else "a"
            raise Problem("E220", f"cannot {what} {a} {x.type} to {t}", loc)
        src, k = x.src, x.type.kind
        if t.kind == "STRING" and (k == "CHAR" or x.type.length > t.length):
            return f"_fit(_ok, {src}, {t.length})" if k != "CHAR" else src
        if t.aggregate:  # member names may differ: then they are the target's
            return f"_clone({src})" if x.type == t else f"_recast({src}, {self.b.const(t)})"
        if k == "BOOL" and t.kind != "BOOL":
            return f"int({src})"
        if t.kind == "REAL" and k == "INT":
            return f"float({src})"
        if t.kind == "REAL" and k == "DINT":
            return f"_f32({src})"
        return src

    # ---- operators

    def unary(self, e: m.Unary) -> X:
        x = self.expr(e.operand)
        k = x.type.kind
        if k == "ERROR":
            return ERROR
        if e.op == "NOT":
            if k == "BOOL":
                return X(ty.BOOL, f"(not {x.src})")
            if k in ty.MASK:
                return X(x.type, f"({x.src} ^ {ty.MASK[k]})")
        elif e.op == "+" and (ty.is_num(x.type) or k == "TIME"):
            return x
        elif e.op == "-":
            if k in _BITS:
                return X(x.type, checked(f"-({x.src})", k))
            if k == "REAL":
                return X(x.type, f"(-{x.src})")
        raise Problem("E221", f"{e.op} is not defined for {x.type}", e.loc)

    def binary(self, e: m.Binary) -> X:
        left, right = self.expr(e.left), self.expr(e.right)
        if left.type.kind == "ERROR" or right.type.kind == "ERROR":
            return ERROR
        left, right = self._in_context(e.op, left, right), self._in_context(e.op, right, left)
        if e.op in _LOGIC:
            return self._logic(e, left, right)
        if e.op in COMPARE:
            return self._compare(e, left, right)
        return self._arith(e, left, right)

    def _in_context(self, op: str, x: X, other: X) -> X:
        """An untyped number beside a typed operand takes that operand's type where its value
        fits: an INT or DINT (a DINT when an INT is too small) in arithmetic and comparisons
        (``i + 16#1``, ``i = 2#101``), a BYTE, WORD or DWORD in logic (``w AND 5``) — S7-SCL
        takes a constant's type from its context. A bit string compared with a decimal number
        stays E221 (the guide's ``MW0 = 23``)."""
        c = x.const
        if c is None or not c.untyped or (other.const is not None and other.const.untyped):
            return x
        t = other.type
        if op not in _LOGIC and ty.is_int(t) and not ty.literal_fits(t, c.value):
            t = ty.DINT  # 16#FFFF beside an INT: a DINT, as 65535 would be
        wanted = t.kind in ty.MASK if op in _LOGIC else ty.is_int(t)
        if not wanted or t == x.type or not ty.literal_fits(t, c.value):
            return x
        return X(t, self.b.literal_src(c.value), Constant(t, c.value))

    def _logic(self, e: m.Binary, a: X, b: X) -> X:
        if not (ty.is_bits(a.type) and ty.is_bits(b.type)):
            raise Problem("E221", f"{a.type} {e.op} {b.type}: {e.op} takes bit strings", e.loc)
        t = ty.common(a.type, b.type)
        assert t is not None
        x, y = self.convert(a, t, e.loc, "use"), self.convert(b, t, e.loc, "use")
        return X(t, f"({x} {_LOGIC[e.op]} {y})")

    def _compare(self, e: m.Binary, a: X, b: X) -> X:
        t = ty.common(a.type, b.type)
        if t is None or t.aggregate or t.kind in ("TIMER", "COUNTER", "BLOCK_DB", "FB", "ANY"):
            raise Problem("E221", f"cannot compare {a.type} with {b.type}", e.loc)
        if e.op not in ("=", "<>") and t.kind not in _ORDERED:
            raise Problem("E221", f"{t} values compare only with = and <>", e.loc)
        x, y = self.convert(a, t, e.loc, "compare"), self.convert(b, t, e.loc, "compare")
        return X(ty.BOOL, f"({x} {COMPARE[e.op]} {y})")

    def _arith(self, e: m.Binary, a: X, b: X) -> X:
        op = e.op
        if ty.is_num(a.type) and ty.is_num(b.type):
            return self._numeric(e, a, b)
        timed = self._timed(op, a, b)
        if timed is not None:
            return timed
        raise Problem("E221", f"{a.type} {op} {b.type} is not defined", e.loc)

    def _numeric(self, e: m.Binary, a: X, b: X) -> X:
        op = e.op
        if op == "**":
            x, y = self.convert(a, ty.REAL, e.loc, "use"), self.convert(b, ty.REAL, e.loc, "use")
            return X(ty.REAL, f"_pow(_ok, {x}, {y})")
        t = ty.common(a.type, b.type)
        assert t is not None
        if op in ("DIV", "MOD") and t.kind == "REAL":
            raise Problem("E221", f"{op} takes INT or DINT, not REAL", e.loc)
        x, y = self.convert(a, t, e.loc, "use"), self.convert(b, t, e.loc, "use")
        if t.kind == "REAL":
            if op == "/":
                return X(t, f"_rdiv(_ok, {x}, {y})")
            return X(t, f"_r32(_ok, {x} {op} {y})")
        d = b.const.value if b.const is not None else None
        return X(t, self._integer(op, x, y, t.kind, d if isinstance(d, int) else None))

    def _integer(self, op: str, x: str, y: str, kind: str, divisor: int | None = None) -> str:
        if divisor is not None and divisor >= 2 and op in ("/", "DIV", "MOD"):
            # by a constant of 2 or more: no division by zero, no overflow — inline, toward
            # zero (the remainder with the dividend's sign)
            how = "//" if op != "MOD" else "%"
            return f"(_v {how} {divisor} if (_v := {x}) >= 0 else -(-_v {how} {divisor}))"
        if op in ("/", "DIV"):
            return f"_idiv(_ok, {x}, {y}, {_BITS[kind]})"
        if op == "MOD":
            return f"_imod(_ok, {x}, {y})"
        return checked(f"{x} {op} {y}", kind)

    def _timed(self, op: str, a: X, b: X) -> X | None:
        """The time and date rows of the arithmetic table (None: not one of them)."""
        ka, kb = a.type.kind, b.type.kind
        if ka == "TIME" and kb == "TIME" and op in ("+", "-"):
            return X(ty.TIME, checked(f"{a.src} {op} {b.src}", "TIME"))
        if ka == "TIME" and ty.is_int(b.type) and op in ("*", "/", "DIV"):
            return X(ty.TIME, self._integer(op, a.src, b.src, "TIME"))
        if ty.is_int(a.type) and kb == "TIME" and op == "*":
            return X(ty.TIME, checked(f"{a.src} * {b.src}", "TIME"))
        if ka == "TIME_OF_DAY" and kb == "TIME" and op in ("+", "-"):
            return X(ty.TOD, f"_tod({a.src} {op} {b.src})")
        if ka == "DATE_AND_TIME" and kb == "TIME" and op in ("+", "-"):
            sign = "" if op == "+" else "-"
            return X(ty.DT, f"_dt_add(_ok, {a.src}, {sign}{b.src})")
        if op == "-" and ka == kb and ka in ("DATE", "DATE_AND_TIME"):
            return X(ty.TIME, f"_dt_diff(_ok, {a.src}, {b.src})")
        if op == "-" and ka == kb == "TIME_OF_DAY":
            return X(ty.TIME, f"({a.src} - {b.src})")
        return None
