"""How a sequence is drawn, for the exporters: which transitions leave each step (in
written order; ``priority`` gives GRAPH's order of them), which reach a step going down
the chart, which are jumps.

A link from a transition to a step is a jump when the step is in another sequence, is an
initial step, or stands above (or level with) every step the transition leaves — as a
GRAPH editor draws it; and also when the transition opens a simultaneous branch into a
step other transitions already reach going down (a branch path cannot merge there).

Every step but the sequence's first and its initial steps hangs in the drawing: one that no
link reaches going down is reached by its first link from a single-target transition of
the sequence that closes no loop of direct links, drawn as a direct link although it leads
up. Otherwise such a step would stand alone, and other tools reading the drawing (a PLCopen
SFC) would take it for a chart of its own.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from s7graph.sequencer.text.model import Sequence

__all__ = ["Shape", "priority", "shape_of"]


def priority(leaving: list[int]) -> list[int]:
    """Transition numbers leaving one step (written order) in S7-GRAPH's priority: the first
    written (directly below the step), then the others by number, lowest first (manual 6-7)."""
    return leaving[:1] + sorted(leaving[1:])


@dataclass
class Shape:
    leaving: dict[int, list[int]] = field(default_factory=dict)  # step → transitions
    arriving: dict[int, list[int]] = field(default_factory=dict)  # step → transitions (down)
    jumps: set[tuple[int, int]] = field(default_factory=set)  # (transition, step)


def shape_of(q: Sequence) -> Shape:
    order = {s.number: i for i, s in enumerate(q.steps)}
    initial = {s.number for s in q.steps if s.initial}
    out = Shape()
    for t in q.transitions:
        for s in t.sources:
            out.leaving.setdefault(s, []).append(t.number)
    for t in q.transitions:
        above = min(order.get(s, -1) for s in t.sources)
        for d in t.targets:
            back = d not in order or d in initial or order[d] <= above
            if back or (len(t.targets) > 1 and out.arriving.get(d)):
                out.jumps.add((t.number, d))
            else:
                out.arriving.setdefault(d, []).append(t.number)
    _hang(q, out, initial)
    return out


def _hang(q: Sequence, out: Shape, initial: set[int]) -> None:
    """Give each step that no link reaches going down a direct link (module docstring)."""
    own = {s.number for s in q.steps}
    for s in q.steps[1:]:
        if s.number in initial or out.arriving.get(s.number):
            continue
        for t in q.transitions:
            if (
                t.targets == (s.number,)
                and (t.number, s.number) in out.jumps
                and set(t.sources) <= own
                and not _reaches(s.number, set(t.sources), q, out)
            ):
                out.jumps.discard((t.number, s.number))
                out.arriving.setdefault(s.number, []).append(t.number)
                break


def _reaches(start: int, goals: set[int], q: Sequence, out: Shape) -> bool:
    """Whether direct links lead from step ``start`` to one of ``goals``."""
    seen, todo = {start}, [start]
    while todo:
        step = todo.pop()
        if step in goals:
            return True
        for t in q.transitions:
            if step in t.sources:
                for d in t.targets:
                    if (t.number, d) not in out.jumps and d not in seen:
                        seen.add(d)
                        todo.append(d)
    return False
