"""The editor's form where the element is drawn: a small window floated beside the step or
transition clicked on the chart, holding its fields (name, number, condition …), its
action rows as a table, what can be inserted or deleted at that place, and Undo, Redo and
Delete. A condition field offers the names that complete the word being typed. The keys
Delete, Ctrl+Z and Ctrl+Y (Ctrl+Shift+Z) do the same as the buttons while the focus is
not in a text field (the browser's own undo works there). A click on an empty place of
the chart offers the inserts there, and the window follows the chart when the camera
moves. ``InPlace`` is a part of
``web.view.editor.Editor``, which owns the attributes it declares.
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, Final

import viser

from s7graph.engine.symbols import SymbolTable
from s7graph.sequencer.change.edit import BY_NAME, Operation, Session
from s7graph.sequencer.text.elements import Ref, RowRef, SequenceRef, StepRef, TransitionRef
from s7graph.web.view.drawing import (
    BAR_W,
    BOX_W,
    Picture,
    chart_point,
    on_step_box,
    scale_px,
    target_at,
)
from s7graph.web.view.edit_forms import EXPRESSIONS, Field, Form, completed, completions, names_for

__all__ = ["EDIT_OFFSET", "PICK", "PLACE_WIDTH", "InPlace", "column_transition", "delete_of"]

EDIT_OFFSET: Final = (0.0, -2000.0)  # where a page draws the chart it edits (off the live one)
FOLLOW_S: Final = 0.25  # the window follows the camera once it rests this long

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


def _hit(pic: Picture, x: float, y: float) -> bool:
    """Whether the picture point ``(x, y)`` is on a step box or a transition's click target
    (their own clicks handle it)."""
    return on_step_box(pic, x, y) or target_at(pic, x, y) is not None


def column_transition(pic: Picture, x: float, y: float) -> int | None:
    """The transition an empty place ``(x, y)`` of the picture inserts after: the nearest one
    above it in its column (a step box wide); None off every column (a new sequencer)."""
    above = [(ty, n) for n, (tx, ty) in pic.transitions.items() if abs(x - tx) <= BOX_W / 2]
    above = [(ty, n) for ty, n in above if ty > y]
    return min(above)[1] if above else None


class InPlace:
    """The floating form, its placing, name completion and the edit keys."""

    client: viser.ClientHandle
    editing: bool
    _picture: Picture | None
    session: Session | None
    symbols: SymbolTable | None
    _form: Form | None
    _form_handles: list[Any]
    _completers: dict[str, tuple[Any, Any]]

    if TYPE_CHECKING:

        def _guarded(self, action: Callable[[], object]) -> None: ...

        def _later(self, key: str, delay: float, action: Callable[[], None]) -> None: ...

        def select(self, ref: Ref | None) -> None: ...

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
        self._anchor: Ref | tuple[float, float] | None = None
        self._placed: tuple[int, int, int, int] | None = None
        self.client.camera.on_update(self._camera_moved)

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
        self.client.scene.on_click()(self._clicked_empty)

    def _keys_off(self) -> None:
        for command in self._keys:
            command.remove()
        self._keys = []
        self._anchor = None
        with contextlib.suppress(Exception):  # the page is gone
            self.client.scene.remove_click_callback(self._clicked_empty)

    def _clicked_empty(self, event: Any) -> None:
        """A click on the chart where nothing is drawn: the inserts of that place — after the
        transition above it in its column (*Step + Transition* …), off every column the
        chart's (*Sequencer*) — in the window beside it."""
        pic, (ox, oy) = self._picture, EDIT_OFFSET
        at = chart_point(event, EDIT_OFFSET)
        if not self.editing or pic is None or at is None:
            return
        x, y = at
        if _hit(pic, x, y):
            return
        n = column_transition(pic, x, y)
        ref = TransitionRef(n) if n is not None else None
        self._guarded(lambda: self._place_at((x + ox, y + oy)))
        self._guarded(lambda: self.select(ref))

    # ------------------------------------------------------------ placing

    def _place_aside(self) -> None:
        """Show the form folded in the lower right corner, off the chart, until an element
        is clicked (its header unfolds it)."""
        self._anchor, self._placed = None, None
        self.place.visible = True
        self.place.float(x=-16, y=-16)
        self.place.minimize()

    def _place_at(self, at: Ref | tuple[float, float] | None, *, unfold: bool = True) -> None:
        """Float the form beside where ``at`` is drawn (a step, a transition, or a scene
        point clicked) and remember it, so the form follows when the chart moves."""
        pic, (ox, oy) = self._picture, EDIT_OFFSET
        if isinstance(at, tuple):
            self._anchor = at
            self._place_beside(*at, unfold=unfold)
        elif isinstance(at, StepRef) and pic is not None and at.number in pic.steps:
            self._anchor = at
            x, y = pic.steps[at.number]
            self._place_beside(x + ox + BOX_W / 2, y + oy, unfold=unfold)
        elif isinstance(at, TransitionRef) and pic is not None and at.number in pic.transitions:
            self._anchor = at
            x, y = pic.transitions[at.number]
            self._place_beside(x + ox + BAR_W / 2, y + oy, unfold=unfold)
        elif unfold:
            self.place.expand()

    def _camera_moved(self, _: Any) -> None:
        """The page's camera moved (zoomed, panned, or aimed after an edit changed the
        chart's size): the form follows its element once the camera rests."""
        if self.editing and self._anchor is not None:
            self._later("follow", FOLLOW_S, self._follow)

    def _follow(self) -> None:
        """Float the form beside its element again, where it is drawn now (folded or not as
        the user left it)."""
        if self.editing and self._anchor is not None:
            self._place_at(self._anchor, unfold=False)

    def _place_beside(self, right: float, y: float, *, unfold: bool = True) -> None:
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
        placed = (round(left), round(top), round(width), round(height))
        if placed != self._placed:
            self.place.float(x=placed[0], y=placed[1], width=placed[2], height=placed[3])
            self._placed = placed
        if unfold:
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
