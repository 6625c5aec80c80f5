"""Write the chart model back as `.s7g` source text (docs/chart-format.md).

``format_chart(chart)`` is the inverse of ``sequencer.text.parse.parse_chart``: for every chart
the parser builds, ``parse_chart(format_chart(c))`` equals ``c`` once source places are set
aside (``walk.unlocated``). Comments are kept with their elements (``sequencer.text.comments``)
and written where they stood: on lines of their own above an element, or at the end of its
first line (a trailing comment, a symbol's too).
The layout is the one of the examples: header and options, ``VAR``, ``SYMBOLS``,
``PERMANENT BEFORE``, the sequences (all steps, then all transitions, in model order — the
first written transition leaving a step has priority, the others go by number), ``PERMANENT AFTER``.

Expressions are written with the fewest parentheses the grammar's precedence needs
(``OR`` < ``XOR`` < ``AND`` < comparison < shift < ``+ -`` < ``* / MOD`` < ``NOT``/``-``);
a comparison's sides are never comparisons. Options are written when they differ from
their default, ``PARAMETERS`` always.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TypeVar

from s7graph.sequencer.text.comments import find_comments
from s7graph.sequencer.text.model import (
    ActionRow,
    Assignment,
    Binary,
    BlockCall,
    Chart,
    ChartOptions,
    Coil,
    Const,
    Expr,
    FuncCall,
    Operand,
    PermanentInstruction,
    Sequence,
    Step,
    StepAttr,
    StepTarget,
    SymbolDecl,
    TransAttr,
    Transition,
    Unary,
    VarDecl,
)
from s7graph.steps.syntax import CHAIN_OPS

__all__ = ["format_chart", "format_expr", "format_permanent", "format_row", "quote", "row_body"]

T = TypeVar("T")

# Binding strength of each binary operator (higher binds tighter), as in grammar.lark.
_LEVEL: dict[str, int] = {
    "OR": 1,
    "XOR": 2,
    "AND": 3,
    **{op: 4 for op in ("=", "<>", "<", ">", "<=", ">=")},
    **{op: 5 for op in ("SHL", "SHR", "SSR", "ROL", "ROR")},
    "+": 6,
    "-": 6,
    "*": 7,
    "/": 7,
    "MOD": 7,
}
_UNARY = 8
_PRIMARY = 9
_COMPARISON = 4


def quote(name: str) -> str:
    """A double-quoted name; a quote inside is doubled (``"a""b"``)."""
    return '"' + name.replace('"', '""') + '"'


def _level(e: Expr) -> int:
    if isinstance(e, Binary):
        return _LEVEL.get(e.op, _PRIMARY)
    if isinstance(e, Unary):
        return _UNARY
    if isinstance(e, Const) and e.text.startswith("-"):
        return _UNARY  # a folded negative literal reads as '-' applied to the literal
    return _PRIMARY


def format_expr(
    e: Expr, operand: Callable[[Expr], str | None] | None = None, *, chains: bool = False
) -> str:
    """An expression in `.s7g` syntax; ``operand`` may spell operands, constants and
    step attributes another way (a TIA action's text), returning None to keep ours.
    ``chains`` writes a chain of one associative operator (``a AND (b AND c)``, the
    balanced shape the parser builds) without its inner parentheses, for a reader
    (``web.bus.protocol.condition_text``); the text then parses to an equal condition,
    not necessarily to the same tree."""
    if operand is not None and not isinstance(e, Binary | Unary | FuncCall):
        spelled = operand(e)
        if spelled is not None:
            return spelled
    if isinstance(e, Const):
        return e.text or str(e.value)
    if isinstance(e, Operand):
        text = quote(e.name) if e.quoted else e.name
        return f"{text}.{e.member}" if e.member else text  # DB10.Q, "T_S2".Q
    if isinstance(e, StepAttr):
        return f"S{e.step}.{e.attr}"
    if isinstance(e, TransAttr):
        return f"T{e.transition}.TT"
    if isinstance(e, FuncCall):
        return f"{e.name}({', '.join(format_expr(a, operand, chains=chains) for a in e.args)})"
    if isinstance(e, Unary):
        inner = _wrap(e.operand, _UNARY, operand, chains)
        return f"NOT {inner}" if e.op == "NOT" else f"-{inner}"
    level = _LEVEL[e.op]
    if level == _COMPARISON:  # comparison sides are shift expressions
        left = _wrap(e.left, level + 1, operand, chains)
        right = _wrap(e.right, level + 1, operand, chains)
    else:  # left-associative (a chain's right part, when ``chains``, needs no parentheses)
        chained = (
            chains and e.op in CHAIN_OPS and isinstance(e.right, Binary) and e.right.op == e.op
        )
        left = _wrap(e.left, level, operand, chains)
        right = _wrap(e.right, level if chained else level + 1, operand, chains)
    return f"{left} {e.op} {right}"


def _wrap(
    e: Expr, at_least: int, operand: Callable[[Expr], str | None] | None, chains: bool
) -> str:
    text = format_expr(e, operand, chains=chains)
    return text if _level(e) >= at_least else f"({text})"


# ---------------------------------------------------------------- rows and instructions


def _call(c: BlockCall) -> str:
    block = f"{c.kind} {c.block}" if c.kind else quote(str(c.block))
    text = block
    if c.instance is not None:
        inst = f"DB {c.instance}" if isinstance(c.instance, int) else quote(c.instance)
        text += f", {inst}"
    params = [f"{n} := {format_expr(v)}" for n, v in c.inputs]
    params += [f"{n} => {format_expr(o)}" for n, o in c.outputs]
    if params:
        text += f" ({', '.join(params)})"
    return text


def format_row(r: ActionRow) -> str:
    """One action row ``[event] qualifier[C] operand [, value];``."""
    head = f"{r.event} " if r.event else ""
    head += r.qualifier + ("C" if r.interlocked else "")
    return f"{head} {row_body(r)};"


def row_body(r: ActionRow, operand: Callable[[Expr], str | None] | None = None) -> str:
    """A row without its event and qualifier: ``operand [, value]``."""
    op = r.operand
    if isinstance(op, Assignment):
        body = f"{format_expr(op.target, operand)} := {format_expr(op.expr, operand)}"
    elif isinstance(op, BlockCall):
        body = _call(op)
    elif isinstance(op, StepTarget):
        body = "S_ALL" if op.step is None else f"S{op.step}"
    else:
        body = format_expr(op, operand)
    if r.value is not None:
        body += f", {format_expr(r.value, operand)}"
    return body


def format_permanent(p: PermanentInstruction) -> str:
    """A permanent instruction as the chart file writes it (``S "Lamp" := "Fault";``)."""
    if isinstance(p, Coil):
        kind = "" if p.kind == "=" else f"{p.kind} "
        return f"{kind}{format_expr(p.target)} := {format_expr(p.condition)};"
    if isinstance(p, Assignment):
        return f"{format_expr(p.target)} := {format_expr(p.expr)};"
    return f"CALL {_call(p)};"


# ---------------------------------------------------------------- structure


def _options(o: ChartOptions) -> list[str]:
    default = ChartOptions()
    out = [f"  PARAMETERS := {o.parameters};"]
    flags = [
        ("SKIP_STEPS", o.skip_steps, default.skip_steps),
        ("ACK_REQUIRED", o.ack_required, default.ack_required),
        ("MESSAGES", o.messages, default.messages),
        ("ACK_FORCES_SWITCH", o.ack_forces_switch, default.ack_forces_switch),
    ]
    out += [f"  {key} := {'TRUE' if v else 'FALSE'};" for key, v, d in flags if v != d]
    if o.order != default.order:
        out.append(f"  ORDER := {o.order.upper()};")
    return out


def _above(comment: str, indent: str) -> list[str]:
    """An element's comments (``sequencer.text.comments``), one after the other on lines of their
    own at ``indent``; a block comment's inner lines as written."""
    return [indent + c.text for c in find_comments(comment)] if comment else []


def _after(trailing: str) -> str:
    """An element's trailing comments, at the end of its first line as written (a ``//``
    comment can only be the last on its line)."""
    return "".join(" " + c.text for c in find_comments(trailing)) if trailing else ""


def _var(v: VarDecl) -> list[str]:
    init = f" := {v.init.text}" if v.init is not None else ""
    return [*_above(v.comment, "  "), f"  {v.name} : {v.type}{init};{_after(v.trailing)}"]


def _symbol(s: SymbolDecl) -> str:
    comment = f"  // {s.comment}" if s.comment else ""
    return f"  {quote(s.name)} : {s.address} : {s.type};{comment}"


def _step(s: Step) -> list[str]:
    kw = "INITIAL_STEP" if s.initial else "STEP"
    names = ""
    if s.name or s.message:
        names = f" {quote(s.name)}" + (f" {quote(s.message)}" if s.message else "")
    out = [*_above(s.comment, "  "), f"  {kw} S{s.number}{names}:{_after(s.trailing)}"]
    if s.interlock is not None:
        out.append(f"    INTERLOCK := {format_expr(s.interlock)};")
    if s.supervision is not None:
        out.append(f"    SUPERVISION := {format_expr(s.supervision)};")
    for r in s.actions:
        out += [*_above(r.comment, "    "), f"    {format_row(r)}{_after(r.trailing)}"]
    out.append("  END_STEP")
    return out


def _steps(numbers: tuple[int, ...]) -> str:
    refs = [f"S{n}" for n in numbers]
    return refs[0] if len(refs) == 1 else f"({', '.join(refs)})"


def _transition(t: Transition) -> list[str]:
    name = f" {quote(t.name)}" if t.name else ""
    to = _steps(t.targets) if t.targets else "STOP"
    cond = f" := {format_expr(t.condition)}" if t.condition is not None else ""
    line = f"  TRANSITION T{t.number}{name} FROM {_steps(t.sources)} TO {to}{cond};"
    return [*_above(t.comment, "  "), line + _after(t.trailing)]


def _sequence(q: Sequence) -> list[str]:
    name = f" {quote(q.name)}" if q.name else ""
    out = [*_above(q.comment, ""), f"SEQUENCE {q.number}{name}{_after(q.trailing)}"]
    for s in q.steps:
        out += _step(s)
    for t in q.transitions:
        out += _transition(t)
    out.append("END_SEQUENCE")
    return out


def format_chart(chart: Chart, header: str = "") -> str:
    """The `.s7g` text of ``chart``; ``header`` (a comment, without its markers) goes first."""
    out: list[str] = []
    if header:
        out.append("(* " + header.replace("*)", "* )") + " *)")
    out += _above(chart.comment, "")
    head = f"FUNCTION_BLOCK {quote(chart.name)}"
    if chart.fb_number is not None:
        head += f" FB {chart.fb_number}"
    if chart.db_number is not None:
        head += f" DB {chart.db_number}"
    out.append(head + _after(chart.trailing))
    out += _options(chart.options)
    if chart.vars:
        out += ["VAR", *(line for v in chart.vars for line in _var(v)), "END_VAR"]
    if chart.symbols:
        out += ["SYMBOLS", *(_symbol(s) for s in chart.symbols), "END_SYMBOLS"]
    for place, items in (("BEFORE", chart.before), ("AFTER", chart.after)):
        if items and place == "BEFORE":
            out += [
                "PERMANENT BEFORE",
                *(f"  {format_permanent(p)}" for p in items),
                "END_PERMANENT",
            ]
    for q in chart.sequences:
        out += _sequence(q)
    if chart.after:
        out += [
            "PERMANENT AFTER",
            *(f"  {format_permanent(p)}" for p in chart.after),
            "END_PERMANENT",
        ]
    out.append("END_FUNCTION_BLOCK")
    out += _above(chart.end_comment, "")
    return "\n".join(out) + "\n"
