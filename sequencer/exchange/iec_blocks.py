"""The IEC 61131-3 bistables and edge detectors (R_TRIG, F_TRIG, SR, RS) as GRAPH bit
assignments: the body of each as IEC 61131-3 ed.2 gives it and matiec's standard library
(``lib/edge_detection.txt``, ``lib/bistable.txt``) defines it, written on FB variables that
hold the instance's state. Their state starts FALSE, as matiec's does: so an F_TRIG whose
CLK is FALSE in its first call gives Q in that call.

The CPU has no system blocks for them (its system blocks are the IEC timers and counters),
and GRAPH writes a bit from a condition only in a permanent instruction; so a call
``E1(CLK := x)`` is the assignments::

    R_TRIG  Q := CLK AND NOT M;   M := CLK;
    F_TRIG  Q := NOT CLK AND NOT M;   M := NOT CLK;
    SR      Q1 := S1 OR NOT R AND Q1;
    RS      Q1 := NOT R1 AND (S OR Q1);

on the FB variables ``E1_Q``, ``E1_M`` (``E1_Q1``), which a read of ``E1.Q`` names. An input
left out is FALSE (its IEC default); CODESYS spells the bistables' inputs ``SET1``/``RESET``
and ``SET``/``RESET1``. An input that is not a plain operand is first copied to ``E1_CLK``
(``E1_S1`` …), so that it is read once, as in the FB. The caller places them: gated by the
step in an action (PERMANENT AFTER), as they are in the POU body or the chart's network.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Final

from s7graph.engine.errors import SourceLocation
from s7graph.sequencer.text.model import Binary, Const, Expr, Operand, StepAttr, Unary

__all__ = ["EDGE_AND_LATCH", "bistable_body"]

# FB type → (inputs (IEC name, other spellings), outputs)
EDGE_AND_LATCH: Final[dict[str, tuple[tuple[tuple[str, ...], ...], tuple[str, ...]]]] = {
    "R_TRIG": ((("CLK",),), ("Q",)),
    "F_TRIG": ((("CLK",),), ("Q",)),
    "SR": ((("S1", "SET1"), ("R", "RESET")), ("Q1",)),
    "RS": ((("S", "SET"), ("R1", "RESET1")), ("Q1",)),
}

Helper = Callable[[str, str], str]  # (name, type) → the FB variable's name in the chart


def _plain(e: Expr) -> bool:
    if isinstance(e, Unary) and e.op == "NOT":
        return _plain(e.operand)
    return isinstance(e, Const | Operand | StepAttr)


def bistable_body(
    fb_type: str,
    name: str,
    given: dict[str, Expr],
    helper: Helper,
    loc: SourceLocation,
) -> list[tuple[Operand, Expr]]:
    """The assignments of one call of instance ``name`` : ``fb_type`` with the inputs
    ``given`` (upper-case pin → value; checked by the caller against ``EDGE_AND_LATCH``), in
    the order they run; ``helper`` declares an FB variable of the importer."""
    pins, _ = EDGE_AND_LATCH[fb_type]
    out: list[tuple[Operand, Expr]] = []
    value: dict[str, Expr] = {}
    for spellings in pins:
        found = next((given[p] for p in spellings if p in given), None)
        if found is None:
            found = Const(False, "BOOL", "FALSE", loc)
        elif not _plain(found):
            copy = Operand(helper(f"{name}_{spellings[0]}", "BOOL"), False, loc)
            out.append((copy, found))
            found = copy
        value[spellings[0]] = found

    def var(member: str) -> Operand:
        return Operand(helper(f"{name}_{member}", "BOOL"), False, loc)

    def no(e: Expr) -> Expr:
        return Unary("NOT", e, loc)

    def both(a: Expr, b: Expr) -> Expr:
        return Binary("AND", a, b, loc)

    if fb_type == "R_TRIG":
        clk, q, m = value["CLK"], var("Q"), var("M")
        out += [(q, both(clk, no(m))), (m, clk)]
    elif fb_type == "F_TRIG":
        clk, q, m = value["CLK"], var("Q"), var("M")
        out += [(q, both(no(clk), no(m))), (m, no(clk))]
    elif fb_type == "SR":
        q1 = var("Q1")
        out.append((q1, Binary("OR", value["S1"], both(no(value["R"]), q1), loc)))
    else:  # RS
        q1 = var("Q1")
        out.append((q1, both(no(value["R1"]), Binary("OR", value["S"], q1, loc))))
    return out
