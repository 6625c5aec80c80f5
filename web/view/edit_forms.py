"""What the editor's side panel offers for a selection, read off the one table of edit
operations (``sequencer.change.edit.OPERATIONS``): every operation acting on the selected kind of
element, with the fields its arguments need.

An operation that sets one property of the element (its name, number, condition …) is a
*property*: one field showing the current value, applied when it changes. Any other
operation is an *action*: a field per argument and a button with the operation's title
(S7-GRAPH's wording). Action rows get a row editor of their own (event, qualifier, C,
operand, time/value). ``CURRENT`` is the table of how a property's current value is read;
everything else comes from ``OPERATIONS``.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Iterable
from dataclasses import dataclass, replace
from typing import Final

from s7graph.sequencer.change.edit import OPERATIONS, Argument, Operation
from s7graph.sequencer.change.typed import RowFields
from s7graph.sequencer.text.elements import Ref, RowRef, SequenceRef, StepRef, TransitionRef, find
from s7graph.sequencer.text.format import format_expr, quote, row_body
from s7graph.sequencer.text.model import ActionRow, Chart, Expr, Sequence, Step, Transition

__all__ = [
    "CURRENT",
    "DEBOUNCE_S",
    "Field",
    "Form",
    "completed",
    "completions",
    "element_choices",
    "form_for",
    "kind_of",
    "names_for",
    "row_fields",
]


def _expr(e: Expr | None) -> str:
    return "" if e is None else format_expr(e)


def _step(f: Callable[[Step], object]) -> Callable[[object], object]:
    return lambda x: f(x) if isinstance(x, Step) else None


def _transition(f: Callable[[Transition], object]) -> Callable[[object], object]:
    return lambda x: f(x) if isinstance(x, Transition) else None


DEBOUNCE_S: Final = 0.6  # typing pauses this long: the text is applied

# How the current value of a property operation's one argument is read from its element.
CURRENT: Final[dict[str, Callable[[object], object]]] = {
    "rename_step": _step(lambda s: s.name),
    "renumber_step": _step(lambda s: s.number),
    "set_initial": _step(lambda s: s.initial),
    "set_message": _step(lambda s: s.message),
    "set_interlock": _step(lambda s: _expr(s.interlock)),
    "set_supervision": _step(lambda s: _expr(s.supervision)),
    "rename_transition": _transition(lambda t: t.name),
    "renumber_transition": _transition(lambda t: t.number),
    "set_condition": _transition(lambda t: _expr(t.condition)),
    "rename_sequence": lambda q: q.name if isinstance(q, Sequence) else None,
}
# Operations the panel shows elsewhere: the source view, and the row editor.
ELSEWHERE: Final = frozenset({"set_source", "add_row", "change_row", "remove_row", "move_row"})


@dataclass(frozen=True, slots=True)
class Field:
    """One input: the operation's argument ``arg`` with its current or default value."""

    op: Operation
    arg: Argument
    value: object

    @property
    def label(self) -> str:
        return self.op.title if self.op.name in CURRENT else self.arg.name

    @property
    def hint(self) -> str:
        if self.arg.type == "int | None":
            return self.op.hint.removesuffix(".") + " (0: none, a branch stop)."
        return self.op.hint


@dataclass(frozen=True, slots=True)
class Form:
    """The panel's form for one selection: properties, then actions (each a list of
    fields and its button), and whether the row editor belongs to it."""

    ref: Ref | None
    properties: tuple[Field, ...]
    actions: tuple[tuple[Operation, tuple[Field, ...]], ...]
    rows: bool

    @property
    def key(self) -> tuple[object, ...]:
        """What the form's shape depends on (the same key: update values in place)."""
        return (
            type(self.ref).__name__,
            getattr(self.ref, "number", getattr(self.ref, "step", None)),
            tuple(f.op.name for f in self.properties),
            tuple((op.name, len(fs)) for op, fs in self.actions),
            self.rows,
        )


def kind_of(ref: Ref | None) -> str:
    """The kind of element a selection names: step, transition, sequence or chart."""
    if isinstance(ref, StepRef | RowRef):
        return "step"
    if isinstance(ref, TransitionRef):
        return "transition"
    if isinstance(ref, SequenceRef):
        return "sequence"
    return "chart"


def _element(chart: Chart, ref: Ref | None) -> object:
    if isinstance(ref, RowRef):
        ref = StepRef(ref.step)
    if isinstance(ref, StepRef) and ref.part:
        ref = StepRef(ref.number)
    return find(chart, ref) if ref is not None else chart


def _default(arg: Argument, element: object) -> object:
    """A starting value for an action's argument: its default (None shows as 0), else the
    element's own number or first target, else nothing."""
    if not arg.required:
        return 0 if arg.default is None else arg.default
    if arg.type.startswith("int"):
        if isinstance(element, Transition):
            return element.targets[0] if element.targets else 1
        return element.number if isinstance(element, Step) else 1
    return False if arg.type == "bool" else ""


def form_for(chart: Chart, ref: Ref | None) -> Form:
    """The form of the selection ``ref`` (None: the chart) of ``chart``."""
    kind = kind_of(ref)
    element = _element(chart, ref)
    target: Ref | None = ref
    if kind == "chart":
        target = None
    elif isinstance(element, Step):
        target = StepRef(element.number)
    properties: list[Field] = []
    actions: list[tuple[Operation, tuple[Field, ...]]] = []
    for op in OPERATIONS:
        if op.target != kind or op.name in ELSEWHERE:
            continue
        args = [a for a in op.arguments if a.name not in op.element_arguments]
        if op.name in CURRENT and len(args) == 1:
            properties.append(Field(op, args[0], CURRENT[op.name](element)))
        else:
            fields = tuple(Field(op, a, _default(a, element)) for a in args)
            actions.append((op, fields))
    return Form(target, tuple(properties), tuple(actions), kind == "step")


def row_fields(row: ActionRow) -> RowFields:
    """The editor's fields of an action row (the inverse of ``parse_row``)."""
    value = "" if row.value is None else format_expr(row.value)
    return RowFields(
        qualifier=row.qualifier,
        operand=row_body(replace(row, value=None)),
        event=row.event or "",
        interlocked=row.interlocked,
        value=value,
    )


def element_choices(chart: Chart) -> list[tuple[str, Ref | None]]:
    """The selection dropdown: the chart, each sequencer, step and transition, in order."""
    out: list[tuple[str, Ref | None]] = [("Chart (block options, new sequencer)", None)]
    for q in chart.sequences:
        out.append((f"Sequencer {q.number} {q.name}".rstrip(), SequenceRef(q.number)))
        out += [(f"S{s.number} {s.name}".rstrip(), StepRef(s.number)) for s in q.steps]
        out += [(f"T{t.number} {t.name}".rstrip(), TransitionRef(t.number)) for t in q.transitions]
    return out


# ---------------------------------------------------------------- completing names

MAX_COMPLETIONS: Final = 40  # names a completion list offers at once
EXPRESSIONS: Final = frozenset({"set_condition", "set_interlock", "set_supervision"})
_PLAIN: Final = re.compile(r"[A-Za-z_][A-Za-z0-9_]*(\.[A-Za-z_][A-Za-z0-9_]*)?")
_WORD: Final = re.compile(r'("[^"]*|[A-Za-z0-9_.#]*)$')


def names_for(chart: Chart, symbols: Iterable[str] = ()) -> list[str]:
    """The names a condition may read, as it writes them: the symbols (of the symbol
    table and of the chart), the chart's variables, and each step's and transition's
    flags (``S2.X``, ``S2.T``, ``T1.TT``); a name that is not a plain word is quoted."""
    out: list[str] = []
    for name in [*symbols, *(d.name for d in chart.symbols), *(v.name for v in chart.vars)]:
        out.append(name if _PLAIN.fullmatch(name) else quote(name))
    for q in chart.sequences:
        for s in q.steps:
            out += [f"S{s.number}.X", f"S{s.number}.T"]
        out += [f"T{t.number}.TT" for t in q.transitions]
    return list(dict.fromkeys(out))


def completions(names: Iterable[str], text: str) -> list[str]:
    """The names completing the word ``text`` ends with: those starting with it first,
    then those containing it, case-insensitive, at most ``MAX_COMPLETIONS``."""
    word = _WORD.search(text)
    stem = (word.group(1) if word else "").lstrip('"').lower()
    starts = [n for n in names if n.lstrip('"').lower().startswith(stem)]
    inside = [n for n in names if stem and stem in n.lower() and n not in starts]
    return (starts + inside)[:MAX_COMPLETIONS]


def completed(text: str, name: str) -> str:
    """``text`` with the word it ends with replaced by ``name``."""
    word = _WORD.search(text)
    return text[: word.start(1) if word else len(text)] + name
