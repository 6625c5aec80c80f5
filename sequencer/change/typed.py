"""Texts typed into the editor, read by the real `.s7g` parser (``sequencer.text.parse``).

A condition, an action row or an option is parsed inside a minimal chart around it, so it
means exactly what it would mean in a file; its syntax errors come back located in the
typed text itself (line 1, column where the problem is) and the element it builds carries
places in that text (file ``<condition>``, ``<interlock>``, ``<row>`` ...). A text holding
more than its element (``I0.0; TRANSITION ...``) is refused. Texts longer than
``MAX_TEXT`` characters, or nesting deeper than ``MAX_DEPTH``, are refused before anything
recursive reads them.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, replace
from typing import Final

from s7graph.sequencer.change.base import (
    MAX_DEPTH,
    MAX_ROWS,
    MAX_SEQUENCES,
    MAX_SOURCE,
    MAX_STEPS,
    MAX_TEXT,
    MAX_TRANSITIONS,
    EditRefused,
)
from s7graph.sequencer.checks.diagnostics import Diagnostic
from s7graph.sequencer.text.model import ActionRow, Chart, Expr
from s7graph.sequencer.text.parse import ChartSyntaxError, parse_chart
from s7graph.sequencer.text.walk import depth, relocated
from s7graph.steps.qualifiers import EVENTS, QUALIFIERS

# The minimal charts around a typed text: (text before, text after). The typed text starts
# a line of its own, so its line numbers are the wrapper's less the lines before it, and a
# `//` comment in it cannot swallow the `;` that closes it.
_CONDITION: Final = (
    'FUNCTION_BLOCK "_"\nSEQUENCE 1\nINITIAL_STEP S1: END_STEP\nTRANSITION T1 FROM S1 TO S1 :=\n',
    "\n;\nEND_SEQUENCE\nEND_FUNCTION_BLOCK\n",
)
_ROW: Final = (
    'FUNCTION_BLOCK "_"\nSEQUENCE 1\nINITIAL_STEP S1:\n',
    "\n;\nEND_STEP\nTRANSITION T1 FROM S1 TO S1;\nEND_SEQUENCE\nEND_FUNCTION_BLOCK\n",
)
_OPTION: Final = (
    'FUNCTION_BLOCK "_"\n',
    ";\nSEQUENCE 1\nINITIAL_STEP S1: END_STEP\nTRANSITION T1 FROM S1 TO S1;\nEND_SEQUENCE\n"
    "END_FUNCTION_BLOCK\n",
)
_WORD = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


def _typed(text: object, what: str, limit: int = MAX_TEXT) -> str:
    if not isinstance(text, str):
        raise EditRefused(f"{what} must be text, not {type(text).__name__}")
    if len(text) > limit:
        raise EditRefused(f"{what} has {len(text):,} characters; at most {limit:,} are accepted")
    return text


def _in_text(d: Diagnostic, text: str, file: str, head_lines: int) -> Diagnostic:
    """``d`` of the wrapper, located in the typed text; past its end: at its end."""
    lines = text.split("\n")
    line = d.loc.line - head_lines
    if line < 1:  # pragma: no cover - the wrapper's own text parses
        return replace(d, loc=replace(d.loc, file=file, line=1, col=1))
    if line <= len(lines):
        return replace(d, loc=replace(d.loc, file=file, line=line))
    expected = d.message.partition("; expected ")[2]
    message = "the text ends too early" + (f"; expected {expected}" if expected else "")
    end = replace(d.loc, file=file, line=len(lines), col=len(lines[-1]) + 1)
    return replace(d, message=message, loc=end)


def _file(what: str) -> str:
    """The file name of places in a typed text: ``<condition>``, ``<row>`` ... (the element
    itself is named by the diagnostic's ``element``, which follows renumbering)."""
    return f"<{what.split()[0]}>"


def _parse_wrapped(wrapper: tuple[str, str], text: str, what: str) -> tuple[Chart, int]:
    head, tail = wrapper
    head_lines = head.count("\n")
    file = _file(what)
    try:
        chart = parse_chart(head + text + tail, file)
    except ChartSyntaxError as exc:
        diags = tuple(_in_text(d, text, file, head_lines) for d in exc.diagnostics)
        first = diags[0]
        raise EditRefused(
            f"{what}: {first.message} (line {first.loc.line}, column {first.loc.col})", diags
        ) from None
    _check_depth(chart, what)
    q = chart.sequences
    if (
        len(q) != 1
        or len(q[0].steps) != 1
        or len(q[0].transitions) != 1
        or chart.vars
        or chart.symbols
        or chart.before
        or chart.after
        or len(chart.option_locs) > (1 if wrapper is _OPTION else 0)
    ):
        raise EditRefused(f"{what}: the text holds more than one {what} (a ';' ends it)")
    return chart, head_lines


def _check_depth(node: object, what: str) -> None:
    # up to 6 levels are the structure around a condition (chart, sequencer, step, row...)
    if depth(node) > MAX_DEPTH + 6:
        raise EditRefused(f"{what}: nests deeper than {MAX_DEPTH} levels")


def parse_condition(text: str, what: str = "condition") -> Expr | None:
    """The condition ``text`` (``.s7g`` condition syntax, docs/semantics.md, "Conditions"); None
    when blank."""
    text = _typed(text, what)
    if not text.strip():
        return None
    chart, head_lines = _parse_wrapped(_CONDITION, text, what)
    return relocated(chart.sequences[0].transitions[0].condition, _file(what), head_lines)


@dataclass(frozen=True, slots=True)
class RowFields:
    """An action row as the editor's fields, ``[event] qualifier[C] operand [, value]``
    (docs/semantics.md, "Actions"): ``event`` "" for none, ``operand`` e.g. ``Q0.0``,
    ``"Motor_on"``, ``S4``, ``S_ALL``, ``pieces := pieces + 1``, ``FB 5, DB 5 (IN1 := I0.0)``;
    ``value`` the time of D/L, the preset of CS, the S5TIME of TL/TD/TF."""

    qualifier: str
    operand: str
    event: str = ""
    interlocked: bool = False
    value: str = ""

    def text(self) -> str:
        """The row as written in a ``.s7g`` step (the interlock mark apart: ``N C Q0.0``)."""
        parts = [self.event, self.qualifier, "C" if self.interlocked else "", self.operand]
        row = " ".join(p for p in parts if p)
        return f"{row}, {self.value}" if self.value.strip() else row


def parse_row(fields: RowFields, what: str = "row") -> ActionRow:
    """The action row ``fields`` describe, read as the parser reads a row of a step."""
    if not isinstance(fields, RowFields):
        raise EditRefused(f"{what} must be row fields, not {type(fields).__name__}")
    event = _typed(fields.event, f"{what} event").strip().upper()
    qualifier = _typed(fields.qualifier, f"{what} qualifier").strip().upper()
    if event and event not in EVENTS:
        raise EditRefused(f"{what}: unknown event {event!r}; events are {' '.join(EVENTS)}")
    if qualifier not in QUALIFIERS:
        raise EditRefused(
            f"{what}: unknown qualifier {qualifier!r}; qualifiers are {' '.join(QUALIFIERS)}"
        )
    if not isinstance(fields.interlocked, bool):
        raise EditRefused(f"{what}: the interlock mark C is on or off (true or false)")
    operand = _typed(fields.operand, f"{what} operand")
    value = _typed(fields.value, f"{what} value")
    text = RowFields(qualifier, operand, event, fields.interlocked, value).text()
    _typed(text, what)
    chart, head_lines = _parse_wrapped(_ROW, text, what)
    step = chart.sequences[0].steps[0]
    if len(step.actions) != 1 or step.interlock is not None or step.supervision is not None:
        raise EditRefused(f"{what}: the text holds more than one {what} (a ';' ends it)")
    return relocated(step.actions[0], _file(what), head_lines)


def parse_option(keyword: str, value: str) -> tuple[str, object]:
    """The ``ChartOptions`` field and value of the header option ``keyword := value;``
    (``SKIP_STEPS := TRUE``), checked by the parser's own table of options."""
    keyword = _typed(keyword, "option", 64).strip()
    value = _typed(value, f"option {keyword}", 64).strip()
    if not _WORD.fullmatch(keyword) or not _WORD.fullmatch(value):
        raise EditRefused(f"option {keyword} := {value}: a name and a value like SKIP_STEPS, TRUE")
    chart, _ = _parse_wrapped(_OPTION, f"{keyword} := {value}", f"option {keyword}")
    if len(chart.option_locs) != 1:  # pragma: no cover - one option written, one read
        raise EditRefused(f"option {keyword}: not read")
    field = chart.option_locs[0][0]
    return field, getattr(chart.options, field)


def parse_source(text: str, file: str) -> Chart:
    """A whole chart from its ``.s7g`` text (the source view), within the editor's limits."""
    text = _typed(text, "the source", MAX_SOURCE)
    try:
        chart = parse_chart(text, file)
    except ChartSyntaxError as exc:
        first = exc.diagnostics[0]
        raise EditRefused(
            f"the source does not parse: {first.message} (line {first.loc.line}, column "
            f"{first.loc.col})",
            exc.diagnostics,
        ) from None
    check_bounds(chart)
    return chart


def check_bounds(chart: Chart) -> None:
    """Refuse a chart beyond the editor's limits (numbers of elements, nesting)."""
    n_steps, n_trans = len(chart.all_steps()), len(chart.all_transitions())
    for count, limit, what in (
        (len(chart.sequences), MAX_SEQUENCES, "sequencers"),
        (n_steps, MAX_STEPS, "steps"),
        (n_trans, MAX_TRANSITIONS, "transitions"),
    ):
        if count > limit:
            raise EditRefused(
                f"the chart has {count:,} {what}; the editor takes at most {limit:,} "
                "(S7-GRAPH allows 250 steps, 250 transitions, 8 sequencers)"
            )
    for s in chart.all_steps():
        if len(s.actions) > MAX_ROWS:
            raise EditRefused(
                f"step S{s.number} has {len(s.actions)} action rows; the editor "
                f"takes at most {MAX_ROWS}"
            )
        _check_depth((s.interlock, s.supervision, s.actions), f"step S{s.number}")
    for t in chart.all_transitions():
        _check_depth(t.condition, f"the condition of T{t.number}")
    _check_depth((chart.before, chart.after), "the permanent instructions")
