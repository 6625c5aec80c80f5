"""The action rows of the selected step in the editor's form: the fields of one row and
the buttons that add, change, remove or move it. ``RowEditing`` is a part of
``web.view.editor.Editor``, which owns the attributes it declares.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, Final

import viser

from s7graph.sequencer.change.base import Edit, EditRefused
from s7graph.sequencer.change.edit import Session, make_edit
from s7graph.sequencer.change.typed import RowFields
from s7graph.sequencer.text.elements import Ref, RowRef, StepRef, find
from s7graph.sequencer.text.format import format_row
from s7graph.sequencer.text.model import Chart, Step
from s7graph.steps.qualifiers import EVENTS, QUALIFIERS
from s7graph.web.view import texts
from s7graph.web.view.edit_forms import Form, row_fields
from s7graph.web.view.editor_cpu import refused

__all__ = ["NO_EVENT", "RowEditing"]

NO_EVENT: Final = "(none)"


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

        def apply(self, edit: Edit) -> None: ...

    def _rows_form(self, chart: Chart, ref: Ref | None) -> None:
        gui = self.client.gui
        self.rows_html = gui.add_html("")
        self.row_number = gui.add_number(
            "Row", 1, min=1, max=256, step=1, hint="the action row the fields below show"
        )
        self.row_event = gui.add_dropdown("Event", [NO_EVENT, *EVENTS])
        self.row_qualifier = gui.add_dropdown("Qualifier", list(QUALIFIERS))
        self.row_c = gui.add_checkbox("C (interlocked)", False)
        self.row_operand = gui.add_text("Operand", "", hint='Q0.0, "Motor_on", S4, n := n + 1')
        self.row_value = gui.add_text("Time / value", "", hint="T#2S for D and L, C#10 for CS")
        buttons = {
            "add": gui.add_button("Add action row", hint="the fields above as a new last row"),
            "change": gui.add_button("Change action row", hint="row Row becomes the fields"),
            "remove": gui.add_button("Remove action row", hint="remove row Row"),
            "up": gui.add_button("Move action row up"),
            "down": gui.add_button("Move action row down"),
        }
        self._form_handles += [
            self.rows_html,
            self.row_number,
            self.row_event,
            self.row_qualifier,
            self.row_c,
            self.row_operand,
            self.row_value,
            *buttons.values(),
        ]
        for what, button in buttons.items():
            button.on_click(self._click(functools.partial(self._row_action, what)))
        self.row_number.on_update(self._row_chosen)
        self._rows_show(chart, ref, fill=True)

    def _step_of(self, chart: Chart, ref: Ref | None) -> Step | None:
        number = ref.number if isinstance(ref, StepRef) else None
        found = find(chart, StepRef(number)) if number is not None else None
        return found if isinstance(found, Step) else None

    def _rows_show(self, chart: Chart, ref: Ref | None, *, fill: bool = False) -> None:
        step = self._step_of(chart, ref)
        rows = step.actions if step is not None else ()
        self.rows_html.content = texts.rows_html([format_row(r) for r in rows])
        sel = self.session.selection if self.session is not None else None
        if isinstance(sel, RowRef):
            fill = True
            if int(self.row_number.value) != sel.index + 1:
                self.row_number.value = sel.index + 1  # type: ignore[misc]
        if fill:
            self._row_fill(rows)

    def _row_fill(self, rows: tuple[Any, ...]) -> None:
        i = int(self.row_number.value) - 1
        if not 0 <= i < len(rows):
            return
        f = row_fields(rows[i])
        self.row_event.value = f.event or NO_EVENT  # type: ignore[misc]
        if f.qualifier in QUALIFIERS:
            self.row_qualifier.value = f.qualifier  # type: ignore[misc]
        self.row_c.value = f.interlocked  # type: ignore[misc]
        self.row_operand.value = f.operand  # type: ignore[misc]
        self.row_value.value = f.value  # type: ignore[misc]

    def _row_chosen(self, event: Any) -> None:
        if getattr(event, "client", None) is None or self.session is None:
            return
        step = self._step_of(self.session.chart, self._form.ref if self._form else None)
        if step is not None:
            self._guarded(lambda: self._row_fill(step.actions))

    def _row_action(self, what: str) -> None:
        if self.session is None or self._form is None or not isinstance(self._form.ref, StepRef):
            return
        n = self._form.ref.number
        index = int(self.row_number.value) - 1
        event = str(self.row_event.value)
        fields = RowFields(
            qualifier=str(self.row_qualifier.value),
            operand=str(self.row_operand.value),
            event="" if event == NO_EVENT else event,
            interlocked=bool(self.row_c.value),
            value=str(self.row_value.value),
        )
        args: dict[str, dict[str, object]] = {
            "add": {"op": "add_row", "step": n, "row": fields},
            "change": {"op": "change_row", "step": n, "index": index, "row": fields},
            "remove": {"op": "remove_row", "step": n, "index": index},
            "up": {"op": "move_row", "step": n, "index": index, "to": index - 1},
            "down": {"op": "move_row", "step": n, "index": index, "to": index + 1},
        }
        chosen = dict(args[what])
        name = str(chosen.pop("op"))
        try:
            edit = make_edit(name, chosen)
        except EditRefused as exc:
            self.session = refused(self.session, exc)
            self._show(source_changed=False)
            return
        self.apply(edit)
        sel = self.session.selection
        if isinstance(sel, RowRef):  # the row just made, moved or changed
            self.row_number.value = sel.index + 1  # type: ignore[misc]
