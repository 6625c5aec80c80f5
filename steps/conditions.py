"""Conditions (transitions, interlocks, supervisions, permanent coils) → Python source
(docs/semantics.md, "Conditions" and "Decisions").

A condition is a boolean expression of *contacts*: an address / symbol / variable contact,
``Sn.X``, ``Tn.TT``, or a comparison box (``S3.U > T#10S`` is one contact). Every contact is
evaluated (no short circuit) so the criteria word is complete: bit ``k`` = truth of the
``k``-th contact in source order (max 32, CRIT/CRIT_LOC/CRIT_SUP, M-V5 15-9). The generated
function ``def name(st): ... return value, crit`` is compiled once with the whole chart.
"""

from __future__ import annotations

import re

from s7graph.steps.expressions import COMPARE, Resolve, StepIndex, expr_type, gen_value
from s7graph.steps.operands import CodeGen
from s7graph.steps.syntax import Binary, Const, Expr, Operand, StepAttr, TransAttr, Unary

MAX_CONTACTS = 32


def contacts(e: Expr | None, resolve: Resolve) -> list[Expr]:
    """The contacts of a condition in source order."""
    out: list[Expr] = []

    def walk(n: Expr) -> None:
        if isinstance(n, Unary) and n.op == "NOT":
            walk(n.operand)
        elif (
            isinstance(n, Binary)
            and n.op.upper() in ("AND", "OR", "XOR")
            and expr_type(n, resolve) == "BOOL"
        ):
            walk(n.left)
            walk(n.right)
        else:
            out.append(n)

    if e is not None:
        walk(e)
    return out


def contact_leaves(e: Expr | None) -> list[tuple[Expr, bool]]:
    """The contacts of a condition in source order, each with whether an odd number of NOTs
    inverts it (a normally closed contact). Walks every AND/OR/XOR below a BOOL root, which
    are BOOL, without recursion (a chain may be thousands long)."""
    out: list[tuple[Expr, bool]] = []
    todo: list[tuple[Expr, bool]] = [(e, False)] if e is not None else []
    while todo:
        n, negated = todo.pop()
        if isinstance(n, Unary) and n.op == "NOT":
            todo.append((n.operand, not negated))
        elif isinstance(n, Binary) and n.op.upper() in ("AND", "OR", "XOR"):
            todo += [(n.right, negated), (n.left, negated)]
        else:
            out.append((n, negated))
    return out


def contact_negations(e: Expr | None) -> list[bool]:
    """Per contact of ``contacts`` (same order): whether an odd number of NOTs inverts it
    (a normally closed contact); ``contact_leaves``' second half."""
    return [negated for _, negated in contact_leaves(e)]


def contact_text(e: Expr) -> str:
    """A short label of a contact (for criteria displays)."""
    if isinstance(e, Operand):
        text = f'"{e.name}"' if e.quoted else e.name
        return f"{text}.{e.member}" if e.member else text
    if isinstance(e, StepAttr):
        return f"S{e.step}.{e.attr}"
    if isinstance(e, TransAttr):
        return f"T{e.transition}.TT"
    if isinstance(e, Const):
        return e.text
    if isinstance(e, Binary) and e.op in COMPARE:
        return f"{contact_text(e.left)} {e.op} {contact_text(e.right)}"
    return type(e).__name__


def gen_condition(
    name: str,
    e: Expr | None,
    g: CodeGen,
    resolve: Resolve,
    sidx: StepIndex,
    tidx: StepIndex,
) -> str:
    """Source of ``def name(st) -> (bool, crit)``; an empty condition holds with crit 0."""
    return condition_source(name, condition_parts(e, g, resolve, sidx, tidx))


def condition_source(name: str, parts: tuple[list[str], str, str]) -> str:
    """``gen_condition`` from the ``condition_parts`` of the condition."""
    lines, value, crit = parts
    return with_locals([f"def {name}(st):", *lines, f"    return {value}, {crit}"])


def condition_parts(
    e: Expr | None,
    g: CodeGen,
    resolve: Resolve,
    sidx: StepIndex,
    tidx: StepIndex,
) -> tuple[list[str], str, str]:
    """The body of a condition (statements indented one level, binding ``c0``, ``c1``, …
    the contacts), its value expression and its criteria expression."""
    if e is None:
        return [], "True", "0"
    leaves = contacts(e, resolve)
    ids = {id(c): k for k, c in enumerate(leaves)}
    lines: list[str] = []
    for k, c in enumerate(leaves):
        src = gen_value(c, g, resolve, sidx, tidx)
        if isinstance(c, Binary) and c.op in COMPARE:  # a comparison is a bool already
            lines.append(f"    c{k} = {src}")
        else:
            lines.append(f"    c{k} = bool({src})")

    def combine(n: Expr) -> str:
        if id(n) in ids:
            return f"c{ids[id(n)]}"
        if isinstance(n, Unary):
            return f"(not {combine(n.operand)})"
        assert isinstance(n, Binary)
        op = n.op.upper()
        if op == "XOR":
            return f"({combine(n.left)} != {combine(n.right)})"
        return f"({combine(n.left)} {op.lower()} {combine(n.right)})"

    terms = [f"c{k} << {k}" if k else "c0" for k in range(min(len(leaves), 32))]
    crit = " | ".join(terms) if len(terms) > 1 else f"+{terms[0]}" if terms else "0"
    return lines, combine(e), f"({crit})"  # an int always: one contact's bool made 0 or 1


_USES_X = re.compile(r"(?<![\w.])X\[")
_USES_V = re.compile(r"(?<![\w.])V\[")


def with_locals(lines: list[str]) -> str:
    """The function of ``lines`` (header first) with the locals ``X = st.x`` and
    ``V = st.vars`` bound after the header when its body uses them."""
    body = "\n".join(lines[1:])
    head = [lines[0]]
    if _USES_X.search(body):
        head.append("    X = st.x")
    if _USES_V.search(body):
        head.append("    V = st.vars")
    return "\n".join(head) + "\n" + body + "\n"
