"""What a view draws of a chart beside its boxes and bars, as text: each step's action
table as S7-GRAPH shows it, and where each contact of a condition stands in its text.

:func:`action_rows` gives a step's rows — event, qualifier (``C`` appended when the row is
interlocked), operand, time or value — each with the name of the operand whose value the
CPU sends while the step is active (``web.bus.live``: the bit a row sets, the variable an
assignment writes, a timer's or counter's Q, ``Sn.X`` of a step an ``ON``/``OFF`` row
switches; none for a ``CALL``); :func:`permanent_rows` the chart's permanent instructions,
each with the operand it writes (none for a ``CALL``). :func:`contact_spans` writes a condition as
``condition_text`` does and says where each contact stands in that text, in CRIT bit
order (``steps.conditions.contacts``: bit ``k`` is the ``k``-th contact in source order), so
a view colours the contacts of the condition it draws from the CRIT bits of the last
evaluation. Plain tuples: ``web.bus.protocol`` makes its messages of them.
"""

from __future__ import annotations

import dataclasses
from typing import Literal, NamedTuple

from s7graph.sequencer.text.format import format_expr, format_permanent, row_body
from s7graph.sequencer.text.model import Chart
from s7graph.steps.conditions import MAX_CONTACTS, contact_leaves
from s7graph.steps.expressions import COMPARE
from s7graph.steps.syntax import (
    CHAIN_OPS,
    ActionRow,
    Assignment,
    Binary,
    BlockCall,
    Coil,
    Const,
    Expr,
    Operand,
    PermanentInstruction,
    StepAttr,
    StepTarget,
    TransAttr,
    Unary,
)

__all__ = [
    "ContactText",
    "PermanentText",
    "RowText",
    "action_rows",
    "coil_contacts",
    "contact_spans",
    "permanent_rows",
]

MAX_WATCH_NAME = 128  # the longest value name a state update carries


class RowText(NamedTuple):
    """One action row as the view draws it; ``watch``: the value to show beside it ("")."""

    event: str
    qualifier: str
    operand: str
    value: str
    watch: str


def action_rows(rows: tuple[ActionRow, ...]) -> list[RowText]:
    """A step's action rows, in their order."""
    return [
        RowText(
            event=r.event or "",
            qualifier=r.qualifier + ("C" if r.interlocked else ""),
            operand=row_body(dataclasses.replace(r, value=None)),
            value=format_expr(r.value) if r.value is not None else "",
            watch=_watched(r),
        )
        for r in rows
    ]


class ContactText(NamedTuple):
    """One contact of a permanent instruction's condition: as written (``NOT "Stop"``), the
    bit it reads (``Stop``, ``S2.X``, ``T1.TT``; "" for a comparison, whose truth the view
    cannot tell from one value), and whether a NOT inverts it (a normally closed contact)."""

    text: str
    watch: str
    negated: bool


class PermanentText(NamedTuple):
    """One permanent instruction as the view lists it: ``place`` ``before`` or ``after`` the
    sequences, its text as the chart file writes it, the operand it writes (""), whose
    value the CPU sends every scan, and the contacts of a coil (or of an assignment of a
    logic operation), whose bits it sends too."""

    place: Literal["before", "after"]
    text: str
    watch: str
    contacts: tuple[ContactText, ...] = ()


def permanent_rows(chart: Chart) -> list[PermanentText]:
    """The chart's permanent instructions before the sequences, then those after, in order."""
    before = [_permanent("before", p) for p in chart.before]
    return before + [_permanent("after", p) for p in chart.after]


def _permanent(place: Literal["before", "after"], p: PermanentInstruction) -> PermanentText:
    watch = "" if isinstance(p, BlockCall) else p.target.name
    contacts: tuple[ContactText, ...] = ()
    if isinstance(p, Coil):
        contacts = coil_contacts(p.condition)
    elif isinstance(p, Assignment) and _logic(p.expr):  # "x := a AND NOT b": a coil too
        contacts = coil_contacts(p.expr)
    watch = watch if len(watch) <= MAX_WATCH_NAME else ""
    return PermanentText(place, format_permanent(p), watch, contacts)


def coil_contacts(condition: Expr) -> tuple[ContactText, ...]:
    """The contacts of a coil's condition in order (at most ``MAX_CONTACTS``), each with the
    bit it reads and whether it is negated, as the criteria of a transition are counted
    (``steps.conditions.contact_leaves``)."""
    return tuple(
        ContactText(f"NOT {format_expr(e)}" if negated else format_expr(e), _bit(e), negated)
        for e, negated in contact_leaves(condition)[:MAX_CONTACTS]
    )


def _logic(e: Expr) -> bool:
    """Whether ``e`` is a logic operation (its root AND, OR, XOR or NOT)."""
    if isinstance(e, Unary):
        return e.op == "NOT"
    return isinstance(e, Binary) and e.op.upper() in _LOGIC


def _bit(e: Expr) -> str:
    """The name of the bit contact ``e`` reads ("" for any other contact)."""
    if isinstance(e, Operand):
        name = e.name
    elif isinstance(e, StepAttr) and e.attr == "X":
        name = f"S{e.step}.X"
    elif isinstance(e, TransAttr):
        name = f"T{e.transition}.TT"
    else:
        return ""
    return name if len(name) <= MAX_WATCH_NAME else ""


def _watched(r: ActionRow) -> str:
    op = r.operand
    if isinstance(op, Operand):
        name = op.name
    elif isinstance(op, Assignment):
        name = op.target.name
    elif isinstance(op, StepTarget) and op.step is not None:
        name = f"S{op.step}.X"
    else:  # a CALL, or OFF S_ALL
        name = ""
    return name if len(name) <= MAX_WATCH_NAME else ""


# Binding strength as the chart writer prints (sequencer.text.format): the logic operators,
# a comparison, NOT and a negative literal, a primary.
_LOGIC = {"OR": 1, "XOR": 2, "AND": 3}
_COMPARISON, _SHIFT, _UNARY, _PRIMARY = 4, 5, 8, 9


def _level(e: Expr) -> int:
    if isinstance(e, Binary):
        op = e.op.upper()
        return _LOGIC.get(op, _COMPARISON if e.op in COMPARE else _SHIFT)
    if isinstance(e, Unary) or (isinstance(e, Const) and e.text.startswith("-")):
        return _UNARY
    return _PRIMARY


def contact_spans(expr: Expr | None) -> tuple[str, list[tuple[int, int]]]:
    """``expr`` as text (``web.bus.protocol.condition_text`` writes the same) and the span
    ``(start, end)`` of each contact in it, in CRIT bit order (at most ``MAX_CONTACTS``)."""
    if expr is None:
        return "", []
    parts: list[str] = []
    spans: list[tuple[int, int]] = []
    at = [0]

    def put(text: str) -> None:
        parts.append(text)
        at[0] += len(text)

    def wrap(e: Expr, at_least: int) -> None:
        if _level(e) < at_least:
            put("(")
            walk(e)
            put(")")
        else:
            walk(e)

    def walk(e: Expr) -> None:
        if isinstance(e, Unary) and e.op == "NOT":
            put("NOT ")
            wrap(e.operand, _UNARY)
        elif isinstance(e, Binary) and e.op.upper() in _LOGIC:
            level = _LOGIC[e.op.upper()]
            chained = e.op in CHAIN_OPS and isinstance(e.right, Binary) and e.right.op == e.op
            wrap(e.left, level)
            put(f" {e.op} ")
            wrap(e.right, level if chained else level + 1)
        else:  # a contact: an operand, a step or transition attribute, a comparison
            start = at[0]
            put(format_expr(e, chains=True))
            spans.append((start, at[0]))

    walk(expr)
    return "".join(parts), spans[:MAX_CONTACTS]
