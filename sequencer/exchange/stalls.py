"""Steps an imported chart can never leave, found before anyone runs it.

A transition can never switch when its condition is FALSE whatever happens outside the FB:
every operand it reads is either a constant or an FB variable only the chart itself could
write — one the importer made (the output of an FB instance, a transition body's result),
one only a body kept for the SCL block writes, a constant without its value — that nothing
in the chart writes (no row, permanent instruction or call output), so it keeps its initial
value. The variables the source declared may be written from outside (an HMI, a caller),
and step attributes, symbols and addresses may change: a condition reading them is not
judged. A step whose every leaving transition can never switch is a stall: the import warns
(I025) at the step, for each initial step so stuck and for any other step the chart can
reach, saying which variables the conditions wait for and why nothing writes them (an
instance never called, a body kept for the SCL block).
"""

from __future__ import annotations

from collections.abc import Iterator

from s7graph.sequencer.exchange.problems import Problems
from s7graph.sequencer.text.model import (
    Assignment,
    Binary,
    BlockCall,
    Chart,
    Coil,
    Const,
    Expr,
    Operand,
    Step,
    Transition,
    Unary,
)

__all__ = ["report_stalls"]

_Value = bool | int | float | None  # None: not known before the chart runs


def _written(chart: Chart) -> set[str]:
    """The FB variables (upper case) the chart writes."""
    out: set[str] = set()
    for s in chart.all_steps():
        for r in s.actions:
            out.update(_writes(r.operand))
    for p in (*chart.before, *chart.after):
        out.update(_writes(p))
    return out


def _writes(op: object) -> list[str]:
    """What a row's operand or a permanent instruction writes (upper case)."""
    if isinstance(op, Operand):
        return [op.name.upper()]
    if isinstance(op, Assignment | Coil):
        return [op.target.name.upper()]
    if isinstance(op, BlockCall):
        return [o.name.upper() for _, o in op.outputs]
    return []


class _Judge:
    def __init__(self, chart: Chart, internal: set[str]) -> None:
        written = _written(chart)
        self.fixed: dict[str, _Value] = {}
        for v in chart.vars:
            key = v.name.upper()
            if key in written or key not in internal:
                continue
            init = v.init.value if v.init is not None else None
            if v.type == "BOOL":
                self.fixed[key] = bool(init)
            elif v.type in ("INT", "DINT", "BYTE", "WORD", "DWORD", "TIME", "REAL"):
                self.fixed[key] = init if isinstance(init, int | float) else 0

    def value(self, e: Expr) -> _Value:
        if isinstance(e, Const):
            v = e.value
            return v if isinstance(v, bool | int | float) else None
        if isinstance(e, Operand):
            return None if e.quoted else self.fixed.get(e.name.upper())
        if isinstance(e, Unary):
            inner = self.value(e.operand)
            if inner is None:
                return None
            return (not inner) if e.op == "NOT" and isinstance(inner, bool) else None
        if isinstance(e, Binary):
            return self.binary(e)
        return None

    def binary(self, e: Binary) -> _Value:
        left, right = self.value(e.left), self.value(e.right)
        if e.op == "AND" and False in (left, right):
            return False
        if e.op == "OR" and True in (left, right):
            return True
        if left is None or right is None:
            return None
        both_bool = isinstance(left, bool) and isinstance(right, bool)
        if e.op in ("AND", "OR", "XOR") and both_bool:
            return {"AND": left and right, "OR": left or right, "XOR": left != right}[e.op]
        compare = {
            "=": left == right,
            "<>": left != right,
            "<": left < right,
            ">": left > right,
            "<=": left <= right,
            ">=": left >= right,
        }
        return compare.get(e.op)

    def never(self, t: Transition) -> bool:
        return t.condition is not None and self.value(t.condition) is False

    def waits_for(self, e: Expr) -> Iterator[str]:
        """The fixed FB variables ``e`` reads."""
        if isinstance(e, Operand) and not e.quoted and e.name.upper() in self.fixed:
            yield e.name
        for child in (
            getattr(e, "left", None),
            getattr(e, "right", None),
            getattr(e, "operand", None),
        ):
            if child is not None:
                yield from self.waits_for(child)


def report_stalls(
    chart: Chart, problems: Problems, internal: set[str], why: dict[str, str]
) -> None:
    """Warn (I025) at each step the chart reaches and can never leave. ``internal``: the FB
    variables (upper case) only the chart could write; ``why``: for a variable (upper case)
    the reason nothing writes it (``an instance never called`` …)."""
    judge = _Judge(chart, internal)
    steps = {s.number: s for s in chart.all_steps()}
    leaving: dict[int, list[Transition]] = {}
    for t in chart.all_transitions():
        for src in t.sources:
            leaving.setdefault(src, []).append(t)
    reached = [s.number for s in chart.all_steps() if s.initial]
    seen = set(reached)
    while reached:
        number = reached.pop(0)
        outs = leaving.get(number, [])
        live = [t for t in outs if not judge.never(t)]
        if outs and not live:
            _warn(steps[number], outs, judge, problems, why)
        for t in live:
            for d in t.targets:
                if d not in seen:
                    seen.add(d)
                    reached.append(d)


def _warn(
    step: Step, outs: list[Transition], judge: _Judge, problems: Problems, why: dict[str, str]
) -> None:
    names: list[str] = []
    for t in outs:
        assert t.condition is not None
        names += [n for n in judge.waits_for(t.condition) if n not in names]
    reasons = "; ".join(
        f"{n} {why.get(n.upper(), 'is written by nothing in the chart')}" for n in names
    )
    which = "initial step" if step.initial else "step"
    label = f'S{step.number} "{step.name}"' if step.name else f"S{step.number}"
    trs = ", ".join(f"T{t.number}" for t in outs)
    never = "can never hold" if len(outs) == 1 else "can ever hold"
    head = f"{trs} {never}" if len(outs) == 1 else f"none of {trs} {never}"
    problems.warn(
        "I025",
        f"the chart cannot leave {which} {label}: {head} — "
        f"{reasons or 'their conditions are constant'}",
        step.loc,
    )
