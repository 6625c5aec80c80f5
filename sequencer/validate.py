"""Check a parsed chart and report every problem at once (SPEC.md §2.1, §2.8, §2.9, §3).

``validate(chart, symbols)`` runs each rule below (one small function per rule) and returns
all diagnostics sorted by place; errors stop compilation, warnings do not. Codes and their
meaning are listed in ``sequencer.diagnostics.CODES``. The event × qualifier table is read
from ``steps.qualifiers`` (never re-encoded here); operand resolution is
``sequencer.names.resolve_operand``.

Typing (SPEC §2.8, §2.9; seed 000:5838-5884): comparisons need the same type on both sides,
one of INT DINT REAL TIME; ``+ - * /`` on INT DINT REAL (``+ -`` also on TIME); ``MOD`` on
DINT; ``AND OR XOR`` on BOOL (logic) or WORD/DWORD (bitwise, assignments only); ``SHL SHR``
on WORD/DWORD, ``SSR`` on INT/DINT, ``ROL ROR`` on DWORD, shift count INT. An untyped absolute
address adapts (WORD address ~ INT, DWORD address ~ DINT REAL TIME); an integer literal fits
INT and DINT. Conditions hold only contacts, NOT AND OR XOR and comparisons (SPEC §2.9).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Final

from engine.address import parse_address
from engine.errors import AddressError, SourceLocation, SymbolError
from engine.symbols import SymbolTable
from sequencer.diagnostics import Diagnostic, error, sort_key, warning
from sequencer.model import (
    ActionRow,
    Assignment,
    Binary,
    BlockCall,
    Chart,
    Coil,
    Const,
    Expr,
    FuncCall,
    Operand,
    Step,
    StepAttr,
    StepTarget,
    TransAttr,
    Transition,
    Unary,
)
from sequencer.names import Resolved, resolve_operand
from steps.qualifiers import (
    COUNTER_QUALIFIERS,
    NEEDS_VALUE,
    TIMED_QUALIFIERS,
    TIMER_QUALIFIERS,
    check,
    operand_kind,
)

# Limits that warn (SPEC §2.1).
MAX_STEPS: Final = 250
MAX_TRANSITIONS: Final = 250
MAX_ALTERNATIVE_PATHS: Final = 125
MAX_SIMULTANEOUS_PATHS: Final = 249
MAX_SEQUENCES: Final = 8
MAX_CONDITION_ELEMENTS: Final = 32
MAX_MARKINGS: Final = 20_000  # state-space bound of the join analysis

COMPARABLE: Final = frozenset({"INT", "DINT", "REAL", "TIME"})
COMPARISONS: Final = frozenset({"=", "<>", "<", ">", "<=", ">="})
LOGIC: Final = frozenset({"AND", "OR", "XOR"})
# Untyped absolute addresses and integer literals: the types each may stand for.
_FLEX: Final[dict[str, frozenset[str]]] = {
    "@8": frozenset({"BYTE", "CHAR"}),
    "@16": frozenset({"INT", "WORD", "S5TIME"}),
    "@32": frozenset({"DINT", "REAL", "TIME", "DWORD"}),
    "#INT": frozenset({"INT", "DINT"}),
}
_FLEX_DEFAULT: Final = {"@8": "BYTE", "@16": "INT", "@32": "DINT", "#INT": "INT"}
_ADDRESS_FLEX: Final = {"BYTE": "@8", "WORD": "@16", "DWORD": "@32"}
# Built-in functions of seed 000:5861-5884: name → {argument type: result type}.
FUNCTIONS: Final[dict[str, dict[str, str]]] = {
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
_SHIFT_LEFT: Final = {
    "SHL": ("WORD", "DWORD"),
    "SHR": ("WORD", "DWORD"),
    "SSR": ("INT", "DINT"),
    "ROL": ("DWORD",),
    "ROR": ("DWORD",),
}


@dataclass
class _Ctx:
    chart: Chart
    symbols: SymbolTable | None
    steps: dict[int, Step] = field(default_factory=dict)
    transitions: dict[int, Transition] = field(default_factory=dict)
    diags: list[Diagnostic] = field(default_factory=list)

    def err(self, code: str, msg: str, loc: SourceLocation, element: str = "") -> None:
        self.diags.append(error(code, msg, loc, element))

    def warn(self, code: str, msg: str, loc: SourceLocation, element: str = "") -> None:
        self.diags.append(warning(code, msg, loc, element))


def validate(chart: Chart, symbols: SymbolTable | None = None) -> list[Diagnostic]:
    """Every diagnostic of ``chart`` (errors and warnings), sorted by place."""
    ctx = _Ctx(chart, symbols)
    for s in chart.all_steps():
        ctx.steps.setdefault(s.number, s)
    for t in chart.all_transitions():
        ctx.transitions.setdefault(t.number, t)
    for rule in RULES:
        rule(ctx)
    unique = list(dict.fromkeys(ctx.diags))
    return sorted(unique, key=sort_key)


def _step_el(n: int) -> str:
    return f"step S{n}"


def _row_el(step: Step, i: int) -> str:
    return f"step S{step.number} row {i + 1}"


# ---------------------------------------------------------------- structure


def rule_duplicate_numbers(ctx: _Ctx) -> None:
    """Step and transition numbers are unique within the FB (E011, E012)."""
    seen_s: dict[int, Step] = {}
    for s in ctx.chart.all_steps():
        if s.number in seen_s:
            first = seen_s[s.number].loc
            ctx.err("E011", f"step S{s.number} is defined twice (first at line {first.line})",
                    s.loc, _step_el(s.number))  # fmt: skip
        seen_s.setdefault(s.number, s)
    seen_t: dict[int, Transition] = {}
    for t in ctx.chart.all_transitions():
        if t.number in seen_t:
            first = seen_t[t.number].loc
            ctx.err("E012", f"transition T{t.number} is defined twice (first at line "
                    f"{first.line})", t.loc, f"transition T{t.number}")  # fmt: skip
        seen_t.setdefault(t.number, t)


def rule_duplicate_declarations(ctx: _Ctx) -> None:
    """FB variables and chart symbols are declared once each (E013)."""
    seen: set[str] = set()
    for v in ctx.chart.vars:
        if v.name.upper() in seen:
            ctx.err("E013", f"FB variable {v.name} is declared twice", v.loc)
        seen.add(v.name.upper())
    seen_sym: set[str] = set()
    for s in ctx.chart.symbols:
        if s.name.casefold() in seen_sym:
            ctx.err("E013", f'symbol "{s.name}" is declared twice', s.loc)
        seen_sym.add(s.name.casefold())


def rule_declarations(ctx: _Ctx) -> None:
    """Chart symbols name valid addresses (E041); a variable's initial value fits its
    type (E031)."""
    for s in ctx.chart.symbols:
        try:
            parse_address(s.address, s.loc)
        except AddressError as exc:
            ctx.err("E041", exc.message, s.loc, f'symbol "{s.name}"')
    for v in ctx.chart.vars:
        if v.init is not None:
            t = _type(ctx, v.init, f"variable {v.name}")
            if t is not None and _unify(v.type.upper(), t) is None:
                ctx.err("E031", f"initial value {v.init.text} ({_show(t)}) does not fit "
                        f"{v.name} : {v.type}", v.init.loc, f"variable {v.name}")  # fmt: skip


def rule_unknown_steps_in_from_to(ctx: _Ctx) -> None:
    """Every step named in FROM / TO exists in the FB (E010); the column is the step's own."""
    for t in ctx.chart.all_transitions():
        for part, numbers, locs in (("FROM", t.sources, t.source_locs),
                                    ("TO", t.targets, t.target_locs)):  # fmt: skip
            for i, n in enumerate(numbers):
                if n not in ctx.steps:
                    loc = locs[i] if i < len(locs) else t.loc
                    ctx.err("E010", f"unknown step S{n} in {part}", loc, f"transition T{t.number}")


def rule_initial_steps(ctx: _Ctx) -> None:
    """Each sequencer has at least one initial step, else it never starts (W103)."""
    for seq in ctx.chart.sequences:
        if seq.steps and not any(s.initial for s in seq.steps):
            ctx.warn("W103", f"sequence {seq.number} has no initial step; it starts only by "
                     "ON or MAN mode", seq.loc, f"sequence {seq.number}")  # fmt: skip


def _on_targets(ctx: _Ctx) -> set[int]:
    return {
        r.operand.step
        for s in ctx.chart.all_steps()
        for r in s.actions
        if r.qualifier == "ON" and isinstance(r.operand, StepTarget) and r.operand.step is not None
    }


def rule_ways_in_and_out(ctx: _Ctx) -> None:
    """A step that is not initial needs a transition (or ON) leading in (W101); every step
    needs a transition leading out (W102)."""
    into = {n for t in ctx.chart.all_transitions() for n in t.targets} | _on_targets(ctx)
    out = {n for t in ctx.chart.all_transitions() for n in t.sources}
    for s in ctx.chart.all_steps():
        if not s.initial and s.number not in into:
            ctx.warn("W101", f"no transition leads to step S{s.number}; it can never become "
                     "active", s.loc, _step_el(s.number))  # fmt: skip
        if s.number not in out:
            ctx.warn("W102", f"no transition leaves step S{s.number}; once active it stays "
                     "active", s.loc, _step_el(s.number))  # fmt: skip


def rule_limits(ctx: _Ctx) -> None:
    """The limits of SPEC §2.1 warn (W110)."""
    c = ctx.chart
    steps, trans = c.all_steps(), c.all_transitions()
    if len(c.sequences) > MAX_SEQUENCES:
        ctx.warn("W110", f"{len(c.sequences)} sequencers; S7-GRAPH allows {MAX_SEQUENCES}",
                 c.sequences[MAX_SEQUENCES].loc)  # fmt: skip
    if len(steps) > MAX_STEPS:
        ctx.warn("W110", f"{len(steps)} steps; S7-GRAPH allows {MAX_STEPS}", steps[MAX_STEPS].loc)
    if len(trans) > MAX_TRANSITIONS:
        ctx.warn("W110", f"{len(trans)} transitions; S7-GRAPH allows {MAX_TRANSITIONS}",
                 trans[MAX_TRANSITIONS].loc)  # fmt: skip
    leaving: dict[int, list[Transition]] = {}
    for t in trans:
        for n in t.sources:
            leaving.setdefault(n, []).append(t)
        paths = max(len(t.sources), len(t.targets))
        if paths > MAX_SIMULTANEOUS_PATHS:
            ctx.warn("W110", f"{paths} simultaneous paths; S7-GRAPH allows "
                     f"{MAX_SIMULTANEOUS_PATHS}", t.loc, f"transition T{t.number}")  # fmt: skip
    for n, ts in leaving.items():
        if len(ts) > MAX_ALTERNATIVE_PATHS:
            msg = f"{len(ts)} alternative paths leave S{n}; S7-GRAPH allows {MAX_ALTERNATIVE_PATHS}"
            ctx.warn("W110", msg, ts[MAX_ALTERNATIVE_PATHS].loc, _step_el(n))
    for expr, loc, el in _conditions(ctx):
        k = _elements(expr)
        if k > MAX_CONDITION_ELEMENTS:
            ctx.warn("W110", f"condition has {k} elements; S7-GRAPH allows "
                     f"{MAX_CONDITION_ELEMENTS}", loc, el)  # fmt: skip


def _elements(e: Expr) -> int:
    """Contacts and comparators of a condition (each is one CRIT bit)."""
    if isinstance(e, Binary) and e.op in LOGIC:
        return _elements(e.left) + _elements(e.right)
    if isinstance(e, Unary) and e.op == "NOT":
        return _elements(e.operand)
    return 1


def rule_empty_conditions(ctx: _Ctx) -> None:
    """An empty transition condition always holds (W120, SPEC §2.9)."""
    for t in ctx.chart.all_transitions():
        if t.condition is None:
            ctx.warn("W120", f"transition T{t.number} has no condition; it switches at once",
                     t.loc, f"transition T{t.number}")  # fmt: skip


def rule_c_without_interlock(ctx: _Ctx) -> None:
    """Rows marked C on a step without INTERLOCK always run (W122, SPEC §2.3)."""
    for s in ctx.chart.all_steps():
        if s.interlock is not None:
            continue
        for i, r in enumerate(s.actions):
            if r.interlocked:
                ctx.warn("W122", f"row marked C but step S{s.number} has no INTERLOCK; the "
                         "mark has no effect", r.loc, _row_el(s, i))  # fmt: skip


# ---------------------------------------------------------------- action rows (SPEC §2.8)


def rule_action_rows(ctx: _Ctx) -> None:
    """Each row: event/qualifier/C per the table (E020, E025), value present and typed
    (E021, E022, E023), operand of the right kind (E024), ON/OFF steps known (E026),
    no bit assignments in actions (E035), assignments typed (E031)."""
    for s in ctx.chart.all_steps():
        for i, r in enumerate(s.actions):
            _check_row(ctx, s, i, r)


def _check_row(ctx: _Ctx, step: Step, i: int, r: ActionRow) -> None:
    el = _row_el(step, i)
    op = r.operand
    s_all = isinstance(op, StepTarget) and op.step is None
    kind = operand_kind(r.qualifier, assignment=isinstance(op, Assignment), s_all=s_all)
    rule = check(r.event, r.qualifier, r.interlocked, kind)
    if not rule.allowed:
        ctx.err("E025" if s_all else "E020", rule.reason, r.loc, el)
    q = r.qualifier
    if q in NEEDS_VALUE and r.value is None:
        example = {"D": "T#2S", "L": "T#2S", "CS": "C#5"}.get(q, "S5T#2S")
        ctx.err("E021", f"{q} needs a value after a comma, e.g. ', {example}'", r.loc, el)
    if r.value is not None:
        _check_row_value(ctx, r, el)
    if isinstance(op, StepTarget):
        if op.step is not None and op.step not in ctx.steps:
            ctx.err("E026", f"{q} of unknown step S{op.step}", op.loc, el)
    elif isinstance(op, Assignment):
        _check_assignment(ctx, op, el, in_action=True)
    elif isinstance(op, BlockCall):
        _check_call(ctx, op, el)
    elif isinstance(op, Operand):
        _check_row_operand(ctx, r, op, el)


def _check_row_value(ctx: _Ctx, r: ActionRow, el: str) -> None:
    q, value = r.qualifier, r.value
    assert value is not None
    if q not in NEEDS_VALUE:
        ctx.err("E023", f"{q} takes no value", _loc(value), el)
        return
    t = _type(ctx, value, el)
    if t is None:
        return
    want = {"D": "TIME", "L": "TIME", "CS": "WORD"}.get(q, "S5TIME")
    if _unify(t, want) != want:
        code = "E022" if q in TIMED_QUALIFIERS else "E023"
        example = {"TIME": "T#2S", "WORD": "C#5", "S5TIME": "S5T#2S"}[want]
        ctx.err(code, f"{q} needs a {want} value like {example}, not {_show(t)}", _loc(value), el)


def _check_row_operand(ctx: _Ctx, r: ActionRow, op: Operand, el: str) -> None:
    res = _resolve(ctx, op, el)
    if res is None:
        return
    q = r.qualifier
    if q in COUNTER_QUALIFIERS:
        want, what = "COUNTER", "a counter like C 5"
    elif q in TIMER_QUALIFIERS:
        want, what = "TIMER", "a timer like T 5"
    else:
        want, what = "BOOL", "a bit like Q0.0"
    if res.type != want:
        ctx.err("E024", f"{q} needs {what}, not {op.name} ({res.type})", op.loc, el)
    elif not res.writable:
        ctx.err("E045", f"{op.name} is an FB output; the chart cannot write it", op.loc, el)


def _check_call(ctx: _Ctx, call: BlockCall, el: str) -> None:
    for _, e in call.inputs:
        _type(ctx, e, el)
    for _, o in call.outputs:
        _resolve(ctx, o, el)


def _check_assignment(ctx: _Ctx, a: Assignment, el: str, *, in_action: bool) -> None:
    res = _resolve(ctx, a.target, el)
    t = _type(ctx, a.expr, el)
    if res is None:
        return
    if not res.writable:
        ctx.err("E045", f"{a.target.name} is an FB output; the chart cannot write it",
                a.target.loc, el)  # fmt: skip
        return
    target = _ADDRESS_FLEX.get(res.type, res.type) if res.is_untyped else res.type
    if in_action and target == "BOOL":
        ctx.err("E035", f"{a.target.name} := ... writes a bit: a coil belongs in the permanent "
                "instructions; in a step use N, S or R", a.target.loc, el)  # fmt: skip
        return
    if t is not None and _unify(target, t) is None:
        ctx.err("E031", f"cannot assign {_show(t)} to {a.target.name} ({_show(target)})",
                a.target.loc, el)  # fmt: skip


# ---------------------------------------------------------------- permanent instructions


def rule_permanent_instructions(ctx: _Ctx) -> None:
    """Coils write bits from conditions; assignments are typed; calls name known operands."""
    for place, items in (("before", ctx.chart.before), ("after", ctx.chart.after)):
        el = f"permanent {place}"
        for it in items:
            if isinstance(it, Coil):
                res = _resolve(ctx, it.target, el)
                if res is not None and res.type != "BOOL":
                    ctx.err("E031", f"a coil writes a bit; {it.target.name} is {res.type}",
                            it.target.loc, el)  # fmt: skip
                elif res is not None and not res.writable:
                    ctx.err("E045", f"{it.target.name} is an FB output; the chart cannot "
                            "write it", it.target.loc, el)  # fmt: skip
            elif isinstance(it, Assignment):
                _check_assignment(ctx, it, el, in_action=False)
            elif isinstance(it, BlockCall):
                _check_call(ctx, it, el)


# ---------------------------------------------------------------- conditions (SPEC §2.9)


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
        if t is not None and t != "BOOL":
            ctx.err("E034", f"a condition must be TRUE or FALSE, this is {_show(t)}",
                    _loc(expr), el)  # fmt: skip


def _check_condition_shape(ctx: _Ctx, e: Expr, el: str) -> None:
    if isinstance(e, Binary) and (e.op in LOGIC):
        _check_condition_shape(ctx, e.left, el)
        _check_condition_shape(ctx, e.right, el)
    elif isinstance(e, Unary) and e.op == "NOT":
        _check_condition_shape(ctx, e.operand, el)
    elif isinstance(e, Binary) and e.op in COMPARISONS:
        for side in (e.left, e.right):
            if not isinstance(side, Operand | Const | StepAttr | TransAttr):
                ctx.err("E034", "a comparison in a condition compares operands and constants "
                        "only; compute values in an action or permanent instruction",
                        _loc(side), el)  # fmt: skip
    elif isinstance(e, Binary | Unary | FuncCall):
        what = e.op if isinstance(e, Binary | Unary) else f"{e.name}()"
        ctx.err("E034", f"{what} is not allowed in a condition (contacts, NOT AND OR XOR and "
                "comparisons only)", _loc(e), el)  # fmt: skip


# ---------------------------------------------------------------- typing


def _loc(e: object) -> SourceLocation:
    loc = getattr(e, "loc", None)
    return loc if isinstance(loc, SourceLocation) else SourceLocation()


def _show(t: str) -> str:
    return {"@8": "BYTE", "@16": "WORD", "@32": "DWORD", "#INT": "INT"}.get(t, t)


def _unify(a: str, b: str) -> str | None:
    """The common type of ``a`` and ``b`` (flexible types adapt), or None."""
    if a == b:
        return a
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
        return resolve_operand(op, ctx.chart, ctx.symbols)
    except AddressError as exc:
        where = exc.where if isinstance(exc.where, SourceLocation) else op.loc
        ctx.err("E041", exc.message, where, el)
    except SymbolError as exc:
        ctx.err("E040" if op.quoted else "E042", exc.message, op.loc, el)
    return None


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
        return _ADDRESS_FLEX.get(res.type, res.type) if res.is_untyped else res.type
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
        if t == "BOOL":
            return "BOOL"
        return _apply(ctx, "NOT", FUNCTIONS["NOT"], t, e.loc, el)
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
    return None if t is None else _apply(ctx, e.name, table, t, e.loc, el)


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
    if op in COMPARISONS:
        u = _unify(lt, rt)
        if u is None:
            ctx.err("E030", f"cannot compare {_show(lt)} with {_show(rt)}; both sides need "
                    "the same type", e.loc, el)  # fmt: skip
        elif _concrete(u) not in COMPARABLE:
            ctx.err("E030", f"only INT DINT REAL TIME can be compared, not {_show(u)}", e.loc, el)
        return "BOOL"
    if op in _SHIFT_LEFT:
        allowed = _SHIFT_LEFT[op]
        left = next((a for a in allowed if _unify(a, lt) == a), None)
        if left is None:
            ctx.err("E032", f"{op} works on {' '.join(allowed)}, not {_show(lt)}", e.loc, el)
        if _unify("INT", rt) != "INT":
            ctx.err("E032", f"the count of {op} is an INT (0..255), not {_show(rt)}",
                    _loc(e.right), el)  # fmt: skip
        elif isinstance(e.right, Const) and not 0 <= int(e.right.value) <= 255:  # type: ignore[call-overload]
            ctx.err("E032", f"the count of {op} must be 0..255", _loc(e.right), el)
        return left
    u = _unify(lt, rt)
    if u is None:
        ctx.err("E030" if op in COMPARISONS else "E032",
                f"{op} of {_show(lt)} and {_show(rt)}: both sides need the same type",
                e.loc, el)  # fmt: skip
        return None
    if op in LOGIC:
        if u == "BOOL":
            return "BOOL"
        word = next((w for w in ("WORD", "DWORD") if _unify(w, u) == w), None)
        if word is None:
            ctx.err("E032", f"{op} works on BOOL, WORD or DWORD, not {_show(u)}", e.loc, el)
        return word
    allowed_arith = {"+": "INT DINT REAL TIME", "-": "INT DINT REAL TIME", "*": "INT DINT REAL",
                     "/": "INT DINT REAL", "MOD": "DINT"}.get(op, "")  # fmt: skip
    ok = allowed_arith.split()
    c = u if u in ok else next((x for x in ("INT", "DINT", "REAL", "TIME") if
                                x in ok and _unify(x, u) == x), None)  # fmt: skip
    if c is None:
        ctx.err("E032", f"{op} works on {allowed_arith}, not {_show(u)}", e.loc, el)
    return c


# ---------------------------------------------------------------- join analysis (W130)


def rule_joins(ctx: _Ctx) -> None:
    """A join transition whose source steps are each reachable but never active together
    can never switch (W130). Token game over the net from the initial steps (conditions
    ignored, any enabled transition may fire); skipped when the state space is too large
    or an ON action could activate a source."""
    joins = [t for t in ctx.chart.all_transitions() if len(t.sources) > 1]
    if not joins:
        return
    on = _on_targets(ctx)
    trans = [t for t in ctx.chart.all_transitions() if all(n in ctx.steps for n in t.sources)]
    start = frozenset(s.number for s in ctx.chart.all_steps() if s.initial)
    seen = {start}
    todo = [start]
    while todo:
        m = todo.pop()
        for t in trans:
            if all(n in m for n in t.sources):
                nxt = (m - frozenset(t.sources)) | frozenset(n for n in t.targets if n in ctx.steps)
                if nxt not in seen:
                    if len(seen) >= MAX_MARKINGS:
                        return
                    seen.add(nxt)
                    todo.append(nxt)
    reachable = frozenset().union(*seen)
    for t in joins:
        if any(n not in ctx.steps or n not in reachable or n in on for n in t.sources):
            continue
        if not any(all(n in m for n in t.sources) for m in seen):
            names = ", ".join(f"S{n}" for n in t.sources)
            ctx.warn("W130", f"steps {names} are never active together: transition "
                     f"T{t.number} can never switch", t.loc, f"transition T{t.number}")  # fmt: skip


RULES: Final[tuple[Callable[[_Ctx], None], ...]] = (
    rule_duplicate_numbers,
    rule_duplicate_declarations,
    rule_declarations,
    rule_unknown_steps_in_from_to,
    rule_initial_steps,
    rule_ways_in_and_out,
    rule_limits,
    rule_empty_conditions,
    rule_c_without_interlock,
    rule_action_rows,
    rule_permanent_instructions,
    rule_conditions,
    rule_joins,
)
