"""Stable references to the elements of a chart, and the element each diagnostic concerns.

A reference names an element the way S7-GRAPH does — by step, transition or sequencer
number, an action row by its step and index — so it stays valid across edits that do not
touch that element (the CPU, too, carries its state over by step number). ``label`` gives
the text the validator puts in ``Diagnostic.element`` (``step S2 row 3``); ``parse_label``
reads it back; ``element_of`` maps a diagnostic to its element, so that clicking a
diagnostic selects it in the editor. Row indices are 0-based here and 1-based in
diagnostics, as ``s7graph check`` prints them.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Final, Literal

from s7graph.engine.errors import SourceLocation
from s7graph.sequencer.checks.diagnostics import Diagnostic
from s7graph.sequencer.text.model import (
    ActionRow,
    Chart,
    Sequence,
    Step,
    StepAttr,
    StepTarget,
    SymbolDecl,
    TransAttr,
    Transition,
    VarDecl,
)
from s7graph.sequencer.text.walk import nodes

StepPart = Literal["", "interlock", "supervision"]
DeclKind = Literal["variable", "symbol", "permanent"]


@dataclass(frozen=True, slots=True)
class StepRef:
    """Step ``Sn``; ``part`` narrows it to its interlock or supervision."""

    number: int
    part: StepPart = ""


@dataclass(frozen=True, slots=True)
class RowRef:
    """Action row ``index`` (0-based) of step ``Sn``."""

    step: int
    index: int


@dataclass(frozen=True, slots=True)
class TransitionRef:
    number: int


@dataclass(frozen=True, slots=True)
class SequenceRef:
    number: int


@dataclass(frozen=True, slots=True)
class DeclRef:
    """An FB variable or a chart symbol by name, or the permanent instructions
    ``before`` / ``after`` the sequencers."""

    kind: DeclKind
    name: str


Ref = StepRef | RowRef | TransitionRef | SequenceRef | DeclRef
Element = Step | ActionRow | Transition | Sequence | VarDecl | SymbolDecl | tuple[object, ...]


def label(ref: Ref) -> str:
    """The element text of diagnostics: ``step S3``, ``step S3 interlock``,
    ``step S2 row 3``, ``transition T2``, ``sequence 1``, ``variable n``, ``symbol "X"``,
    ``permanent before``."""
    match ref:
        case StepRef(number=n, part=""):
            return f"step S{n}"
        case StepRef(number=n, part=part):
            return f"step S{n} {part}"
        case RowRef(step=n, index=i):
            return f"step S{n} row {i + 1}"
        case TransitionRef(number=n):
            return f"transition T{n}"
        case SequenceRef(number=n):
            return f"sequence {n}"
        case DeclRef(kind="symbol", name=name):
            return f'symbol "{name}"'
        case DeclRef(kind=kind, name=name):
            return f"{kind} {name}"
    raise TypeError(ref)  # pragma: no cover - Ref is closed


# One table: the element texts the validator writes, and the reference each one names.
_LABELS: Final[tuple[tuple[re.Pattern[str], Callable[[re.Match[str]], Ref]], ...]] = (
    (re.compile(r"step S(\d+) row (\d+)"), lambda m: RowRef(int(m[1]), int(m[2]) - 1)),
    (re.compile(r"step S(\d+) interlock"), lambda m: StepRef(int(m[1]), "interlock")),
    (re.compile(r"step S(\d+) supervision"), lambda m: StepRef(int(m[1]), "supervision")),
    (re.compile(r"step S(\d+)"), lambda m: StepRef(int(m[1]))),
    (re.compile(r"transition T(\d+)"), lambda m: TransitionRef(int(m[1]))),
    (re.compile(r"sequence (\d+)"), lambda m: SequenceRef(int(m[1]))),
    (re.compile(r'symbol "(.*)"'), lambda m: DeclRef("symbol", m[1])),
    (re.compile(r"variable (\w+)"), lambda m: DeclRef("variable", m[1])),
    (re.compile(r"permanent (before|after)"), lambda m: DeclRef("permanent", m[1])),
)


def parse_label(text: str) -> Ref | None:
    """The reference an element text names, or None (``""`` or an unknown text)."""
    for pattern, build in _LABELS:
        m = pattern.fullmatch(text)
        if m is not None:
            return build(m)
    return None


def find(chart: Chart, ref: Ref) -> Element | None:
    """The element ``ref`` names in ``chart``, or None when there is none."""
    match ref:
        case StepRef(number=n):
            return next((s for s in chart.all_steps() if s.number == n), None)
        case RowRef(step=n, index=i):
            step = next((s for s in chart.all_steps() if s.number == n), None)
            return step.actions[i] if step is not None and 0 <= i < len(step.actions) else None
        case TransitionRef(number=n):
            return next((t for t in chart.all_transitions() if t.number == n), None)
        case SequenceRef(number=n):
            return next((q for q in chart.sequences if q.number == n), None)
        case DeclRef(kind="variable", name=name):
            return next((v for v in chart.vars if v.name.upper() == name.upper()), None)
        case DeclRef(kind="symbol", name=name):
            return next((s for s in chart.symbols if s.name.casefold() == name.casefold()), None)
        case DeclRef(kind="permanent", name="before"):
            return chart.before
        case DeclRef(kind="permanent", name="after"):
            return chart.after
    return None


def owners(chart: Chart) -> Iterator[tuple[Ref, object]]:
    """Each part of ``chart`` that may name a step or transition, with its reference:
    interlocks, supervisions, action rows, conditions, permanent instructions."""
    for s in chart.all_steps():
        if s.interlock is not None:
            yield StepRef(s.number, "interlock"), s.interlock
        if s.supervision is not None:
            yield StepRef(s.number, "supervision"), s.supervision
        for i, r in enumerate(s.actions):
            yield RowRef(s.number, i), r
    for t in chart.all_transitions():
        if t.condition is not None:
            yield TransitionRef(t.number), t.condition
    yield DeclRef("permanent", "before"), chart.before
    yield DeclRef("permanent", "after"), chart.after


def references(chart: Chart) -> Iterator[tuple[Ref, StepRef | TransitionRef]]:
    """Every place that names a step or transition by number, and what it names: FROM / TO
    of transitions, ``ON`` / ``OFF Sn`` rows, ``Sn.X`` ``Sn.T`` ``Sn.U`` and ``Tn.TT``."""
    for t in chart.all_transitions():
        for n in (*t.sources, *t.targets):
            yield TransitionRef(t.number), StepRef(n)
    for owner, part in owners(chart):
        for x in nodes(part):
            if isinstance(x, StepAttr) or (isinstance(x, StepTarget) and x.step is not None):
                yield owner, StepRef(x.step)  # type: ignore[arg-type]
            elif isinstance(x, TransAttr):
                yield owner, TransitionRef(x.transition)


def _places(chart: Chart) -> Iterator[tuple[SourceLocation, Ref]]:
    """Where each element of ``chart`` starts (elements built by an edit have no place)."""
    for q in chart.sequences:
        yield q.loc, SequenceRef(q.number)
        for s in q.steps:
            yield s.loc, StepRef(s.number)
            if s.interlock_loc is not None:
                yield s.interlock_loc, StepRef(s.number, "interlock")
            if s.supervision_loc is not None:
                yield s.supervision_loc, StepRef(s.number, "supervision")
            for i, r in enumerate(s.actions):
                yield r.loc, RowRef(s.number, i)
        for t in q.transitions:
            yield t.loc, TransitionRef(t.number)
    for v in chart.vars:
        yield v.loc, DeclRef("variable", v.name)
    for sym in chart.symbols:
        yield sym.loc, DeclRef("symbol", sym.name)


def element_of(diagnostic: Diagnostic, chart: Chart | None = None) -> Ref | None:
    """The element ``diagnostic`` concerns: the one its ``element`` text names, else (a
    diagnostic without one, e.g. a duplicate variable or a limit) the element of ``chart``
    that starts last at or before its place — meaningful when ``chart`` was parsed from the
    text the diagnostic is located in. None when neither says."""
    ref = parse_label(diagnostic.element)
    if ref is not None or chart is None:
        return ref
    at = (diagnostic.loc.line, diagnostic.loc.col)
    best: tuple[tuple[int, int], Ref] | None = None
    for loc, r in _places(chart):
        key = (loc.line, loc.col)
        placed = loc.line > 0 and loc.file == diagnostic.loc.file and key <= at
        if placed and (best is None or key >= best[0]):
            best = (key, r)
    return best[1] if best is not None else None
