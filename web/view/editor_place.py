"""The editor's form where the element is drawn: a small window floated beside the step or
transition clicked on the chart, holding its fields (name, number, condition …), its
action rows as a table, what can be inserted or deleted at that place, and Undo, Redo and
Delete. A condition field offers the names that complete the word being typed. The keys
Delete, Ctrl+Z and Ctrl+Y (Ctrl+Shift+Z) do the same as the buttons while the focus is
not in a text field (the browser's own undo works there). A click on an empty place of
the chart offers the inserts there, and the window follows the chart when the camera
moves. Where the window floats is ``place_window``'s rule, a drawing tool's: beside the
element, never over it while the canvas has room beside, below or above it. ``InPlace``
is a part of
``web.view.editor.Editor``, which owns the attributes it declares.
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Final

import viser

from s7graph.engine.symbols import SymbolTable
from s7graph.sequencer.change.edit import BY_NAME, Operation, Session
from s7graph.sequencer.text.elements import Ref, RowRef, SequenceRef, StepRef, TransitionRef
from s7graph.web.view.drawing import (
    BOX_H,
    BOX_W,
    Picture,
    chart_point,
    on_step_box,
    same_canvas,
    scale_px,
    target_at,
)
from s7graph.web.view.edit_forms import EXPRESSIONS, Field, Form, completed, completions, names_for

__all__ = [
    "EDIT_OFFSET",
    "PICK",
    "PLACE_WIDTH",
    "InPlace",
    "Placed",
    "column_transition",
    "delete_of",
    "element_box",
    "place_window",
    "screen_box",
]

EDIT_OFFSET: Final = (0.0, -2000.0)  # where a page draws the chart it edits (off the live one)
FOLLOW_S: Final = 0.25  # the window follows the camera once it rests this long

PLACE_WIDTH: Final = 340  # pixels of the floating form
MIN_WIDTH: Final = 240  # narrower than this it goes below or above the element rather
PLACE_HEIGHT: Final = 560  # its height at most (it scrolls)
MIN_HEIGHT: Final = 200  # lower than that too, it covers the element
GAP: Final = 12  # pixels between the element and the form
MARGIN: Final = 8  # pixels from the canvas's edges
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


Box = tuple[float, float, float, float]
"""A rectangle: its left, top, right and bottom on the canvas, in pixels (y down)."""


@dataclass(frozen=True)
class Placed:
    """Where the form floats on the canvas (pixels) and on which ``side`` of its element
    (right, left, below, above, or over it); ``pan``: the pixels the chart must move by
    (right, down) for the element to show where the form was placed for it."""

    left: int
    top: int
    width: int
    height: int
    side: str
    pan: tuple[float, float] = (0.0, 0.0)


def element_box(
    pic: Picture | None, at: Ref | tuple[float, float] | None, offset: tuple[float, float]
) -> tuple[float, float, float, float] | None:
    """The scene box (x0, y0, x1, y1; y up) of what the form edits, drawn at ``offset``: a
    step's box, a transition's bar with its text (from its column's left, a step box
    wide: a form on its left leaves the steps above and below it free), or a scene point
    clicked; None if it is not drawn."""
    if isinstance(at, tuple):
        return (at[0], at[1], at[0], at[1])
    ox, oy = offset
    if isinstance(at, StepRef) and pic is not None and at.number in pic.steps:
        x, y = pic.steps[at.number]
        return (x + ox - BOX_W / 2, y + oy - BOX_H / 2, x + ox + BOX_W / 2, y + oy + BOX_H / 2)
    if isinstance(at, TransitionRef) and pic is not None and at.number in pic.shown:
        x0, y0, x1, y1 = pic.shown[at.number]
        x0 = min(x0, pic.transitions[at.number][0] - BOX_W / 2)  # its column's step boxes
        return (x0 + ox, y0 + oy, x1 + ox, y1 + oy)
    return None


def screen_box(
    box: tuple[float, float, float, float],
    camera: tuple[float, float, float],
    canvas: tuple[float, float],
) -> Box:
    """The canvas pixels of the scene box ``box`` (x0, y0, x1, y1; y up) under a camera
    looking straight down at ``(cx, cy)`` with ``scale`` pixels per scene unit, on a
    canvas ``(width, height)`` pixels."""
    x0, y0, x1, y1 = box
    cx, cy, scale = camera
    w, h = canvas
    return (
        w / 2 + (x0 - cx) * scale,
        h / 2 - (y1 - cy) * scale,
        w / 2 + (x1 - cx) * scale,
        h / 2 - (y0 - cy) * scale,
    )


def _into(lo: float, hi: float, start: float, end: float) -> float:
    """How far to move ``lo``..``hi`` for it to lie within ``start``..``end`` (as much of
    it as fits, its start first): the least move."""
    if hi > end:
        return max(end - hi, start - lo)
    return max(0.0, start - lo)


def place_window(
    element: Box,
    canvas: tuple[float, float],
    window: tuple[float, float] = (PLACE_WIDTH, PLACE_HEIGHT),
    *,
    reveal: bool = False,
) -> Placed:
    """Where a form ``window`` (width, height) floats for an ``element`` drawn at canvas
    pixels ``element`` on a ``canvas`` (width, height), as a drawing tool places it: beside
    the element on the side with room (right first; narrower, down to ``MIN_WIDTH``, on a
    narrow canvas), else below or above it (lower, down to ``MIN_HEIGHT``), and only where
    there is room for neither, over it (at the right, narrower if the element then fits
    left of it). ``reveal`` (a placing asked for, not one following the user's panning)
    pans the chart, the least way, to show the element: onto the canvas; where the canvas
    has room beside it, far enough from its edge; one the form must cover, into the part
    of the canvas left free."""
    w, h = canvas
    pan_x = _into(element[0], element[2], MARGIN, w - MARGIN) if reveal else 0.0
    pan_y = _into(element[1], element[3], MARGIN, h - MARGIN) if reveal else 0.0
    x0, y0, x1, y1 = element[0] + pan_x, element[1] + pan_y, element[2] + pan_x, element[3] + pan_y
    width, height = min(window[0], w), min(window[1], max(MIN_HEIGHT, h - 2 * MARGIN))
    right, left = w - x1 - GAP, x0 - GAP
    if reveal and max(right, left) < MIN_WIDTH - 0.5 and w - (x1 - x0) - GAP >= MIN_WIDTH:
        shift = right - MIN_WIDTH if right >= left else MIN_WIDTH - left
        pan_x, x0, x1 = pan_x + shift, x0 + shift, x1 + shift  # room beside it
        right, left = w - x1 - GAP, x0 - GAP
    pan = (pan_x, pan_y)
    if right >= width or left >= width or max(right, left) >= MIN_WIDTH - 0.5:  # rounding
        on_right = right >= width or (left < width and right >= left)
        narrow = min(width, right if on_right else left)
        x = x1 + GAP if on_right else x0 - GAP - narrow
        top = _clamp((y0 + y1) / 2 - 60, MARGIN, h - height - MARGIN)
        side = "right" if on_right else "left"
        return Placed(_clamp(x, 0, w - narrow), top, round(narrow), round(height), side, pan)
    below, above = h - y1 - GAP - MARGIN, y0 - GAP - MARGIN
    if max(below, above) >= MIN_HEIGHT:
        on_below = below >= height or (above < height and below >= above)
        low = min(height, below if on_below else above)
        y = y1 + GAP if on_below else y0 - GAP - low
        side = "below" if on_below else "above"
        return Placed(
            _clamp(x0, 0, w - width), _clamp(y, 0, h - low), round(width), round(low), side, pan
        )
    width = max(min(MIN_WIDTH, w), min(width, w - (x1 - x0) - GAP))  # room left for it
    x, top = round(max(0.0, w - width)), _clamp(y0 - 60, MARGIN, h - height - MARGIN)
    if reveal:
        pan = (pan_x + _into(x0, x1, 0.0, x - GAP), pan_y + _into(y0, y1, 0.0, h))
    return Placed(x, top, round(width), round(height), "over", pan)


def _clamp(v: float, lo: float, hi: float) -> int:
    return round(max(lo, min(v, hi)))


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
        self._reveal = False  # the next follow pans the chart to show the element
        self._full: tuple[float, float] = (0.0, 0.0)  # the canvas at its full resolution
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
        self._anchor, self._placed, self._reveal = None, None, False
        self.place.visible = True
        self.place.float(x=-16, y=-16)
        self.place.minimize()

    def _place_at(
        self, at: Ref | tuple[float, float] | None, *, unfold: bool = True, reveal: bool = True
    ) -> None:
        """Float the form beside where ``at`` is drawn (a step, a transition, or a scene
        point clicked) and remember it, so the form follows when the chart moves;
        ``reveal``: pan the chart so the element shows beside the form."""
        box = element_box(self._picture, at, EDIT_OFFSET)
        if box is not None:
            self._anchor = at
            self._place_box(box, unfold=unfold, reveal=reveal)
        elif unfold:
            self.place.expand()

    def _anchor_of(self, selected: Ref | None) -> Ref | tuple[float, float] | None:
        """What the form floats beside after an edit: the element it shows now (an insert
        selects what it inserted), else where it was."""
        if isinstance(selected, RowRef):
            return StepRef(selected.step)
        return selected if isinstance(selected, StepRef | TransitionRef) else self._anchor

    def _camera_moved(self, camera: Any) -> None:
        """The page's camera moved (zoomed, panned, or aimed after an edit changed the
        chart's size): the form follows its element once the camera rests. The canvas's
        size is kept at its full resolution (``same_canvas``)."""
        with contextlib.suppress(Exception):  # a camera without its canvas yet
            now = (float(camera.image_width), float(camera.image_height))
            if not same_canvas(self._full, now) or now[1] > self._full[1]:
                self._full = now
        if self.editing and self._anchor is not None:
            self._later("follow", FOLLOW_S, self._follow)

    def _follow(self) -> None:
        """Float the form beside its element again, where it is drawn now (folded or not as
        the user left it); after an edit (``_reveal``) the chart pans so it shows, never
        after the user's own panning."""
        if self.editing and self._anchor is not None:
            self._place_at(self._anchor, unfold=False, reveal=self._reveal)
            self._reveal = False

    def _place_box(self, box: Box, *, unfold: bool = True, reveal: bool = False) -> None:
        """Float the form beside the drawn element whose scene box is ``box``, where the
        page's camera looks now (``place_window``); ``reveal``: pan the chart first when
        the element is off the canvas or the form must cover it (not while following the
        user's own panning)."""
        cam = self.client.camera
        try:
            cx, cy, z = (float(v) for v in cam.position)
            w, h = float(cam.image_width), float(cam.image_height)
            if same_canvas(self._full, (w, h)):  # drawn at a lower resolution for now
                w, h = max(w, self._full[0]), max(h, self._full[1])
            scale = scale_px(z, float(cam.fov), h)
        except Exception:  # the page has not told its camera yet
            return
        if w <= 0 or h <= 0 or z <= 0:
            return
        placed = place_window(screen_box(box, (cx, cy, scale), (w, h)), (w, h), reveal=reveal)
        dx, dy = placed.pan
        if dx or dy:  # the element moves by (dx, dy) pixels: the camera the other way
            cam.position = (cx - dx / scale, cy + dy / scale, z)
        at = (placed.left, placed.top, placed.width, placed.height)
        if at != self._placed:
            self.place.float(x=at[0], y=at[1], width=at[2], height=at[3])
            self._placed = at
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
