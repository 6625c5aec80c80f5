"""Validation rules for the chart's structure (docs/semantics.md, "Structure";
docs/chart-format.md): numbers, declarations, FROM/TO, initial steps, ways in and out, limits and
joins."""

from __future__ import annotations

from typing import Final

from s7graph.engine.address import parse_address
from s7graph.engine.datatypes import string_chars
from s7graph.engine.errors import AddressError, LiteralError
from s7graph.engine.literals import parse_literal
from s7graph.sequencer.checks.context import _Ctx, _step_el
from s7graph.sequencer.checks.diagnostics import Diagnostic
from s7graph.sequencer.checks.types import LOGIC, _conditions, _show, _type, _unify
from s7graph.sequencer.text.model import Binary, Chart, Expr, Step, StepTarget, Transition, Unary
from s7graph.sequencer.text.names import db_symbol
from s7graph.steps.operands import TYPE_BYTES

# Limits that warn (docs/semantics.md, "Structure").
MAX_STEPS: Final = 250
MAX_TRANSITIONS: Final = 250
MAX_ALTERNATIVE_PATHS: Final = 125
MAX_SIMULTANEOUS_PATHS: Final = 249
MAX_SEQUENCES: Final = 8
MAX_CONDITION_ELEMENTS: Final = 32
MAX_MARKINGS: Final = 20_000  # state-space bound of the join analysis


def rule_duplicate_numbers(ctx: _Ctx) -> None:
    """Step and transition numbers are unique within the FB (E011, E012)."""
    seen_s: dict[int, Step] = {}
    for s in ctx.chart.all_steps():
        if s.number in seen_s:
            first = seen_s[s.number].loc
            ctx.err(
                "E011",
                f"step S{s.number} is defined twice (first at line {first.line})",
                s.loc,
                _step_el(s.number),
            )
        seen_s.setdefault(s.number, s)
    seen_t: dict[int, Transition] = {}
    for t in ctx.chart.all_transitions():
        if t.number in seen_t:
            first = seen_t[t.number].loc
            ctx.err(
                "E012",
                f"transition T{t.number} is defined twice (first at line {first.line})",
                t.loc,
                f"transition T{t.number}",
            )
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
    """The header's FB and DB numbers are block numbers, 1 to 65535 (E004); chart symbols
    name valid addresses or DBs (E041); a variable's initial value fits its type (E031)."""
    c = ctx.chart
    for kind, number in (("FB", c.fb_number), ("DB", c.db_number)):
        if number is not None and not 1 <= number <= 65535:
            ctx.err("E004", f"{kind} {number}: a block number is 1 to 65535", c.loc)
    for s in ctx.chart.symbols:
        db = db_symbol(s)
        if db is not None:
            if not 1 <= db <= 65535:
                where = f'symbol "{s.name}"'
                ctx.err("E041", f"DB {db}: a block number is 1 to 65535", s.loc, where)
            continue
        try:
            parse_address(s.address, s.loc)
        except AddressError as exc:
            ctx.err("E041", exc.message, s.loc, f'symbol "{s.name}"')
    for v in ctx.chart.vars:
        if (why := _bad_type(v.type)) is not None:
            ctx.err("E014", f"{v.name} : {v.type}: {why}", v.loc, f"variable {v.name}")
            continue
        if v.init is not None:
            t = _type(ctx, v.init, f"variable {v.name}")
            if t == "STRING" and v.type.upper() == "CHAR" and _one_char(v.init.text):
                t = "CHAR"  # 'A' is a CHAR constant (Program Design, appendix C)
            if t is not None and _unify(v.type.upper(), t) is None:
                ctx.err(
                    "E031",
                    f"initial value {v.init.text} ({_show(t)}) does not fit {v.name} : {v.type}",
                    v.init.loc,
                    f"variable {v.name}",
                )
            elif t == "STRING" and _too_long(v.type, v.init.text):
                ctx.err(
                    "E031",
                    f"initial value {v.init.text} is longer than {v.type} ({v.name})",
                    v.init.loc,
                    f"variable {v.name}",
                )


VAR_TYPES: Final = (*TYPE_BYTES, "DATE_AND_TIME")
"""The types an FB variable of a chart may have, beside STRING and STRING[n] (n ≤ 254): the
value types the chart's code reads and writes (``steps.operands.TYPE_BYTES``) and dates
and times."""


def _bad_type(type_name: str) -> str | None:
    """Why a chart's FB variable cannot have type ``type_name`` (None: it can)."""
    t = type_name.upper()
    if t in VAR_TYPES or t == "STRING":
        return None
    n = string_chars(t)
    if n is not None:
        return None if 1 <= n <= 254 else "a STRING holds 1 to 254 characters"
    if t == "DT":
        return "write DATE_AND_TIME"
    return f"a variable of a chart is one of {' '.join(VAR_TYPES)} or STRING[n]"


def _one_char(literal: str) -> bool:
    """Whether the literal ``literal`` is a string of one character: in S7, ``'A'`` also
    stands for the CHAR constant, so it initializes a CHAR variable."""
    try:
        _, value = parse_literal(literal)
    except LiteralError:
        return False
    return isinstance(value, str) and len(value) == 1


def _too_long(declared: str, literal: str) -> bool:
    """Whether the STRING literal ``literal`` has more characters than ``STRING[n]``."""
    n = string_chars(declared)
    if n is None:
        return False
    try:
        _, value = parse_literal(literal)
    except LiteralError:
        return False
    return isinstance(value, str) and len(value) > n


def rule_unknown_steps_in_from_to(ctx: _Ctx) -> None:
    """Every step named in FROM / TO exists in the FB (E010); the column is the step's own."""
    for t in ctx.chart.all_transitions():
        for part, numbers, locs in (
            ("FROM", t.sources, t.source_locs),
            ("TO", t.targets, t.target_locs),
        ):
            for i, n in enumerate(numbers):
                if n not in ctx.steps:
                    loc = locs[i] if i < len(locs) else t.loc
                    ctx.err("E010", f"unknown step S{n} in {part}", loc, f"transition T{t.number}")


def rule_branches_in_one_sequence(ctx: _Ctx) -> None:
    """A simultaneous branch or join stays in one sequence (E015): a sequencer's steps are
    joined and forked only among themselves; only a jump (one step to one step) reaches
    another sequencer (S7-GRAPH manual 6-4)."""
    home = {s.number: q.number for q in ctx.chart.sequences for s in q.steps}
    for t in ctx.chart.all_transitions():
        if len(t.sources) < 2 and len(t.targets) < 2:
            continue
        seqs = {home[n] for n in (*t.sources, *t.targets) if n in home}
        if len(seqs) > 1:
            steps = ", ".join(
                f"S{n} in sequence {home[n]}" for n in (*t.sources, *t.targets) if n in home
            )
            ctx.err(
                "E015",
                f"a simultaneous branch joins or forks steps of different sequences ({steps}); "
                "only a jump to one step reaches another sequence",
                t.loc,
                f"transition T{t.number}",
            )


def rule_initial_steps(ctx: _Ctx) -> None:
    """Each sequencer has at least one initial step, else it never starts (W103)."""
    for seq in ctx.chart.sequences:
        if seq.steps and not any(s.initial for s in seq.steps):
            ctx.warn(
                "W103",
                f"sequence {seq.number} has no initial step; it starts only by ON or MAN mode",
                seq.loc,
                f"sequence {seq.number}",
            )


def initial_step_warnings(chart: Chart) -> list[Diagnostic]:
    """W103 for each sequence of ``chart`` without an initial step (an importer reports it
    at once, in ``check``'s words)."""
    ctx = _Ctx(chart, None)
    rule_initial_steps(ctx)
    return ctx.diags


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
            ctx.warn(
                "W101",
                f"no transition leads to step S{s.number}; it can never become active",
                s.loc,
                _step_el(s.number),
            )
        if s.number not in out:
            ctx.warn(
                "W102",
                f"no transition leaves step S{s.number}; once active it stays active",
                s.loc,
                _step_el(s.number),
            )


def rule_limits(ctx: _Ctx) -> None:
    """The limits of docs/semantics.md, "Structure" warn (W110)."""
    c = ctx.chart
    steps, trans = c.all_steps(), c.all_transitions()
    if len(c.sequences) > MAX_SEQUENCES:
        ctx.warn(
            "W110",
            f"{len(c.sequences)} sequencers; S7-GRAPH allows {MAX_SEQUENCES}",
            c.sequences[MAX_SEQUENCES].loc,
        )
    if len(steps) > MAX_STEPS:
        ctx.warn("W110", f"{len(steps)} steps; S7-GRAPH allows {MAX_STEPS}", steps[MAX_STEPS].loc)
    if len(trans) > MAX_TRANSITIONS:
        ctx.warn(
            "W110",
            f"{len(trans)} transitions; S7-GRAPH allows {MAX_TRANSITIONS}",
            trans[MAX_TRANSITIONS].loc,
        )
    leaving: dict[int, list[Transition]] = {}
    for t in trans:
        for n in t.sources:
            leaving.setdefault(n, []).append(t)
        paths = max(len(t.sources), len(t.targets))
        if paths > MAX_SIMULTANEOUS_PATHS:
            ctx.warn(
                "W110",
                f"{paths} simultaneous paths; S7-GRAPH allows {MAX_SIMULTANEOUS_PATHS}",
                t.loc,
                f"transition T{t.number}",
            )
    for n, ts in leaving.items():
        if len(ts) > MAX_ALTERNATIVE_PATHS:
            msg = f"{len(ts)} alternative paths leave S{n}; S7-GRAPH allows {MAX_ALTERNATIVE_PATHS}"
            ctx.warn("W110", msg, ts[MAX_ALTERNATIVE_PATHS].loc, _step_el(n))
    for expr, loc, el in _conditions(ctx):
        k = _elements(expr)
        if k > MAX_CONDITION_ELEMENTS:
            ctx.warn(
                "W110",
                f"condition has {k} elements; S7-GRAPH allows {MAX_CONDITION_ELEMENTS}",
                loc,
                el,
            )


def _elements(e: Expr) -> int:
    """Contacts and comparators of a condition (each is one CRIT bit)."""
    if isinstance(e, Binary) and e.op in LOGIC:
        return _elements(e.left) + _elements(e.right)
    if isinstance(e, Unary) and e.op == "NOT":
        return _elements(e.operand)
    return 1


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
            ctx.warn(
                "W130",
                f"steps {names} are never active together: transition T{t.number} can never switch",
                t.loc,
                f"transition T{t.number}",
            )
