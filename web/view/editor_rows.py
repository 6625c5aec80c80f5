"""The action rows of the selected step as an editable table in the step's form: one
line of inputs per row (event, qualifier, C, operand, time or value) applied as they
change, each with buttons to move it up or down or remove it, and a new row's inputs with
*Add action row* below. ``RowEditing`` is a part of ``web.view.editor.Editor``, which owns
the attributes it declares.
"""

from __future__ import annotations

import contextlib
import functools
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Final

import viser

from s7graph.sequencer.change.base import Edit, EditRefused
from s7graph.sequencer.change.edit import Session, make_edit
from s7graph.sequencer.change.typed import RowFields
from s7graph.sequencer.text.elements import Ref, StepRef, find
from s7graph.sequencer.text.model import ActionRow, Chart, Step
from s7graph.steps.qualifiers import EVENTS, QUALIFIERS
from s7graph.web.view import texts
from s7graph.web.view.edit_forms import DEBOUNCE_S, Form, row_fields
from s7graph.web.view.editor_cpu import refused

__all__ = ["MAX_TABLE_ROWS", "NO_EVENT", "RowEditing", "pages_of"]

NO_EVENT: Final = "(none)"
MAX_TABLE_ROWS: Final = 16  # rows the table shows at once; *Rows shown* pages through more
MOVES: Final = ("Up", "Down", "Remove")
HINT_EVENT: Final = "When the row runs: (none) every scan the step is active, or at an event."
HINT_QUALIFIER: Final = "What the row does: N sets while active, S/R set and reset, D/L delay"
HINT_C: Final = "Tick it to run the row only while the step's interlock holds."
HINT_OPERAND: Final = 'What the row acts on: Q0.0, "Motor_on", S4 or n := n + 1.'
HINT_VALUE: Final = "A time for D and L (T#2S), a count for CS (C#10); else empty."


def pages_of(count: int) -> list[str]:
    """The choices of *Rows shown* for a step of ``count`` rows: ``1–16``, ``17–32`` …"""
    firsts = range(0, count, MAX_TABLE_ROWS)
    return [f"{a + 1}–{min(a + MAX_TABLE_ROWS, count)}" for a in firsts] or ["1–16"]


@dataclass(slots=True)
class _Line:
    """The inputs of one row of the table (``inputs`` in RowFields order)."""

    folder: Any
    event: Any
    qualifier: Any
    c: Any
    operand: Any
    value: Any
    moves: Any

    def fields(self) -> RowFields:
        event = str(self.event.value)
        return RowFields(
            qualifier=str(self.qualifier.value),
            operand=str(self.operand.value),
            event="" if event == NO_EVENT else event,
            interlocked=bool(self.c.value),
            value=str(self.value.value),
        )

    def show(self, f: RowFields) -> None:
        """Show ``f`` (only what differs is sent)."""
        want: list[tuple[Any, object]] = [
            (self.event, f.event or NO_EVENT),
            (self.c, f.interlocked),
            (self.operand, f.operand),
            (self.value, f.value),
        ]
        if f.qualifier in QUALIFIERS:
            want.append((self.qualifier, f.qualifier))
        for handle, value in want:
            if handle.value != value:
                handle.value = value


class RowEditing:
    """The action-row part of a step's form."""

    client: viser.ClientHandle
    session: Session | None
    _form: Form | None
    _form_handles: list[Any]

    if TYPE_CHECKING:

        def _show(self, *, source_changed: bool) -> None: ...

        def _click(self, action: Callable[[], object]) -> Callable[[Any], None]: ...

        def _guarded(self, action: Callable[[], object]) -> None: ...

        def _later(self, key: str, delay: float, action: Callable[[], None]) -> None: ...

        def apply(self, edit: Edit) -> None: ...

    def _rows_form(self, chart: Chart, ref: Ref | None) -> None:
        gui = self.client.gui
        self.rows_folder = gui.add_folder("Action rows")
        self._form_handles.append(self.rows_folder)
        self._lines: list[_Line] = []
        step = self._step_of(chart, ref)
        with self.rows_folder:
            self.rows_html = gui.add_html("", order=0)
            self._row_start, self._table_start = 0, 0
            self.rows_page = gui.add_dropdown(
                "Rows shown",
                ["1–16"],
                order=0.5,
                visible=False,
                hint="A step with more than 16 action rows: which 16 the table shows.",
            )
            self.rows_page.on_update(self._rows_paged)
            self.rows_table = gui.add_folder("Rows", order=1, visible=False)
            empty = not (step.actions if step is not None else ())
            with gui.add_folder("New action row", order=2, expand_by_default=empty):
                self.row_event = gui.add_dropdown("Event", [NO_EVENT, *EVENTS], hint=HINT_EVENT)
                self.row_qualifier = gui.add_dropdown(
                    "Qualifier", list(QUALIFIERS), hint=HINT_QUALIFIER
                )
                self.row_c = gui.add_checkbox("C (interlocked)", False, hint=HINT_C)
                self.row_operand = gui.add_text("Operand", "", hint=HINT_OPERAND)
                self.row_value = gui.add_text("Time / value", "", hint=HINT_VALUE)
                add = gui.add_button("Add action row", hint="Add the fields above as a last row.")
        add.on_click(self._click(self._row_add))
        self._rows_show(chart, ref)

    def _step_of(self, chart: Chart, ref: Ref | None) -> Step | None:
        number = ref.number if isinstance(ref, StepRef) else None
        found = find(chart, StepRef(number)) if number is not None else None
        return found if isinstance(found, Step) else None

    def _rows_show(self, chart: Chart, ref: Ref | None) -> None:
        """Bring the table up to the step's rows: values in place while the number of rows
        stays, else the table anew."""
        step = self._step_of(chart, ref)
        every = step.actions if step is not None else ()
        pages = pages_of(len(every))
        self._row_start = min(self._row_start, (len(pages) - 1) * MAX_TABLE_ROWS)
        start = self._row_start
        rows = every[start : start + MAX_TABLE_ROWS]
        self.rows_html.content = texts.rows_note(len(rows), len(every), start)
        if list(self.rows_page.options) != pages:
            self.rows_page.options = pages
        shown = pages[start // MAX_TABLE_ROWS]
        if self.rows_page.value != shown:
            self.rows_page.value = shown  # type: ignore[misc]
        self.rows_page.visible = len(pages) > 1
        if len(rows) != len(self._lines) or start != self._table_start:
            self._rows_table(rows, start)
        for line, row in zip(self._lines, rows, strict=True):
            line.show(row_fields(row))
        self.rows_table.visible = bool(rows)

    def _rows_paged(self, event: Any) -> None:
        """Another 16 rows chosen in *Rows shown*."""
        if getattr(event, "client", None) is None or self.session is None or self._form is None:
            return  # set from here
        options = list(self.rows_page.options)
        value = str(self.rows_page.value)
        start = options.index(value) * MAX_TABLE_ROWS if value in options else 0

        def page() -> None:
            if self.session is not None and start != self._row_start:
                self._row_start = start
                self._rows_show(self.session.chart, self._form.ref if self._form else None)

        self._guarded(page)

    def _rows_table(self, rows: tuple[ActionRow, ...], start: int) -> None:
        """The table's lines for ``rows``, the first of them the step's row ``start`` (0-based)."""
        for line in self._lines:
            with contextlib.suppress(Exception):
                line.folder.remove()
        self._lines, self._table_start = [], start
        gui = self.client.gui
        with self.rows_table:
            for i, row in enumerate(rows, start + 1):
                with gui.add_folder(f"Row {i}") as folder:
                    line = _Line(
                        folder,
                        gui.add_dropdown(f"Event {i}", [NO_EVENT, *EVENTS], hint=HINT_EVENT),
                        gui.add_dropdown(f"Qualifier {i}", list(QUALIFIERS), hint=HINT_QUALIFIER),
                        gui.add_checkbox(f"C {i}", False, hint=HINT_C),
                        gui.add_text(f"Operand {i}", "", hint=HINT_OPERAND),
                        gui.add_text(f"Time / value {i}", "", hint=HINT_VALUE),
                        gui.add_button_group(
                            f"Row {i}:", MOVES, hint="Move this row up or down, or remove it."
                        ),
                    )
                line.show(row_fields(row))
                self._lines.append(line)
                for handle, delay in (
                    (line.event, 0.0),
                    (line.qualifier, 0.0),
                    (line.c, 0.0),
                    (line.operand, DEBOUNCE_S),
                    (line.value, DEBOUNCE_S),
                ):
                    handle.on_update(functools.partial(self._row_typed, i - 1, delay))
                line.moves.on_click(functools.partial(self._row_moved, i - 1))

    def _row_typed(self, index: int, delay: float, event: Any) -> None:
        at = index - self._table_start
        if getattr(event, "client", None) is None or not 0 <= at < len(self._lines):
            return  # set from here, or a line of another page
        line = self._lines[at]
        self._later(f"row {index}", delay, lambda: self._row_edit("change_row", index, line))

    def _row_moved(self, index: int, event: Any) -> None:
        what = str(event.target.value)
        op = "remove_row" if what == "Remove" else "move_row"
        to = index - 1 if what == "Up" else index + 1
        self._guarded(lambda: self._row_edit(op, index, None, to))

    def _row_add(self) -> None:
        event = str(self.row_event.value)
        fields = RowFields(
            qualifier=str(self.row_qualifier.value),
            operand=str(self.row_operand.value),
            event="" if event == NO_EVENT else event,
            interlocked=bool(self.row_c.value),
            value=str(self.row_value.value),
        )
        self._row_edit("add_row", -1, fields)

    def _row_edit(self, name: str, index: int, line: _Line | RowFields | None, to: int = 0) -> None:
        """Apply the row operation ``name`` to row ``index`` of the form's step."""
        if self.session is None or self._form is None or not isinstance(self._form.ref, StepRef):
            return
        args: dict[str, object] = {"step": self._form.ref.number}
        if name != "add_row":
            args["index"] = index
        if isinstance(line, _Line):
            args["row"] = line.fields()
        elif isinstance(line, RowFields):
            args["row"] = line
        if name == "move_row":
            args["to"] = to
        try:
            edit = make_edit(name, args)
        except EditRefused as exc:
            self.session = refused(self.session, exc)
            self._show(source_changed=False)
            return
        self.apply(edit)
