"""The editor's form where the element is drawn: a small window floated beside the step or
transition clicked on the chart, holding its fields (name, number, condition …), its
action rows as a table, what can be inserted or deleted at that place, and Undo, Redo and
Delete. A condition field offers the names that complete the word being typed. The keys
Delete, Ctrl+Z and Ctrl+Y (Ctrl+Shift+Z) do the same as the buttons while the focus is
not in a text field (the browser's own undo works there). ``InPlace`` is a part of
``web.view.editor.Editor``, which owns the attributes it declares.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any, Final

import viser

from s7graph.engine.symbols import SymbolTable
from s7graph.sequencer.change.edit import BY_NAME, Operation, Session
from s7graph.sequencer.text.elements import Ref, RowRef, SequenceRef, StepRef, TransitionRef
from s7graph.web.view.drawing import BOX_W, scale_px
from s7graph.web.view.edit_forms import EXPRESSIONS, Field, Form, completed, completions, names_for

__all__ = ["PICK", "PLACE_WIDTH", "InPlace", "delete_of"]

PLACE_WIDTH: Final = 340  # pixels of the floating form
MIN_WIDTH: Final = 240  # narrower than this it covers the element rather
PLACE_HEIGHT: Final = 560  # its height at most (it scrolls)
GAP: Final = 12  # pixels between the element and the form
PICK: Final = "(pick a name)"
HINT_COMPLETE: Final = (
    "Names of symbols, variables, steps and transitions that match the word you are"
    " typing; pick one to put it in place of that word."
)


def delete_of(ref: Ref | None) -> Operation | None:
    """The operation the Delete key and button apply to the element ``ref`` (a row: its
    step; the table's rows have their own Remove)."""
    if isinstance(ref, StepRef | RowRef):
        return BY_NAME["delete_step"]
    if isinstance(ref, TransitionRef):
        return BY_NAME["delete_transition"]
    if isinstance(ref, SequenceRef):
        return BY_NAME["delete_sequence"]
    return None


class InPlace:
    """The floating form, its placing, name completion and the edit keys."""

    client: viser.ClientHandle
    session: Session | None
    symbols: SymbolTable | None
    _form: Form | None
    _form_handles: list[Any]
    _completers: dict[str, tuple[Any, Any]]

    if TYPE_CHECKING:

        def _guarded(self, action: Callable[[], object]) -> None: ...

        def _later(self, key: str, delay: float, action: Callable[[], None]) -> None: ...

        def _apply_op(self, op: Operation, ref: Ref | None, values: dict[str, object]) -> None: ...

        def change(
            self, step: Callable[[Session], Session], *, from_source: bool = ...
        ) -> None: ...

    def _place_build(self) -> None:
        gui = self.client.gui
        self.place = gui.add_panel(visible=False)
        with self.place.add_tab("Edit here"):
            self.form_html = gui.add_html("")
            self.undo_button = gui.add_button(
                "Undo", disabled=True, hint="Take back the last edit (Ctrl+Z on the chart)."
            )
            self.redo_button = gui.add_button(
                "Redo", disabled=True, hint="Make the edit taken back again (Ctrl+Y)."
            )
            self.delete_button = gui.add_button(
                "Delete",
                color="red",
                disabled=True,
                hint="Delete what is selected (the Delete key on the chart).",
            )
            self.form_folder = gui.add_folder("Properties")
            self.insert_folder = gui.add_folder("Insert or delete here")
        self.place.set_width(PLACE_WIDTH)
        self.undo_button.on_click(lambda _: self._guarded(self.undo))
        self.redo_button.on_click(lambda _: self._guarded(self.redo))
        self.delete_button.on_click(lambda _: self._guarded(self.delete_selected))
        self._keys: list[Any] = []
        self._completers = {}

    # ------------------------------------------------------------ undo, redo, delete

    def undo(self) -> None:
        self.change(lambda s: s.undo())

    def redo(self) -> None:
        self.change(lambda s: s.redo())

    def delete_selected(self) -> None:
        """Delete the step, transition or sequencer whose form is shown."""
        ref = self._form.ref if self._form is not None else None
        op = delete_of(ref)
        if op is not None:
            self._apply_op(op, ref, {})

    def _keys_on(self) -> None:
        """The edit keys of this page (its command palette lists them too)."""
        gui = self.client.gui
        keys: list[tuple[str, Any, Any, Callable[[], None]]] = [
            ("Delete the selected element", "delete", None, self.delete_selected),
            ("Undo the last edit", "Z", "cmd/ctrl", self.undo),
            ("Redo", "Y", "cmd/ctrl", self.redo),
            ("Redo (Ctrl+Shift+Z)", "Z", "cmd/ctrl+shift", self.redo),
        ]
        for label, key, modifier, action in keys:
            command = gui.add_command(label, hotkey=key, modifier=modifier)
            command.on_trigger(lambda _, a=action: self._guarded(a))  # type: ignore[misc]
            self._keys.append(command)

    def _keys_off(self) -> None:
        for command in self._keys:
            command.remove()
        self._keys = []

    # ------------------------------------------------------------ placing

    def _place_aside(self) -> None:
        """Show the form folded in the lower right corner, off the chart, until an element
        is clicked (its header unfolds it)."""
        self.place.visible = True
        self.place.float(x=-16, y=-16)
        self.place.minimize()

    def _place_beside(self, right: float, y: float) -> None:
        """Float the form beside a drawn element whose right edge is at scene ``right``
        (its middle at scene ``y``), on the side with room for it (on a narrow canvas
        narrower, on the roomier side); where the page's camera looks now."""
        cam = self.client.camera
        try:
            cx, cy, z = (float(v) for v in cam.position)
            w, h = float(cam.image_width), float(cam.image_height)
            scale = scale_px(z, float(cam.fov), h)
        except Exception:  # the page has not told its camera yet
            return
        if w <= 0 or h <= 0 or z <= 0:
            return
        x_right = w / 2 + (right - cx) * scale
        py = h / 2 - (y - cy) * scale
        x_left = x_right - BOX_W * scale  # an element's width at most: look past it
        right_room, left_room = w - x_right - GAP, x_left - GAP
        width = float(PLACE_WIDTH)
        if right_room < width and left_room < width:  # a narrow canvas: the roomier side
            width = max(float(MIN_WIDTH), min(width, max(right_room, left_room)))
        if right_room >= width or right_room >= left_room:
            left = min(x_right + GAP, w - width)
        else:
            left = max(0.0, x_left - GAP - width)
        height = min(PLACE_HEIGHT, max(200.0, h - 16))
        top = min(max(8.0, py - 60), max(8.0, h - height - 8))
        self.place.float(x=round(left), y=round(top), width=round(width), height=round(height))
        self.place.expand()

    # ------------------------------------------------------------ completing names

    def _complete_for(self, f: Field, handle: Any, ref: Ref | None) -> None:
        """A completion list under the expression field ``f`` (shown by ``handle``)."""
        if f.op.name not in EXPRESSIONS:
            return
        label = "Complete" if f.op.name == "set_condition" else f"Complete {f.label.lower()}"
        gui = self.client.gui
        shown = [PICK, *completions(self._names(), str(handle.value))]
        pick = gui.add_dropdown(label, shown, hint=HINT_COMPLETE)
        self._form_handles.append(pick)
        self._completers[f.op.name] = (pick, handle)
        handle.on_update(lambda event: self._typed(f, event))
        pick.on_update(lambda event: self._picked(f, ref, event))

    def _names(self) -> list[str]:
        symbols = [s.name for s in self.symbols] if self.symbols is not None else []
        return names_for(self.session.chart, symbols) if self.session is not None else []

    def _typed(self, f: Field, event: Any) -> None:
        """A key typed in an expression field: the names completing its last word."""
        if getattr(event, "client", None) is None:
            return
        pick, handle = self._completers.get(f.op.name, (None, None))
        if pick is None:
            return
        shown = [PICK, *completions(self._names(), str(handle.value))]
        if list(pick.options) != shown:
            pick.options = shown

    def _picked(self, f: Field, ref: Ref | None, event: Any) -> None:
        """A name picked: it replaces the word being typed, and the field is applied."""
        pick, handle = self._completers.get(f.op.name, (None, None))
        if getattr(event, "client", None) is None or pick is None or pick.value == PICK:
            return
        text = completed(str(handle.value), str(pick.value))
        handle.value = text
        pick.value = PICK
        self._later(f.op.name, 0.0, lambda: self._apply_op(f.op, ref, {f.arg.name: text}))
