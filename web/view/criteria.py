"""The criteria of the status view: the contacts of a condition coloured on the chart, as
S7-GRAPH's status display shows a transition's, an interlock's or a supervision's contacts
— fulfilled green, not fulfilled red — from the CRIT bits of the last evaluation.

A condition is drawn as its text (``web.view.drawing``); :func:`span_rects` finds where
each contact stands in the wrapped lines (one rectangle per line a contact covers), and
:func:`contact_states` reads from a state update which contacts pass: those of every valid
transition leaving an active step, and the interlock and supervision of every active step
(``StepDetail``). Keys: ``("T", transition)``, ``("C", step)``, ``("V", step)``.
"""

from __future__ import annotations

from s7graph.web.bus.protocol import StepStateUpdate
from s7graph.web.view.glyphs import LINE, text_width

__all__ = [
    "CONTACT_FAILS",
    "CONTACT_PASSES",
    "ConditionKey",
    "Rect",
    "contact_states",
    "span_rects",
]

Rgb = tuple[int, int, int]
CONTACT_PASSES: Rgb = (120, 215, 120)  # fulfilled: lets the condition through
CONTACT_FAILS: Rgb = (250, 150, 150)  # not fulfilled (both keep black text over 4.5:1)
ConditionKey = tuple[str, int]
Rect = tuple[float, float, float, float]  # cx, cy, w, h


def span_rects(
    lines: list[str],
    starts: list[int],
    spans: list[tuple[int, int]],
    left: float,
    top: float,
    size: float,
) -> tuple[tuple[Rect, ...], ...]:
    """Per contact span (in the text ``lines`` were wrapped from, ``starts`` where each line
    begins in it): a rectangle around each piece of the contact on a drawn line (lines from
    ``top`` down, ``size`` high, from ``left``); none for a contact on no drawn line."""
    pitch = size * LINE
    out = []
    for a, b in spans:
        rects = []
        for i, (line, start) in enumerate(zip(lines, starts, strict=True)):
            lo, hi = max(a, start), min(b, start + len(line))
            if lo >= hi:
                continue
            x0 = left + text_width(line[: lo - start], size) - 0.025
            x1 = left + text_width(line[: hi - start], size) + 0.025
            y1 = top - i * pitch
            rects.append(((x0 + x1) / 2, y1 - pitch / 2, x1 - x0, pitch))
        out.append(tuple(rects))
    return tuple(out)


def contact_states(update: StepStateUpdate | None) -> dict[ConditionKey, tuple[bool, ...]]:
    """Which contacts pass, per condition evaluated in ``update``'s scan."""
    states: dict[ConditionKey, tuple[bool, ...]] = {}
    if update is None:
        return states
    for d in update.details:
        if d.interlock:
            states[("C", d.number)] = tuple(c.ok for c in d.interlock)
        if d.supervision:
            states[("V", d.number)] = tuple(c.ok for c in d.supervision)
        for t in d.transitions:
            states[("T", t.number)] = tuple(c.ok for c in t.contacts)
    return states
