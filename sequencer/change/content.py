"""Edits of what an element holds: a step's name, number, initial flag, message text,
interlock, supervision and action rows; a transition's name, number and condition; a
sequencer's name; the header options; the whole chart as text (the source view).

Each edit is a frozen dataclass naming its element by number (``sequencer.change.base``).
Conditions and rows are typed as ``.s7g`` text and read by the real parser
(``sequencer.change.typed``). Renumbering keeps every reference to the number consistent:
FROM / TO, ``ON`` / ``OFF Sn``, ``Sn.X`` ``Sn.T`` ``Sn.U``, ``Tn.TT`` wherever they stand.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

from s7graph.engine.errors import SourceLocation
from s7graph.sequencer.change.base import (
    MAX_MESSAGE,
    MAX_NAME,
    MAX_ROWS,
    Edit,
    EditRefused,
    checked_number,
    checked_text,
    sequence_of,
    step_of,
    transition_of,
    with_sequence,
    with_step,
    with_transition,
)
from s7graph.sequencer.change.typed import (
    RowFields,
    parse_condition,
    parse_option,
    parse_row,
    parse_source,
)
from s7graph.sequencer.text.elements import (
    Ref,
    RowRef,
    SequenceRef,
    StepPart,
    StepRef,
    TransitionRef,
)
from s7graph.sequencer.text.model import (
    NOWHERE,
    Chart,
    Step,
    StepAttr,
    StepTarget,
    TransAttr,
    Transition,
)
from s7graph.sequencer.text.walk import rewrite

# ---------------------------------------------------------------- steps


@dataclass(frozen=True, slots=True)
class RenameStep(Edit):
    """Give step ``step`` the name ``name``."""

    step: int
    name: str

    def apply(self, chart: Chart) -> tuple[Chart, Ref | None]:
        s = step_of(chart, self.step)
        name = checked_text(self.name, f"the name of S{self.step}", MAX_NAME)
        return with_step(chart, replace(s, name=name)), StepRef(self.step)


@dataclass(frozen=True, slots=True)
class SetMessage(Edit):
    """Give step ``step`` the message text ``message`` ("" for none, docs/semantics.md,
    "Messages")."""

    step: int
    message: str

    def apply(self, chart: Chart) -> tuple[Chart, Ref | None]:
        s = step_of(chart, self.step)
        text = checked_text(self.message, f"the message of S{self.step}", MAX_MESSAGE)
        return with_step(chart, replace(s, message=text)), StepRef(self.step)


@dataclass(frozen=True, slots=True)
class SetInitial(Edit):
    """Make step ``step`` an initial step or not (active after INIT_SQ, docs/semantics.md,
    "Structure")."""

    step: int
    initial: bool

    def apply(self, chart: Chart) -> tuple[Chart, Ref | None]:
        s = step_of(chart, self.step)
        if not isinstance(self.initial, bool):
            raise EditRefused("initial is true or false")
        return with_step(chart, replace(s, initial=self.initial)), StepRef(self.step)


def _renumber(chart: Chart, steps: dict[int, int], transitions: dict[int, int]) -> Chart:
    """``chart`` with step and transition numbers mapped, every reference to them too."""

    def fn(x: Any) -> Any:
        if isinstance(x, Step) and x.number in steps:
            return replace(x, number=steps[x.number])
        if isinstance(x, Transition):
            if x.number in transitions:
                x = replace(x, number=transitions[x.number])
            if any(n in steps for n in (*x.sources, *x.targets)):
                return replace(
                    x,
                    sources=tuple(steps.get(n, n) for n in x.sources),
                    targets=tuple(steps.get(n, n) for n in x.targets),
                )
        if isinstance(x, StepAttr | StepTarget) and x.step in steps:
            return replace(x, step=steps[x.step])
        if isinstance(x, TransAttr) and x.transition in transitions:
            return replace(x, transition=transitions[x.transition])
        return x

    return rewrite(chart, fn)


def _new_number(old: int, to: object, used: list[int], prefix: str, what: str) -> int:
    """``to`` as the new number of ``old``: in range and not another one's."""
    n = checked_number(to, f"a {what} number")
    if n != old and n in used:
        raise EditRefused(f"{prefix}{n} exists already; {what} numbers are unique within the FB")
    return n


@dataclass(frozen=True, slots=True)
class RenumberStep(Edit):
    """Give step ``step`` the number ``to``; every FROM / TO, ``ON`` / ``OFF`` and
    ``Sn.X`` / ``.T`` / ``.U`` naming it follows."""

    step: int
    to: int

    def apply(self, chart: Chart) -> tuple[Chart, Ref | None]:
        step_of(chart, self.step)
        used = [s.number for s in chart.all_steps()]
        to = _new_number(self.step, self.to, used, "S", "step")
        return _renumber(chart, {self.step: to}, {}), StepRef(to)


def _step_condition(chart: Chart, n: int, text: str, part: StepPart) -> tuple[Chart, Ref]:
    """``chart`` with the interlock or supervision of ``Sn`` read from ``text``."""
    s = step_of(chart, n)
    expr = parse_condition(text, f"{part} of S{n}")
    loc = None if expr is None else SourceLocation(f"<{part}>", 1, 1)
    edited = replace(s, **{part: expr, f"{part}_loc": loc})  # type: ignore[arg-type]
    return with_step(chart, edited), StepRef(n, part)


@dataclass(frozen=True, slots=True)
class SetInterlock(Edit):
    """Give step ``step`` the interlock condition ``condition`` ("" removes it); rows
    marked C run only while it holds (docs/semantics.md, "Interlock")."""

    step: int
    condition: str

    def apply(self, chart: Chart) -> tuple[Chart, Ref | None]:
        return _step_condition(chart, self.step, self.condition, "interlock")


@dataclass(frozen=True, slots=True)
class SetSupervision(Edit):
    """Give step ``step`` the supervision condition ``condition`` ("" removes it): while
    it holds the step is faulted (docs/semantics.md, "Supervision")."""

    step: int
    condition: str

    def apply(self, chart: Chart) -> tuple[Chart, Ref | None]:
        return _step_condition(chart, self.step, self.condition, "supervision")


# ---------------------------------------------------------------- action rows


def _row_index(s: Step, index: object, *, end: bool = False) -> int:
    top = len(s.actions) if end else len(s.actions) - 1
    if not isinstance(index, int) or isinstance(index, bool) or not 0 <= index <= top:
        rows = f"0..{top}" if top >= 0 else "none"
        raise EditRefused(f"S{s.number} has no row index {index!r} (rows: {rows})")
    return index


@dataclass(frozen=True, slots=True)
class AddRow(Edit):
    """Insert the action row ``row`` into step ``step`` at index ``at`` (None: last)."""

    step: int
    row: RowFields
    at: int | None = None

    def apply(self, chart: Chart) -> tuple[Chart, Ref | None]:
        s = step_of(chart, self.step)
        at = len(s.actions) if self.at is None else _row_index(s, self.at, end=True)
        if len(s.actions) >= MAX_ROWS:
            raise EditRefused(f"S{self.step} has {MAX_ROWS} rows, the most the editor takes")
        row = parse_row(self.row, f"row {at + 1} of S{self.step}")
        actions = (*s.actions[:at], row, *s.actions[at:])
        return with_step(chart, replace(s, actions=actions)), RowRef(self.step, at)


@dataclass(frozen=True, slots=True)
class ChangeRow(Edit):
    """Replace action row ``index`` of step ``step`` by ``row``."""

    step: int
    index: int
    row: RowFields

    def apply(self, chart: Chart) -> tuple[Chart, Ref | None]:
        s = step_of(chart, self.step)
        i = _row_index(s, self.index)
        row = parse_row(self.row, f"row {i + 1} of S{self.step}")
        old = s.actions[i]
        row = replace(row, comment=old.comment, trailing=old.trailing)  # its comments stay
        actions = (*s.actions[:i], row, *s.actions[i + 1 :])
        return with_step(chart, replace(s, actions=actions)), RowRef(self.step, i)


@dataclass(frozen=True, slots=True)
class RemoveRow(Edit):
    """Remove action row ``index`` of step ``step``."""

    step: int
    index: int

    def apply(self, chart: Chart) -> tuple[Chart, Ref | None]:
        s = step_of(chart, self.step)
        i = _row_index(s, self.index)
        actions = (*s.actions[:i], *s.actions[i + 1 :])
        return with_step(chart, replace(s, actions=actions)), StepRef(self.step)


@dataclass(frozen=True, slots=True)
class MoveRow(Edit):
    """Move action row ``index`` of step ``step`` to index ``to`` (rows run top to bottom,
    docs/semantics.md, "One FB call")."""

    step: int
    index: int
    to: int

    def apply(self, chart: Chart) -> tuple[Chart, Ref | None]:
        s = step_of(chart, self.step)
        i, to = _row_index(s, self.index), _row_index(s, self.to)
        rows = list(s.actions)
        rows.insert(to, rows.pop(i))
        return with_step(chart, replace(s, actions=tuple(rows))), RowRef(self.step, to)


# ---------------------------------------------------------------- transitions


@dataclass(frozen=True, slots=True)
class RenameTransition(Edit):
    """Give transition ``transition`` the name ``name``."""

    transition: int
    name: str

    def apply(self, chart: Chart) -> tuple[Chart, Ref | None]:
        t = transition_of(chart, self.transition)
        name = checked_text(self.name, f"the name of T{self.transition}", MAX_NAME)
        return with_transition(chart, replace(t, name=name)), TransitionRef(self.transition)


@dataclass(frozen=True, slots=True)
class RenumberTransition(Edit):
    """Give transition ``transition`` the number ``to``; every ``Tn.TT`` follows."""

    transition: int
    to: int

    def apply(self, chart: Chart) -> tuple[Chart, Ref | None]:
        transition_of(chart, self.transition)
        used = [t.number for t in chart.all_transitions()]
        to = _new_number(self.transition, self.to, used, "T", "transition")
        return _renumber(chart, {}, {self.transition: to}), TransitionRef(to)


@dataclass(frozen=True, slots=True)
class SetCondition(Edit):
    """Give transition ``transition`` the condition ``condition`` ("" leaves it empty:
    it holds at once, W120)."""

    transition: int
    condition: str

    def apply(self, chart: Chart) -> tuple[Chart, Ref | None]:
        t = transition_of(chart, self.transition)
        expr = parse_condition(self.condition, f"condition of T{self.transition}")
        return with_transition(chart, replace(t, condition=expr)), TransitionRef(t.number)


# ---------------------------------------------------------------- sequencers and the chart


@dataclass(frozen=True, slots=True)
class RenameSequence(Edit):
    """Give sequencer ``sequence`` the name ``name``."""

    sequence: int
    name: str

    def apply(self, chart: Chart) -> tuple[Chart, Ref | None]:
        q = sequence_of(chart, self.sequence)
        name = checked_text(self.name, f"the name of sequencer {self.sequence}", MAX_NAME)
        return with_sequence(chart, replace(q, name=name)), SequenceRef(self.sequence)


@dataclass(frozen=True, slots=True)
class SetOption(Edit):
    """Set the header option ``option`` to ``value`` (``SKIP_STEPS``, ``TRUE``), as the
    ``.s7g`` header writes it (docs/chart-format.md)."""

    option: str
    value: str

    def apply(self, chart: Chart) -> tuple[Chart, Ref | None]:
        field, value = parse_option(self.option, self.value)
        options = replace(chart.options, **{field: value})  # type: ignore[arg-type]
        locs = chart.option_locs
        if all(f != field for f, _ in locs):  # written now (the place is the text's, if any)
            locs = (*locs, (field, NOWHERE))
        return replace(chart, options=options, option_locs=locs), None


@dataclass(frozen=True, slots=True)
class SetSource(Edit):
    """Replace the whole chart by the chart ``text`` holds (an edit in the source view)."""

    text: str

    def apply(self, chart: Chart) -> tuple[Chart, Ref | None]:
        return parse_source(self.text, chart.file), None
