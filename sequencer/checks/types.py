"""Validation rules for conditions, operands and types (docs/semantics.md, "Actions" and
"Conditions"; docs/chart-format.md).

Typing (docs/semantics.md, "Actions" and "Conditions"; STEP7 comprehensive guide vol. 2, ch. 14):
comparisons need the same type on both sides, one of INT DINT REAL TIME; ``+ - * /`` on INT DINT
REAL (``+ -`` also on TIME); ``MOD`` on DINT; ``AND OR XOR`` on BOOL (logic) or WORD/DWORD (bitwise,
assignments only); ``SHL SHR`` on WORD/DWORD, ``SSR`` on INT/DINT, ``ROL ROR`` on DWORD, shift count
INT. An untyped absolute address adapts (WORD address ~ INT, DWORD address ~ DINT REAL TIME); an
integer literal fits INT and DINT. A timer or counter cell (``T5``, ``C1``) is a contact (its status
bit) where a BOOL is expected, and its INT value in comparisons, arithmetic, function arguments and
assignments (``steps.operands.CELLS``; El-Shahat's S7-300/400 course). Conditions hold only
contacts, NOT AND OR XOR and comparisons (docs/semantics.md, "Conditions"). Operand resolution is
``sequencer.text.names.resolve_operand``.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Final

from s7graph.engine.datatypes import string_chars
from s7graph.engine.errors import AddressError, SourceLocation, SymbolError
from s7graph.sequencer.checks.context import _Ctx
from s7graph.sequencer.text.model import (
    Binary,
    Coil,
    Const,
    Expr,
    FuncCall,
    Operand,
    StepAttr,
    TransAttr,
    Unary,
)
from s7graph.sequencer.text.names import MemberError, Resolved, resolve_operand
from s7graph.steps.expressions import ARGUMENTS

COMPARABLE: Final = frozenset({"INT", "DINT", "REAL", "TIME"})
COMPARISONS: Final = frozenset({"=", "<>", "<", ">", "<=", ">="})
LOGIC: Final = frozenset({"AND", "OR", "XOR"})
# Untyped absolute addresses and integer literals: the types each may stand for.
_FLEX: Final[dict[str, frozenset[str]]] = {
    "@8": frozenset({"BYTE", "CHAR"}),
    "@16": frozenset({"INT", "WORD", "S5TIME"}),
    "@32": frozenset({"DINT", "REAL", "TIME", "DWORD"}),
    "#INT": frozenset({"INT", "DINT"}),
    "@T": frozenset({"BOOL", "INT"}),  # a timer: status bit or value
    "@C": frozenset({"BOOL", "INT"}),  # a counter: status bit or value
}
_FLEX_DEFAULT: Final = {
    "@8": "BYTE",
    "@16": "INT",
    "@32": "DINT",
    "#INT": "INT",
    "@T": "BOOL",
    "@C": "BOOL",
}
_CELL_FLEX: Final = {"TIMER": "@T", "COUNTER": "@C"}
_ADDRESS_FLEX: Final = {"BYTE": "@8", "WORD": "@16", "DWORD": "@32"}
# Built-in functions: name → {argument type: result type} (``steps.expressions.ARGUMENTS``).
FUNCTIONS: Final = ARGUMENTS
_SHIFT_LEFT: Final = {
    "SHL": ("WORD", "DWORD"),
    "SHR": ("WORD", "DWORD"),
    "SSR": ("INT", "DINT"),
    "ROL": ("DWORD",),
    "ROR": ("DWORD",),
}


def rule_empty_conditions(ctx: _Ctx) -> None:
    """An empty transition condition always holds (W120, docs/semantics.md, "Conditions")."""
    for t in ctx.chart.all_transitions():
        if t.condition is None:
            ctx.warn(
                "W120",
                f"transition T{t.number} has no condition; it switches at once",
                t.loc,
                f"transition T{t.number}",
            )


# ---------------------------------------------------- conditions (docs/semantics.md, "Conditions")


def _conditions(ctx: _Ctx) -> Iterator[tuple[Expr, SourceLocation, str]]:
    for t in ctx.chart.all_transitions():
        if t.condition is not None:
            yield t.condition, _loc(t.condition), f"transition T{t.number}"
    for s in ctx.chart.all_steps():
        if s.interlock is not None:
            yield s.interlock, _loc(s.interlock), f"step S{s.number} interlock"
        if s.supervision is not None:
            yield s.supervision, _loc(s.supervision), f"step S{s.number} supervision"
    for place, items in (("before", ctx.chart.before), ("after", ctx.chart.after)):
        for it in items:
            if isinstance(it, Coil):
                yield it.condition, _loc(it.condition), f"permanent {place}"


def rule_conditions(ctx: _Ctx) -> None:
    """Conditions are booleans of contacts, NOT AND OR XOR and comparisons of same-typed
    INT DINT REAL TIME (E034, E030), over known operands (E040-E044)."""
    for expr, _, el in _conditions(ctx):
        _check_condition_shape(ctx, expr, el)
        t = _type(ctx, expr, el)
        if t is not None and _as_bit(t) != "BOOL":
            ctx.err(
                "E034", f"a condition must be TRUE or FALSE, this is {_show(t)}", _loc(expr), el
            )


def _check_condition_shape(ctx: _Ctx, e: Expr, el: str) -> None:
    if isinstance(e, Binary) and (e.op in LOGIC):
        _check_condition_shape(ctx, e.left, el)
        _check_condition_shape(ctx, e.right, el)
    elif isinstance(e, Unary) and e.op == "NOT":
        _check_condition_shape(ctx, e.operand, el)
    elif isinstance(e, Binary) and e.op in COMPARISONS:
        for side in (e.left, e.right):
            if not isinstance(side, Operand | Const | StepAttr | TransAttr):
                ctx.err(
                    "E034",
                    "a comparison in a condition compares operands and constants "
                    "only; compute values in an action or permanent instruction",
                    _loc(side),
                    el,
                )
    elif isinstance(e, Binary | Unary | FuncCall):
        what = e.op if isinstance(e, Binary | Unary) else f"{e.name}()"
        ctx.err(
            "E034",
            f"{what} is not allowed in a condition (contacts, NOT AND OR XOR and comparisons only)",
            _loc(e),
            el,
        )


# ---------------------------------------------------------------- typing


def _loc(e: object) -> SourceLocation:
    loc = getattr(e, "loc", None)
    return loc if isinstance(loc, SourceLocation) else SourceLocation()


_SHOW: Final = {
    "@8": "BYTE",
    "@16": "WORD",
    "@32": "DWORD",
    "#INT": "INT",
    "@T": "TIMER",
    "@C": "COUNTER",
}


def _show(t: str) -> str:
    return _SHOW.get(t, t)


def _as_bit(t: str) -> str:
    """``t`` where a BOOL is expected: a timer or counter cell is its status bit."""
    return "BOOL" if t in ("@T", "@C") else t


def _as_number(t: str) -> str:
    """``t`` where a number is expected: a timer or counter cell is its INT value."""
    return "INT" if t in ("@T", "@C") else t


def _unify(a: str, b: str) -> str | None:
    """The common type of ``a`` and ``b`` (flexible types adapt), or None. A ``STRING[n]``
    takes any STRING (the engine cuts a longer value to ``n`` characters, as S7 does)."""
    if a == b:
        return a
    if b == "STRING" and string_chars(a) is not None:
        return a
    if a == "STRING" and string_chars(b) is not None:
        return b
    fa, fb = _FLEX.get(a), _FLEX.get(b)
    if fa is not None and fb is not None:
        common = fa & fb
        if a == "#INT" and b in ("@16", "@32"):
            return "INT" if b == "@16" else "DINT"
        if b == "#INT" and a in ("@16", "@32"):
            return "INT" if a == "@16" else "DINT"
        return min(common) if common else None
    if fa is not None:
        return b if b in fa else None
    if fb is not None:
        return a if a in fb else None
    return None


def _concrete(t: str) -> str:
    return _FLEX_DEFAULT.get(t, t)


def _resolve(ctx: _Ctx, op: Operand, el: str) -> Resolved | None:
    try:
        return resolve_operand(op, ctx.chart, ctx.symbols, blocks=ctx.readable)
    except AddressError as exc:
        where = exc.where if isinstance(exc.where, SourceLocation) else op.loc
        ctx.err("E041", exc.message, where, el)
    except MemberError as exc:
        ctx.err("E048", exc.message, op.loc, el)
    except SymbolError as exc:
        ctx.err("E040" if op.quoted else "E042", exc.message, op.loc, el)
    return None


def _operand_type(res: Resolved) -> str:
    """A resolved operand's type; an untyped address's is flexible (``MW10``: any word)."""
    return _ADDRESS_FLEX.get(res.type, res.type) if res.is_untyped else res.type


def _type(ctx: _Ctx, e: Expr, el: str) -> str | None:
    """The type of ``e`` (a flexible one for untyped addresses and integer literals), or
    None when a diagnostic has already been given."""
    if isinstance(e, Const):
        if e.type == "INT" and e.text.lstrip("-").isdigit():
            return "#INT"
        return e.type
    if isinstance(e, Operand):
        res = _resolve(ctx, e, el)
        if res is None:
            return None
        if res.type in _CELL_FLEX:
            return _CELL_FLEX[res.type]
        return _operand_type(res)
    if isinstance(e, StepAttr):
        if e.step not in ctx.steps:
            ctx.err("E043", f"S{e.step}.{e.attr} names an unknown step", e.loc, el)
        return "BOOL" if e.attr == "X" else "TIME"
    if isinstance(e, TransAttr):
        if e.transition not in ctx.transitions:
            ctx.err("E044", f"T{e.transition}.TT names an unknown transition", e.loc, el)
        return "BOOL"
    if isinstance(e, Unary):
        return _type_unary(ctx, e, el)
    if isinstance(e, FuncCall):
        return _type_call(ctx, e, el)
    return _type_binary(ctx, e, el)


def _type_unary(ctx: _Ctx, e: Unary, el: str) -> str | None:
    t = _type(ctx, e.operand, el)
    if t is None:
        return None
    if e.op == "NOT":
        if _as_bit(t) == "BOOL":
            return "BOOL"
        return _apply(ctx, "NOT", FUNCTIONS["NOT"], t, e.loc, el)
    t = _as_number(t)
    ok = {"INT", "DINT", "REAL", "TIME"}
    c = t if t in ok else next((x for x in sorted(_FLEX.get(t, ())) if x in ok), None)
    if c is None:
        ctx.err("E032", f"'-' needs INT DINT REAL or TIME, not {_show(t)}", e.loc, el)
    return c


def _type_call(ctx: _Ctx, e: FuncCall, el: str) -> str | None:
    arg_types = [_type(ctx, a, el) for a in e.args]
    table = FUNCTIONS.get(e.name)
    if table is None:
        known = " ".join(sorted(FUNCTIONS))
        ctx.err("E033", f"unknown function {e.name}; the functions are {known}", e.loc, el)
        return None
    if len(e.args) != 1:
        ctx.err("E033", f"{e.name} takes one argument, not {len(e.args)}", e.loc, el)
        return None
    t = arg_types[0]
    return None if t is None else _apply(ctx, e.name, table, _as_number(t), e.loc, el)


def _apply(
    ctx: _Ctx, name: str, table: dict[str, str], t: str, loc: SourceLocation, el: str
) -> str | None:
    for arg, result in table.items():
        if _unify(arg, t) == arg:
            return result
    allowed = " ".join(table)
    ctx.err("E033", f"{name} takes {allowed}, not {_show(t)}", loc, el)
    return None


def _type_binary(ctx: _Ctx, e: Binary, el: str) -> str | None:
    lt, rt = _type(ctx, e.left, el), _type(ctx, e.right, el)
    if lt is None or rt is None:
        return "BOOL" if e.op in COMPARISONS else None
    op = e.op
    cast = _as_bit if op in LOGIC else _as_number
    lt, rt = cast(lt), cast(rt)
    if op in COMPARISONS:
        u = _unify(lt, rt)
        if u is None:
            ctx.err(
                "E030",
                f"cannot compare {_show(lt)} with {_show(rt)}; both sides need the same type",
                e.loc,
                el,
            )
        elif _concrete(u) not in COMPARABLE:
            ctx.err("E030", f"only INT DINT REAL TIME can be compared, not {_show(u)}", e.loc, el)
        return "BOOL"
    if op in _SHIFT_LEFT:
        allowed = _SHIFT_LEFT[op]
        left = next((a for a in allowed if _unify(a, lt) == a), None)
        if left is None:
            ctx.err("E032", f"{op} works on {' '.join(allowed)}, not {_show(lt)}", e.loc, el)
        if _unify("INT", rt) != "INT":
            ctx.err(
                "E032", f"the count of {op} is an INT (0..255), not {_show(rt)}", _loc(e.right), el
            )
        elif isinstance(e.right, Const) and not 0 <= int(e.right.value) <= 255:  # type: ignore[call-overload]
            ctx.err("E032", f"the count of {op} must be 0..255", _loc(e.right), el)
        return left
    u = _unify(lt, rt)
    if u is None:
        ctx.err(
            "E030" if op in COMPARISONS else "E032",
            f"{op} of {_show(lt)} and {_show(rt)}: both sides need the same type",
            e.loc,
            el,
        )
        return None
    if op in LOGIC:
        if u == "BOOL":
            return "BOOL"
        word = next((w for w in ("WORD", "DWORD") if _unify(w, u) == w), None)
        if word is None:
            ctx.err("E032", f"{op} works on BOOL, WORD or DWORD, not {_show(u)}", e.loc, el)
        return word
    allowed_arith = {
        "+": "INT DINT REAL TIME",
        "-": "INT DINT REAL TIME",
        "*": "INT DINT REAL",
        "/": "INT DINT REAL",
        "MOD": "DINT",
    }.get(op, "")
    ok = allowed_arith.split()
    c = (
        u
        if u in ok
        else next(
            (x for x in ("INT", "DINT", "REAL", "TIME") if x in ok and _unify(x, u) == x), None
        )
    )
    if c is None:
        ctx.err("E032", f"{op} works on {allowed_arith}, not {_show(u)}", e.loc, el)
    return c
