"""Validation rules for action rows and permanent instructions (docs/semantics.md, "Interlock" and
"Actions"; docs/chart-format.md).

The event × qualifier table is read from ``steps.qualifiers`` (never re-encoded here).
"""

from __future__ import annotations

from s7graph.engine.errors import S7Error
from s7graph.sequencer.checks.context import _Ctx, _row_el
from s7graph.sequencer.checks.types import (
    _as_bit,
    _as_number,
    _loc,
    _operand_type,
    _resolve,
    _show,
    _type,
    _unify,
)
from s7graph.sequencer.checks.user_calls import (
    DB_TYPE,
    check_instance,
    check_user_call,
    db_to_value,
    instance_db_passed,
)
from s7graph.sequencer.text.call_sites import call_sites
from s7graph.sequencer.text.model import (
    ActionRow,
    Assignment,
    BlockCall,
    Coil,
    Expr,
    Operand,
    Step,
    StepTarget,
)
from s7graph.sequencer.text.names import Resolved, db_argument, resolve_operand
from s7graph.sequencer.text.walk import nodes
from s7graph.sfb import catalogue
from s7graph.steps.qualifiers import (
    COUNTER_QUALIFIERS,
    NEEDS_VALUE,
    TIMED_QUALIFIERS,
    TIMER_QUALIFIERS,
    check,
    operand_kind,
)


def rule_c_without_interlock(ctx: _Ctx) -> None:
    """Rows marked C on a step without INTERLOCK always run (W122, docs/semantics.md,
    "Interlock")."""
    for s in ctx.chart.all_steps():
        if s.interlock is not None:
            continue
        for i, r in enumerate(s.actions):
            if r.interlocked:
                ctx.warn(
                    "W122",
                    f"row marked C but step S{s.number} has no INTERLOCK; the mark has no effect",
                    r.loc,
                    _row_el(s, i),
                )


# ------------------------------------------------------ action rows (docs/semantics.md, "Actions")


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
        ctx.err("E045", _read_only(op.name, res), op.loc, el)


def _check_call(ctx: _Ctx, call: BlockCall, el: str) -> None:
    """Parameters are typed operands; a call of a system block (``CALL SFB 4, DB 10``, or
    by its name, ``CALL "TON", DB 10``) names one s7graph has, with an instance DB (by
    number) exactly when it is an SFB, and its parameters are pins of it, ``:=`` for
    inputs, ``=>`` for outputs, of the pin's type, all of them for an SFC (the catalogue,
    ``sfb.catalogue``). FB and FC calls name the user's blocks, which only the program
    that loads them knows: checked when it is given (``sequencer.checks.user_calls``)."""
    types = [(name, _input_type(ctx, e, el), e) for name, e in call.inputs]
    for name, o in call.outputs:
        res = _resolve(ctx, o, el)
        if res is not None and not res.writable:
            ctx.err(
                "E045",
                f"{name} => {o.name}: {_read_only(o.name, res)}",
                o.loc,
                el,
            )
        elif res is not None:
            types.append((name, _operand_type(res), o))
    if isinstance(call.instance, int) and not 1 <= call.instance <= 65535:
        ctx.err("E046", f"DB {call.instance}: a DB number is 1 to 65535", call.loc, el)
    if call.kind not in ("SFB", "SFC", ""):
        check_user_call(ctx, call, el, types)
        return
    entry = catalogue.find(f"{call.kind}{call.block}")  # by number, or by name ("TON")
    if entry is None and call.kind == "":
        check_user_call(ctx, call, el, types)  # a user block's symbol
        return
    if entry is None:
        known = " ".join(e.key for e in catalogue.CATALOGUE if e.kind == call.kind)
        ctx.err(
            "E046",
            f"{call.kind} {call.block} is not a system block s7graph has ({call.kind}s: {known})",
            call.loc,
            el,
        )
        return
    problems = entry.check_call(
        [n for n, _ in call.inputs],
        [n for n, _ in call.outputs],
        has_instance=call.instance is not None,
    )
    for problem in problems:
        ctx.err("E046", problem, call.loc, el)
    given = {n.upper() for n, _ in (*call.inputs, *call.outputs)}
    missing = [p.name for p in entry.pins if p.name not in given]
    if not entry.needs_instance and missing:  # an FC's parameters all are given (S7)
        ctx.err(
            "E046",
            f"{entry.key} {entry.name}: an SFC takes every parameter; {', '.join(missing)} missing",
            call.loc,
            el,
        )
    if entry.needs_instance:  # one block per instance DB (and the program's, when given)
        check_instance(ctx, call, el, entry.key)
    if entry.needs_instance and isinstance(call.instance, str):
        ctx.err(
            "E046",
            f"{entry.key} {entry.name}: name its instance DB by number "
            f"(DB 10), not {call.instance!r}",
            call.loc,
            el,
        )

    for name, t, e in types:
        pin = entry.pin(name)
        if pin is not None and t == DB_TYPE:
            why = db_to_value(f"{entry.key} {entry.name}", pin.name, pin.type, e)
            ctx.err("E046", why, getattr(e, "loc", call.loc), el)
            continue
        if pin is None or t is None or pin.type == "ANY":
            continue
        if _unify(pin.type, _as_bit(t) if pin.type == "BOOL" else _as_number(t)) is None:
            ctx.err(
                "E046",
                f"{entry.key} {entry.name}: {pin.name} is {_show(pin.type)}, "
                f"{_show(t)} does not fit it",
                getattr(e, "loc", call.loc),
                el,
            )


def _input_type(ctx: _Ctx, e: Expr, el: str) -> str | None:
    """The type of a call's input ``e``: ``DB_TYPE`` for a DB (``DB5``, a DB's symbol),
    which a BLOCK_DB input takes (``sequencer.checks.user_calls``); E041 for a DB numbered
    outside 1..65535."""
    number = db_argument(e, ctx.chart, ctx.symbols)
    if number is None:
        return _type(ctx, e, el)
    if not 1 <= number <= 65535:
        ctx.err("E041", f"DB{number}: a DB is numbered 1..65535", _loc(e), el)
    return DB_TYPE


def _read_only(name: str, res: Resolved) -> str:
    """Why the chart cannot write ``name``: an FB output, or a peripheral input (PI)."""
    if res.kind == "member":
        return (
            f"DB{res.db}.{res.member} is a variable of an instance DB, which its block writes; "
            "the chart only reads it"
        )
    if res.address is not None:
        return f"{name} is a peripheral input, read by the program only; the chart cannot write it"
    return f"{name} is an FB output; the chart cannot write it"


def _check_assignment(ctx: _Ctx, a: Assignment, el: str, *, in_action: bool) -> None:
    res = _resolve(ctx, a.target, el)
    t = _type(ctx, a.expr, el)
    if res is None:
        return
    if not res.writable:
        ctx.err("E045", _read_only(a.target.name, res), a.target.loc, el)
        return
    target = _operand_type(res)
    if in_action and target == "BOOL":
        ctx.err(
            "E035",
            f"{a.target.name} := ... writes a bit: a coil belongs in the permanent "
            "instructions; in a step use N, S or R",
            a.target.loc,
            el,
        )
        return
    if t is not None and _unify(target, t) is None:
        ctx.err(
            "E031",
            f"cannot assign {_show(t)} to {a.target.name} ({_show(target)})",
            a.target.loc,
            el,
        )


# ---------------------------------------------------------------- permanent instructions


def rule_permanent_instructions(ctx: _Ctx) -> None:
    """Coils write bits from conditions; assignments are typed; calls name known operands."""
    for place, items in (("before", ctx.chart.before), ("after", ctx.chart.after)):
        el = f"permanent {place}"
        for it in items:
            if isinstance(it, Coil):
                res = _resolve(ctx, it.target, el)
                if res is not None and res.type != "BOOL":
                    ctx.err(
                        "E031",
                        f"a coil writes a bit; {it.target.name} is {res.type}",
                        it.target.loc,
                        el,
                    )
                elif res is not None and not res.writable:
                    ctx.err(
                        "E045",
                        _read_only(it.target.name, res),
                        it.target.loc,
                        el,
                    )
            elif isinstance(it, Assignment):
                _check_assignment(ctx, it, el, in_action=False)
            elif isinstance(it, BlockCall):
                _check_call(ctx, it, el)


def rule_instance_db_addresses(ctx: _Ctx) -> None:
    """An absolute address into an instance DB the chart knows (its own, or one of its
    calls': ``DB10.DBX6.0`` of ``CALL "TON", DB 10``) has no bytes to reach — such a DB
    holds its FB's variables by name — and stopped the CPU at its first call (E041): a
    call's output is read through its ``=>`` parameter instead; nor has such a DB bytes for
    a BLOCK_DB input to reach (``src := DB10``: E041). Run after the rows, whose calls name
    the instance DBs."""
    program = ctx.readable.instances if ctx.readable is not None else {}
    for site in call_sites(ctx.chart):
        for _, e in site.call.inputs:
            number = db_argument(e, ctx.chart, ctx.symbols)
            owner = ctx.instances.get(number) or program.get(number) if number else None
            if owner is not None and number is not None:
                why = f"{instance_db_passed(number, owner)}: pass a global DB"
                ctx.err("E041", why, _loc(e), site.element)
    seen: set[tuple[str, bool]] = set()
    for op in nodes(ctx.chart):
        if not isinstance(op, Operand) or op.member or (op.name, op.quoted) in seen:
            continue
        seen.add((op.name, op.quoted))
        try:
            res = resolve_operand(op, ctx.chart, ctx.symbols)
        except S7Error:
            continue  # said where the operand is checked
        db = res.address.db if res.address is not None else None
        owner = ctx.instances.get(db) if db is not None else None
        if owner is not None:
            ctx.err(
                "E041",
                f"{op.name}: DB{db} is the instance DB of {owner}; it holds its variables by "
                "name, not at byte addresses: take an output out with the call's => (Q => x)",
                op.loc,
            )
