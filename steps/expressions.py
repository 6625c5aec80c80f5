"""Arithmetic of action rows and comparisons of conditions, compiled to Python source
(docs/semantics.md, "Actions" last row, STEP7 comprehensive guide vol. 2, ch. 14, docs/semantics.md,
"Decisions").

Operators ``+ - * /`` on INT DINT REAL (TIME counts as DINT ms), ``MOD`` (DINT),
``AND OR XOR`` on WORD/DWORD, ``SHL SHR SSR ROL ROR``; the functions of ``FUNCTIONS``.
INT/DINT results that leave their range, and divisions by zero, do not raise: they set the
overflow status (``st.ov``, ``st.ov_count``, one line in ``st.diag``) and the result wraps
as on the CPU (``/`` by zero gives 0); ``ROUND``/``TRUNC`` of a REAL without a whole
value in DINT (NaN, infinite, too large) give 0 and set it too.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import replace
from typing import Any

from s7graph.engine.datatypes import real32 as _single
from s7graph.engine.datatypes import string_chars
from s7graph.engine.errors import TypeMismatch
from s7graph.steps.operands import CELL_VALUE_TYPE, CELLS, CodeGen, Ref
from s7graph.steps.syntax import (
    Binary,
    Const,
    Expr,
    FuncCall,
    Operand,
    StepAttr,
    TransAttr,
    Unary,
)

Resolve = Callable[[Operand], Ref]
StepIndex = Callable[[int, Any], int]

INTS = frozenset({"INT", "DINT", "TIME", "S5TIME", "TIME_OF_DAY", "TOD"})
BITS = frozenset({"BYTE", "WORD", "DWORD", "CHAR"})
NUMERIC = INTS | BITS | {"REAL"}
_COMPLEMENT = frozenset({"INT", "DINT"})
"""The number types whose NOT is their one's complement, as the type check has it
(``sequencer.checks.types``: NOT of INT is INT, of DINT is DINT)."""
RANGE = {"INT": (-32768, 32767), "DINT": (-(2**31), 2**31 - 1), "TIME": (-(2**31), 2**31 - 1)}
MASK = {"BYTE": 0xFF, "CHAR": 0xFF, "WORD": 0xFFFF, "DWORD": 0xFFFFFFFF}
LOGIC = frozenset({"AND", "OR", "XOR"})
_SHIFTS = frozenset({"SHL", "SHR", "SSR", "ROL", "ROR"})
COMPARE = {"=": "==", "<>": "!=", "<": "<", ">": ">", "<=": "<=", ">=": ">="}

# name -> (result type or None = same as argument, Python helper name)
FUNCTIONS: dict[str, tuple[str | None, str]] = {
    "BCD_TO_NUM": (None, "_bcd_to_num"),
    "NUM_TO_BCD": (None, "_num_to_bcd"),
    "INT_TO_DINT": ("DINT", "int"),
    "DINT_TO_REAL": ("REAL", "float"),
    "ROUND": ("DINT", "_round"),
    "TRUNC": ("DINT", "_trunc"),
    "NEGR": ("REAL", "_negr"),
    "ABS": ("REAL", "_abs"),
    "SQR": ("REAL", "_sqr"),
    "SQRT": ("REAL", "_sqrt"),
    "LN": ("REAL", "_ln"),
    "EXP": ("REAL", "_exp"),
    "SIN": ("REAL", "_sin"),
    "ASIN": ("REAL", "_asin"),
    "COS": ("REAL", "_cos"),
    "ACOS": ("REAL", "_acos"),
    "TAN": ("REAL", "_tan"),
    "ATAN": ("REAL", "_atan"),
    "NEG": (None, "_neg"),
    "NOT": (None, "_not"),
    "SWAP": (None, "_swap"),
    "RLDA": ("DWORD", "_rlda"),
    "RRDA": ("DWORD", "_rrda"),
}


# The argument types each function takes, and what it gives for each (the type check reads
# it, ``sequencer.checks.types``; an untyped address argument is read as the first of them
# its width allows): STEP7 comprehensive guide vol. 2, ch. 14.
ARGUMENTS: dict[str, dict[str, str]] = {
    "BCD_TO_NUM": {"WORD": "INT", "DWORD": "DINT"},
    "NUM_TO_BCD": {"INT": "WORD", "DINT": "DWORD"},
    "INT_TO_DINT": {"INT": "DINT"},
    "DINT_TO_REAL": {"DINT": "REAL"},
    "ROUND": {"REAL": "DINT"},
    "TRUNC": {"REAL": "DINT"},
    "NEG": {"INT": "INT", "DINT": "DINT", "REAL": "REAL"},
    "NOT": {"INT": "INT", "DINT": "DINT", "WORD": "WORD", "DWORD": "DWORD"},
    "SWAP": {"WORD": "WORD", "DWORD": "DWORD"},
    "RLDA": {"DWORD": "DWORD"},
    "RRDA": {"DWORD": "DWORD"},
    **{
        f: {"REAL": "REAL"}
        for f in (
            "NEGR",
            "ABS",
            "SQR",
            "SQRT",
            "LN",
            "EXP",
            "SIN",
            "ASIN",
            "COS",
            "ACOS",
            "TAN",
            "ATAN",
        )
    },
}
_DOUBLE = ("DINT", "REAL", "TIME", "DWORD")
"""What an untyped double-word address may stand for, in the order the type check tries."""


def settled(ref: Ref, context: str) -> Ref:
    """``ref`` read or written beside a value of type ``context``: an untyped double word
    (``MD20``, ``ref.flex``) beside a REAL holds a REAL's bits (``MD20 > 1.5`` compares as
    ``L MD20`` / ``>R`` does), else ``ref`` as it is."""
    if ref.flex and context == "REAL" and ref.type == "DINT":
        return replace(ref, type="REAL")
    return ref


def _beside(e: Expr, context: str, resolve: Resolve) -> Ref | None:
    """The operand ``e`` is, settled by ``context`` (``settled``); None when ``e`` is no
    operand that a value of ``context`` settles."""
    if not isinstance(e, Operand):
        return None
    ref = resolve(e)
    new = settled(ref, context)
    return None if new is ref else new


def _value_beside(
    e: Expr,
    context: str,
    g: CodeGen,
    resolve: Resolve,
    sidx: StepIndex,
    tidx: StepIndex,
    number: bool,
) -> str:
    """``gen_value`` of ``e`` standing beside a value of type ``context``: an untyped double
    word beside a REAL read as one."""
    new = _beside(e, context, resolve)
    return g.read_number(new) if new is not None else gen_value(e, g, resolve, sidx, tidx, number)


def expr_type(e: Expr, resolve: Resolve, number: bool = False) -> str:
    """The S7 type of an expression (for code selection and the same-type check);
    ``number``: where a number is expected (a timer or counter cell is its INT value)."""
    if isinstance(e, Const):
        return e.type
    if isinstance(e, Operand):
        ref = resolve(e)
        return CELL_VALUE_TYPE if number and ref.kind in CELLS else ref.type
    if isinstance(e, StepAttr):
        return "BOOL" if e.attr == "X" else "TIME"
    if isinstance(e, TransAttr):
        return "BOOL"
    if isinstance(e, Unary):
        if e.op == "NOT":  # of an INT or DINT: its one's complement (INVI, INVD), else BOOL
            t = expr_type(e.operand, resolve)  # a timer or counter: its status bit
            return t if t in _COMPLEMENT else "BOOL"
        return expr_type(e.operand, resolve, True)
    if isinstance(e, FuncCall):
        res, _ = FUNCTIONS.get(e.name.upper(), (None, ""))
        return res or (expr_type(e.args[0], resolve, True) if e.args else "DINT")
    if isinstance(e, Binary):
        if e.op in COMPARE:
            return "BOOL"
        arith = e.op.upper() not in LOGIC
        lt, rt = expr_type(e.left, resolve, arith), expr_type(e.right, resolve, arith)
        if e.op in _SHIFTS:
            return lt
        if lt == "BOOL" and rt == "BOOL":
            return "BOOL"
        return _wider(lt, rt)
    raise TypeMismatch(f"not an expression: {e!r}")


def _wider(a: str, b: str) -> str:
    order = ("BYTE", "CHAR", "WORD", "INT", "S5TIME", "DWORD", "DINT", "TIME", "REAL")
    if a == b:
        return a
    if "TIME" in (a, b):
        return "TIME"
    ia = order.index(a) if a in order else 0
    ib = order.index(b) if b in order else 0
    return a if ia >= ib else b


def gen_value(
    e: Expr, g: CodeGen, resolve: Resolve, sidx: StepIndex, tidx: StepIndex, number: bool = False
) -> str:
    """Python source computing the value of ``e`` (locals ``st V X`` in scope); ``number``:
    where a number is expected — inside comparisons, arithmetic and function arguments, and
    for an assignment to a number — a timer or counter cell reads its value, else its
    status bit (``operands.CELLS``)."""
    if isinstance(e, Const):
        v = e.value
        if e.type == "REAL" and isinstance(v, float):
            return repr(_single(v))  # a REAL constant holds 32 bits, as the CPU loads it
        if isinstance(v, (bool, int, float)):
            return repr(v)
        return g.const(v)
    if isinstance(e, Operand):
        return g.read_number(resolve(e)) if number else g.read(resolve(e))
    if isinstance(e, StepAttr):
        i = sidx(e.step, e.loc)
        if e.attr == "X":
            return f"X[{i}]"
        arr = "t_ns" if e.attr == "T" else "u_ns"
        return f"(st.{arr}[{i}] // 1000000)"
    if isinstance(e, TransAttr):
        return f"st.tt[{tidx(e.transition, e.loc)}]"
    if isinstance(e, Unary):
        if e.op == "NOT":
            inner = gen_value(e.operand, g, resolve, sidx, tidx)
            t = expr_type(e.operand, resolve)  # a timer or counter: its status bit
            if t in BITS or t in _COMPLEMENT:
                return f"_not(st, {inner}, {t!r})"
            return f"(not {inner})"
        inner = gen_value(e.operand, g, resolve, sidx, tidx, True)
        t = expr_type(e.operand, resolve, True)
        return _checked(f"-({inner})", t) if t in RANGE else f"(-({inner}))"
    if isinstance(e, FuncCall):
        return _gen_call(e, g, resolve, sidx, tidx)
    if isinstance(e, Binary):
        return _gen_binary(e, g, resolve, sidx, tidx)
    raise TypeMismatch(f"not an expression: {e!r}")


def _gen_call(e: FuncCall, g: CodeGen, resolve: Resolve, sidx: StepIndex, tidx: StepIndex) -> str:
    """A call of one of ``FUNCTIONS`` (an untyped double word given to a REAL function is
    read as a REAL)."""
    name = e.name.upper()
    if name not in FUNCTIONS:
        raise TypeMismatch(f"unknown function {e.name}", e.loc)
    takes = next((a for a in ARGUMENTS.get(name, {}) if a in _DOUBLE), "")
    args = [_value_beside(a, takes, g, resolve, sidx, tidx, True) for a in e.args]
    t = expr_type(e.args[0], resolve, True) if e.args else "DINT"
    if e.args and _beside(e.args[0], takes, resolve) is not None:
        t = "REAL"
    _, helper = FUNCTIONS[name]
    if helper == "float":  # DINT_TO_REAL: 24 bits of mantissa
        return f"_single({args[0]})"
    if helper == "int":
        return f"int({args[0]})"
    return f"{helper}(st, {', '.join(args)}, {t!r})"


def _gen_binary(e: Binary, g: CodeGen, resolve: Resolve, sidx: StepIndex, tidx: StepIndex) -> str:
    """A comparison, logic, a shift or arithmetic (an untyped double word beside a REAL is
    read as a REAL)."""
    op = e.op.upper()
    arith = op not in LOGIC
    lt = rt = ""  # an untyped double word beside a REAL is one (not in logic or shifts)
    if arith and op not in _SHIFTS:
        lt, rt = expr_type(e.left, resolve, True), expr_type(e.right, resolve, True)
    left = _value_beside(e.left, rt, g, resolve, sidx, tidx, arith)
    right = _value_beside(e.right, lt, g, resolve, sidx, tidx, arith)
    if op in COMPARE:
        return f"({left} {COMPARE[op]} {right})"
    t = expr_type(e, resolve)
    if op in LOGIC:
        py = {"AND": "and", "OR": "or", "XOR": "!="}[op]
        if t == "BOOL":
            if op == "XOR":
                return f"(bool({left}) != bool({right}))"
            return f"(bool({left}) {py} bool({right}))"
        py = {"AND": "&", "OR": "|", "XOR": "^"}[op]
        return f"(({left}) {py} ({right}))"
    if op in _SHIFTS:
        return f"_shift(st, {op!r}, {left}, {right}, {t!r})"
    if op in ("+", "-", "*"):
        src = f"(({left}) {op} ({right}))"
        if t in RANGE:
            return _checked(src, t)
        if t in MASK:
            return f"({src} & {MASK[t]})"
        return f"_single{src}" if t == "REAL" else src
    if op == "/":
        return f"_div(st, {left}, {right}, {t!r})"
    if op == "MOD":
        return f"_mod(st, {left}, {right}, {t!r})"
    raise TypeMismatch(f"unknown operator {e.op}", e.loc)


def gen_assigned(
    e: Expr, target: Ref, g: CodeGen, resolve: Resolve, sidx: StepIndex, tidx: StepIndex
) -> str:
    """The statement ``target := e``: a number target reads timer and counter cells of
    ``e`` as values, a BOOL target as status bits (``gen_value``'s ``number``). A
    ``STRING[n]`` target keeps the value's first ``n`` characters, as S7 does."""
    value = _value_beside(e, target.type, g, resolve, sidx, tidx, target.type != "BOOL")
    target = settled(target, expr_type(e, resolve, True))
    if (n := string_chars(target.type)) is not None:
        value = f"({value})[:{n}]"
    return g.write(target, value)


def _checked(src: str, t: str) -> str:
    """``_ck(st, src, t)`` with the in-range case inline (no call): the same value, and the
    overflow handling of ``_ck`` otherwise. ``_v`` is a local of the generated function."""
    lo, hi = RANGE[t]
    return f"(_v if {lo} <= (_v := {src}) <= {hi} else _ck(st, _v, {t!r}))"


# ------------------------------------------------------------ runtime helpers


def _overflow(st: Any, what: str) -> None:
    st.ov = True
    st.ov_count += 1
    st.diag.append(what)
    if len(st.diag) > 16:
        del st.diag[0]


def _ck(st: Any, v: Any, t: str) -> Any:
    """Range check of an INT/DINT/TIME result: out of range sets OV and wraps."""
    lo, hi = RANGE[t]
    if lo <= v <= hi:
        return v
    _overflow(st, f"{t} overflow: {v}")
    span = hi - lo + 1
    return (int(v) - lo) % span + lo


def _div(st: Any, a: Any, b: Any, t: str) -> Any:
    if t == "REAL":
        if b == 0:
            _overflow(st, "REAL division by zero")
            if a == 0 or a != a:
                return math.nan
            return math.copysign(math.inf, a) * math.copysign(1.0, b)
        return _single(a / b)
    if b == 0:
        _overflow(st, f"{t} division by zero")
        return 0
    q = abs(int(a)) // abs(int(b))
    q = q if (a >= 0) == (b >= 0) else -q
    return _ck(st, q, t) if t in RANGE else q


def _mod(st: Any, a: int, b: int, t: str) -> int:
    if b == 0:
        _overflow(st, f"{t} MOD by zero")
        return 0
    r = abs(int(a)) % abs(int(b))
    return r if a >= 0 else -r


def _width(t: str) -> int:
    return {"BYTE": 8, "CHAR": 8, "WORD": 16, "INT": 16, "S5TIME": 16}.get(t, 32)


def _shift(st: Any, op: str, v: int, n: int, t: str) -> int:
    w = _width(t)
    mask = (1 << w) - 1
    n = int(n) & 255
    u = int(v) & mask
    if op == "SHL":
        r = (u << n) & mask if n < w else 0
    elif op == "SHR":
        r = u >> n if n < w else 0
    elif op == "SSR":
        s = int(v) if int(v) < (1 << (w - 1)) else int(v) - (1 << w)
        return s >> min(n, w)
    else:
        n %= w
        r = (
            ((u << n) | (u >> (w - n))) & mask
            if op == "ROL"
            else ((u >> n) | (u << (w - n))) & mask
        )
    if t in RANGE:  # signed view of the bit pattern
        return r - (1 << w) if r >> (w - 1) else r
    return r


def _bcd_to_num(st: Any, v: int, t: str) -> int:
    digits = (_width(t) // 4) - 1
    u = int(v) & ((1 << _width(t)) - 1)
    n = 0
    for k in range(digits - 1, -1, -1):
        d = (u >> (4 * k)) & 15
        if d > 9:
            _overflow(st, f"BCD_TO_NUM: invalid BCD digit in {u:#x}")
            return 0
        n = n * 10 + d
    sign = (u >> (4 * digits)) & 15
    return -n if sign else n


def _num_to_bcd(st: Any, v: int, t: str) -> int:
    digits = (_width(t) // 4) - 1
    a = abs(int(v))
    if a >= 10**digits:
        _overflow(st, f"NUM_TO_BCD: {v} has more than {digits} digits")
        return 0
    r = 0
    for k, ch in enumerate(reversed(str(a))):
        r |= int(ch) << (4 * k)
    if v < 0:
        r |= 15 << (4 * digits)
    return r


def _whole(st: Any, v: float, n: int | None) -> int:
    """A REAL made a DINT (``n``: its whole value; None: NaN or infinite): out of range
    or not a number sets the overflow status and gives 0, as S7 leaves no valid result."""
    if n is None or not RANGE["DINT"][0] <= n <= RANGE["DINT"][1]:
        _overflow(st, f"DINT overflow: {v}")
        return 0
    return n


def _round(st: Any, v: float, t: str) -> int:
    """ROUND (STL ``RND``): to the nearest whole number, a half to the even one."""
    v = float(v)
    return _whole(st, v, round(v) if math.isfinite(v) else None)


def _trunc(st: Any, v: float, t: str) -> int:
    """TRUNC: the whole part, towards zero."""
    v = float(v)
    return _whole(st, v, math.trunc(v) if math.isfinite(v) else None)


def _negr(st: Any, v: float, t: str) -> float:
    return -float(v)


def _abs(st: Any, v: float, t: str) -> float:
    return abs(float(v))


def _sqr(st: Any, v: float, t: str) -> float:
    return _single(float(v) * float(v))


def _real(fn: Callable[[float], float], name: str) -> Callable[[Any, float, str], float]:
    def apply(st: Any, v: float, t: str) -> float:
        try:
            return _single(fn(float(v)))
        except OverflowError:  # EXP of a large value: beyond the REAL range
            _overflow(st, f"{name}({v}) is out of the REAL range")
            return math.inf
        except ValueError:  # LN(0.0): minus infinity; SQRT(-1.0), LN(-1.0): NaN
            _overflow(st, f"{name}({v}) is not a number")
            return -math.inf if name == "LN" and v == 0 else math.nan

    return apply


_sqrt = _real(math.sqrt, "SQRT")
_ln = _real(math.log, "LN")
_exp = _real(math.exp, "EXP")
_sin = _real(math.sin, "SIN")
_asin = _real(math.asin, "ASIN")
_cos = _real(math.cos, "COS")
_acos = _real(math.acos, "ACOS")
_tan = _real(math.tan, "TAN")
_atan = _real(math.atan, "ATAN")


def _neg(st: Any, v: Any, t: str) -> Any:
    return _ck(st, -v, t) if t in RANGE else -v


def _not(st: Any, v: Any, t: str) -> int:
    if t in RANGE:
        return ~int(v)
    return ~int(v) & MASK.get(t, 0xFFFFFFFF)


def _swap(st: Any, v: int, t: str) -> int:
    n = _width(t) // 8
    return int.from_bytes((int(v) & ((1 << (8 * n)) - 1)).to_bytes(n, "big")[::-1], "big")


def _rlda(st: Any, v: int, t: str) -> int:
    return _shift(st, "ROL", v, 1, "DWORD")


def _rrda(st: Any, v: int, t: str) -> int:
    return _shift(st, "ROR", v, 1, "DWORD")


RUNTIME: dict[str, Any] = {
    name: obj
    for name, obj in globals().items()
    if name.startswith("_") and callable(obj) and not name.startswith("__")
}
