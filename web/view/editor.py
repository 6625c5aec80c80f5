"""Edit mode of one browser page (an engineer's): the chart as an editing session
(``sequencer.change.edit.Session``), drawn on the page's own scene, edited in the side panel and
in its source view, checked live, saved, opened and downloaded into the running CPU.

- **Select** a step or transition on the chart (or in *Element*); its form lists what the
  table of edit operations offers for it (``web.view.edit_forms``): properties applied as
  they change, actions as buttons, and for a step its action rows.
- **Diagnostics** are ``s7graph check``'s, located by line and column in the source view
  (the chart written as ``.s7g`` text); a click on one selects its element. A refused
  edit says why and changes nothing. Reads of the FBs' variables by name, and calls of
  those blocks, are checked in the user blocks the CPU runs (``editor_cpu.cpu_blocks``: its
  S7-SCL sources, or the interfaces it sends of blocks without them), as a download's
  compile does.
- **Source view**: the same chart as text; an edit there is applied once typing pauses
  (the ``set_source`` edit), an edit anywhere else rewrites the text.
- **Save** / **Open** / **New**, **Download** and **Undo download** are commands to the CPU
  (the engineer's, checked and audited there): the CPU compiles the chart off its scan
  thread and answers with the change summary first (a preview); the page asks for
  confirmation — and, when active steps would be removed, whether to keep the other steps
  or initialize the sequencer — before the real download.

Everything here runs in viser's callback threads or the view's render thread, never in the
CPU's scan; the editor's own lock keeps one page's actions in order.
"""

from __future__ import annotations

import contextlib
import functools
import html
import threading
from collections.abc import Callable
from typing import Any, Final

from s7graph.engine.errors import internal_error
from s7graph.engine.symbols import SymbolTable
from s7graph.sequencer.change.base import Edit, EditRefused
from s7graph.sequencer.change.content import SetSource
from s7graph.sequencer.change.edit import Operation, Session, diagnostics_of
from s7graph.sequencer.change.typed import parse_source
from s7graph.sequencer.checks.diagnostics import Diagnostic
from s7graph.sequencer.checks.interfaces import ProgramBlocks
from s7graph.sequencer.text.elements import Ref, RowRef, StepRef, TransitionRef, element_of, find
from s7graph.sequencer.text.format import format_chart
from s7graph.sequencer.text.model import Chart
from s7graph.sequencer.text.parse import ChartSyntaxError, parse_chart
from s7graph.web.bus.protocol import ChartLayout, ChartSource
from s7graph.web.view import texts
from s7graph.web.view.drawing import (
    FLAWED,
    SELECTED,
    Drawing,
    Picture,
    aim_camera,
    picture,
)
from s7graph.web.view.edit_forms import DEBOUNCE_S, Field, Form, element_choices, form_for
from s7graph.web.view.editor_cpu import (
    MAX_DIAGNOSTIC_BUTTONS,
    CpuCommands,
    Located,
    cpu_blocks,
    refused,
)
from s7graph.web.view.editor_place import EDIT_OFFSET, FOLLOW_S, InPlace, delete_of
from s7graph.web.view.editor_rows import RowEditing
from s7graph.web.view.editor_xref import CrossReferencing, key_ref
from s7graph.web.view.engineering import EditorPage
from s7graph.web.view.layout import place

__all__ = ["EDIT_OFFSET", "Editor"]

EDITOR_WIDTH: Final = 400  # pixels of the editor's panel, docked left of the chart


class Editor(CpuCommands, RowEditing, InPlace, CrossReferencing):
    """The edit mode of ``panel``'s page (built only for a role that may download)."""

    def __init__(self, panel: EditorPage) -> None:
        self.panel = panel
        self.client = panel.client
        wiring = panel.wiring
        assert wiring.engineering is not None and wiring.host is not None
        self.eng = wiring.engineering
        self.host = wiring.host
        self._lock = threading.RLock()
        self.editing = False
        self.session: Session | None = None
        self.base: ChartSource | None = None
        self.symbols: SymbolTable | None = None
        self.interfaces: ProgramBlocks | None = None
        self.located = Located((), None)
        self.note = ""
        self._drawing: Drawing | None = None
        self._drawn: Chart | None = None
        self._picture: Picture | None = None
        self._form: Form | None = None
        self._form_handles: list[Any] = []
        self._inputs: dict[str, Any] = {}
        self._diag_buttons: list[Any] = []
        self._diag_shown: list[Diagnostic] = []
        self._timers: dict[str, tuple[threading.Timer, Callable[[], None]]] = {}
        self._source_text = ""
        self._choices: dict[str, Ref | None] = {}
        self._modal: Any = None
        self._closed = False
        self._build()

    # ------------------------------------------------------------ building

    def _build(self) -> None:
        gui = self.client.gui
        order = float(self.panel.control_folder.order) - 0.5  # right under the login
        with gui.add_folder("Edit chart", order=order) as self.folder:
            self.toggle = gui.add_button("Edit mode", hint="edit this chart and download it")
            self.status = gui.add_html(self._status_html())
            with gui.add_folder("Chart", visible=False) as self.tools:
                self.download_button = gui.add_button(
                    "Download", color="orange", hint="compile and download into the CPU"
                )
                self.undo_download_button = gui.add_button(
                    "Undo download", hint="put the chart before the last download back"
                )
                self.file = gui.add_text("File", "", hint="the .s7g file Save writes")
                self.save_button = gui.add_button("Save", hint="write the chart as the File")
                self.save_here_button = gui.add_button(
                    "Save to this computer",
                    hint="the chart being edited, as a .s7g file your browser downloads",
                )
                self.open_choice = gui.add_dropdown(
                    "Open file", ["(none)"], hint="A chart or importable file of the CPU's project."
                )
                self.chart_choices: dict[str, tuple[str, str]] = {}
                self.open_button = gui.add_button("Open", hint="open the chosen file")
                self.new_button = gui.add_button("New", hint="a new chart: S1 and T1")
        # The element's form floats beside it on the chart; the problems and the source
        # are a panel of their own, docked left of the chart while editing.
        self._place_build()
        self.side = gui.add_panel(visible=False)
        with self.side.add_tab("Element"):
            self.element = gui.add_dropdown(
                "Element", ["Chart"], hint="Choose what to edit, or click it on the chart."
            )
            self.diag_folder = gui.add_folder("Diagnostics")
            with self.diag_folder:
                self.diag_html = gui.add_html("")
        with self.side.add_tab("Source (.s7g)"):
            self.source = gui.add_text(
                "Source",
                "",
                multiline=True,
                hint="The chart as .s7g text; what you type becomes the chart when typing pauses.",
            )
            # the page's height: a minimum, for Mantine's autosize writes the height
            # inline (!important, which no style sheet overrides) at six rows
            uid = self.source._impl.uuid
            rule = (
                f".mantine-Flex-root:has(label[for='{uid}']) textarea{{"
                "min-height:calc(100vh - 12em) !important;max-height:none !important;"
                "font-family:monospace;font-size:0.75em;white-space:pre;"
                "overflow:auto !important}"
            )
            gui.add_html(f"<style>{rule}</style>")
        self._xref_build(self.side)
        self.side.dock_left()
        self.side.set_width(EDITOR_WIDTH)
        self.toggle.on_click(lambda _: self._toggle())
        self.save_button.on_click(lambda _: self._guarded(self.save))
        self.save_here_button.on_click(lambda _: self._guarded(self.save_here))
        self.open_button.on_click(lambda _: self._guarded(self.open))
        self.new_button.on_click(lambda _: self._guarded(self.new))
        self.download_button.on_click(lambda _: self._guarded(self.download))
        self.undo_download_button.on_click(lambda _: self._guarded(self.undo_download))
        self.element.on_update(self._element_chosen)
        self.source.on_update(self._source_typed)

    def close(self, *, page_gone: bool = False) -> None:
        """The page's role changed (or it logged out): leave edit mode, drop the panel;
        ``page_gone``: the page itself went, there is nothing left to update."""
        with self._lock:
            self._closed = True
            for timer, _ in self._timers.values():
                timer.cancel()
            if page_gone:
                return
            if self.editing:
                self.leave()
            with contextlib.suppress(Exception):
                self.folder.remove()
            with contextlib.suppress(Exception):
                self.place.remove()
            with contextlib.suppress(Exception):
                self.side.remove()

    def _click(self, action: Callable[[], object]) -> Callable[[Any], None]:
        """A click handler running ``action`` through :meth:`_guarded`."""
        return lambda _: self._guarded(action)

    def _guarded(self, action: Callable[[], object]) -> None:
        """Run one action of this page in order; an unexpected error is a notification,
        never a dead callback."""
        try:
            with self._lock:
                if not self._closed:
                    action()
        except Exception as exc:
            self._notify("editor", internal_error("in the editor", exc), ok=False)

    # ------------------------------------------------------------ edit mode

    def _toggle(self) -> None:
        self._guarded(self.leave_asked if self.editing else self.enter)

    def enter(self) -> None:
        """Start editing the chart the CPU runs."""
        source, why = self._source()
        if source is None:
            self._notify("edit mode", why or "the CPU does not answer with its chart", ok=False)
            return
        try:
            symbols = SymbolTable.from_text(source.symbols) if source.symbols else None
            chart = parse_source(source.text, source.file or "chart.s7g")
            interfaces, blocks_note = cpu_blocks(source, chart)
            session = Session.open(chart, symbols, interfaces)
        except Exception as exc:  # EditRefused, a symbol table that does not load ...
            reason = exc.reason if isinstance(exc, EditRefused) else str(exc)
            self._notify("edit mode", f"cannot edit the running chart: {reason}", ok=False)
            return
        self.base, self.symbols, self.session = source, symbols, session
        self.interfaces = interfaces
        self._xref_blocks = None  # the CPU's S7-SCL blocks read again for this session
        self.file.value = source.file or f"{chart.name}.s7g"  # type: ignore[misc]
        self.editing = True
        self.toggle.label = "Leave edit mode"
        self.tools.visible = True
        self.side.visible = True
        self._place_aside()
        self._keys_on()
        self._refresh_files()
        self.note = f"editing version {source.version} as the CPU runs it"
        self.note += f"; {blocks_note}" if blocks_note else ""
        self._show(source_changed=True)
        self.aim(whole=False)

    def leave(self) -> None:
        """Back to the live chart (the session is dropped; nothing is downloaded)."""
        self.editing = False
        self.toggle.label = "Edit mode"
        self.tools.visible = False
        self.side.visible = False
        self.place.visible = False
        self._keys_off()
        if self._drawing is not None:
            self._drawing.remove()
            self._drawing, self._drawn = None, None
        self._clear_form()
        self.status.content = self._status_html()
        self.panel.fit(lambda: None)
        pic = getattr(self.host, "picture", None)
        if pic is not None:
            self.panel.fit(lambda: aim_camera(self.client, pic, whole=False))

    def aim(self, *, whole: bool) -> None:
        """Aim the page at the chart edited (the docked panels narrow the canvas: the page
        says its size)."""
        pic = self._picture
        if pic is not None:
            self.panel.fit(lambda: aim_camera(self.client, pic, whole=whole, offset=EDIT_OFFSET))

    def running_changed(self, layout: ChartLayout) -> None:
        """The CPU runs another chart version (a download, from here or elsewhere)."""
        with self._lock:
            if self.editing:
                self.status.content = self._status_html()

    # ------------------------------------------------------------ edits

    def change(self, step: Callable[[Session], Session], *, from_source: bool = False) -> None:
        """Move the session on by ``step`` (an edit, undo, redo, a selection) and show it."""
        if self.session is None:
            return
        before = self.session
        self.session = step(before)
        if self.session.refusal is None:
            self.note = ""
        self._show(source_changed=self.session.chart is not before.chart and not from_source)

    def apply(self, edit: Edit) -> None:
        self.change(lambda s: s.apply(edit))

    def select(self, ref: Ref | None) -> None:
        """Select ``ref``; what was typed in the form and not applied yet (its pause not
        over) is applied first, to the element it was typed for."""
        self._flush_typing()
        self.change(lambda s: s.select(ref))

    def _apply_op(self, op: Operation, ref: Ref | None, values: dict[str, object]) -> None:
        try:
            edit = op.on(ref, **values)
        except EditRefused as exc:
            if self.session is not None:
                self.session = refused(self.session, exc)
            self._show(source_changed=False)
            return
        self.apply(edit)

    # ------------------------------------------------------------ showing

    def _status_html(self) -> str:
        s = self.session
        return texts.editor_status_html(
            editing=self.editing,
            file=str(self.file.value) if hasattr(self, "file") else "",
            base=self.base.version if self.base is not None else None,
            running=self.host.layout.version,
            undo=s.undo_label if s is not None else None,
            redo=s.redo_label if s is not None else None,
            note=self.note,
        )

    def _show(self, *, source_changed: bool) -> None:
        """Bring the page up to the session: chart drawing, form, diagnostics, source."""
        s = self.session
        if s is None or not self.editing:
            return
        chart = s.chart
        if chart is not self._drawn:
            self.located = _located(chart, self.symbols, s.blocks)
            self._draw(chart)
            self._xref_show(chart)
        self._colour()
        with self.client.atomic():
            self._form_of(chart, s.selection)
            self._diagnostics(s)
            self._choose_element(chart, s.selection)
            if source_changed:
                self._source_text = format_chart(chart)
                self.source.value = self._source_text  # type: ignore[misc]
            self.undo_button.disabled = s.undo_label is None
            self.redo_button.disabled = s.redo_label is None
            shown = self._form.ref if self._form is not None else None
            self.delete_button.disabled = delete_of(shown) is None
            self.status.content = self._status_html()

    def _draw(self, chart: Chart) -> None:
        """Draw ``chart``; when the edit made it larger or smaller, fit the page to it —
        unless the form is beside an element: the chart stays where the user looks, and
        pans only for that element to show beside the form (a re-aim at its top left
        would lose it)."""
        before = self._picture.bounds if self._picture is not None else None
        self._picture = picture(place(ChartLayout.from_chart(chart)))
        if before is not None and before != self._picture.bounds and self._anchor is None:
            self.aim(whole=False)
        self._reveal = self._anchor is not None
        if self._drawing is not None:
            self._drawing.remove()
        self._drawing = Drawing(
            self.client.scene,
            self._picture,
            root="/edit",
            offset=EDIT_OFFSET,
            on_step=self._clicked_step,
            on_transition=self._clicked_transition,
        )
        self._drawn = chart
        if self._anchor is not None:  # its element may be drawn elsewhere now
            self._anchor = self._anchor_of(self.session.selection if self.session else None)
            self._later("follow", FOLLOW_S, self._follow)

    def _clicked_step(self, number: int, _: Any) -> None:
        self._guarded(functools.partial(self._place_at, StepRef(number)))
        self._guarded(functools.partial(self.select, StepRef(number)))

    def _clicked_transition(self, number: int, _: Any) -> None:
        self._guarded(functools.partial(self._place_at, TransitionRef(number)))
        self._guarded(functools.partial(self.select, TransitionRef(number)))

    def _colour(self) -> None:
        if self._drawing is None or self.session is None:
            return
        steps: dict[int, tuple[int, int, int]] = {}
        transitions: dict[int, tuple[int, int, int]] = {}
        for d in self.session.diagnostics:
            ref = element_of(d)
            if d.is_error and isinstance(ref, StepRef | RowRef):
                steps[ref.number if isinstance(ref, StepRef) else ref.step] = FLAWED
            elif d.is_error and isinstance(ref, TransitionRef):
                transitions[ref.number] = FLAWED
        sel = self.session.selection
        if isinstance(sel, StepRef | RowRef):
            steps[sel.number if isinstance(sel, StepRef) else sel.step] = SELECTED
        elif isinstance(sel, TransitionRef):
            transitions[sel.number] = SELECTED
        self._drawing.paint(steps, transitions)

    def _choose_element(self, chart: Chart, selection: Ref | None) -> None:
        choices = element_choices(chart)
        self._choices = {label: ref for label, ref in choices}
        labels = [label for label, _ in choices]
        if list(self.element.options) != labels:
            self.element.options = labels
        want = key_ref(selection)
        shown = next((label for label, ref in choices if ref == want), labels[0])
        if self.element.value != shown:
            self.element.value = shown  # type: ignore[misc]

    def _element_chosen(self, event: Any) -> None:
        if getattr(event, "client", None) is None:
            return  # set from here
        ref = self._choices.get(str(self.element.value))
        self._guarded(lambda: self._place_at(ref))
        self._guarded(lambda: self.select(ref))

    def _diagnostics(self, s: Session) -> None:
        refusal = s.refusal.reason if s.refusal is not None else ""
        shown = list(s.refusal.diagnostics) if s.refusal is not None else []
        shown += list(self.located.diagnostics)
        shown = shown[:MAX_DIAGNOSTIC_BUTTONS]
        self.diag_html.content = texts.diagnostics_html(shown, refusal)
        if shown == self._diag_shown:
            return
        self._diag_shown = shown
        for button in self._diag_buttons:
            button.remove()
        self._diag_buttons = []
        with self.diag_folder:
            for i, d in enumerate(shown, 1):
                button = self.client.gui.add_button(
                    texts.diagnostic_button(i, d),
                    color="red" if d.is_error else "yellow",
                    hint=f"select it: {texts.diagnostic_line(d)}",
                )
                button.on_click(self._click(functools.partial(self.select_diagnostic, d)))
                self._diag_buttons.append(button)

    def select_diagnostic(self, d: Diagnostic) -> None:
        """Select the element diagnostic ``d`` concerns (a click in the list)."""
        ref = element_of(d, self.located.chart)
        if ref is None and self.session is not None:
            ref = element_of(d, self.session.chart)
        self.select(key_ref(ref) if ref is not None else None)

    # ------------------------------------------------------------ the form

    def _clear_form(self) -> None:
        """Drop the form and what was typed in it and waits (the window's following stays:
        an edit that selects another element rebuilds the form right after drawing)."""
        for key in [k for k in self._timers if k != "follow"]:
            self._timers.pop(key)[0].cancel()
        for handle in self._form_handles:
            with contextlib.suppress(Exception):
                handle.remove()
        self._form_handles, self._inputs, self._form = [], {}, None
        self._completers = {}

    def _form_of(self, chart: Chart, selection: Ref | None) -> None:
        form = form_for(chart, selection)
        title = texts.small(f"<b>{html.escape(_title(chart, form.ref))}</b>")
        if self.form_html.content != title:
            self.form_html.content = title
        if self._form is not None and self._form.key == form.key:
            for f in form.properties:  # the same fields: only their values
                handle = self._inputs.get(f.op.name)
                if handle is not None and handle.value != _shown(f):
                    handle.value = _shown(f)
            if form.rows:
                self._rows_show(chart, form.ref)
            self._form = form
            return
        self._clear_form()
        self._form = form
        gui = self.client.gui
        with self.form_folder:
            for f in form.properties:
                handle = self._input(f)
                self._inputs[f.op.name] = handle
                handle.on_update(self._property_handler(f))
                self._complete_for(f, handle, form.ref)
            if form.rows:
                self._rows_form(chart, form.ref)
        quick = delete_of(form.ref)  # the Delete button's
        with self.insert_folder:
            for op, fields in form.actions:
                if quick is not None and op.name == quick.name:
                    continue
                handles = [self._input(f) for f in fields]
                button = gui.add_button(op.title, hint=op.hint)
                self._form_handles.append(button)
                button.on_click(self._action_handler(op, form.ref, fields, handles))

    def _input(self, f: Field) -> Any:
        gui = self.client.gui
        value = _shown(f)
        handle: Any
        if f.arg.type == "bool":
            handle = gui.add_checkbox(f.label, bool(value), hint=f.hint)
        elif f.arg.type.startswith("int"):  # no min or max: the browser would clamp a
            # number typed out of range silently; the edit refuses it, saying the range
            handle = gui.add_number(f.label, int(value), step=1, hint=f.hint)  # type: ignore[call-overload]
        else:
            handle = gui.add_text(f.label, str(value), hint=f.hint)
        self._form_handles.append(handle)
        return handle

    def _property_handler(self, f: Field) -> Callable[[Any], None]:
        def changed(event: Any) -> None:
            if getattr(event, "client", None) is None:
                return  # set from here
            handle = event.target
            ref = self._form.ref if self._form is not None else None
            immediate = f.arg.type == "bool"
            self._later(
                f.op.name,
                0.0 if immediate else DEBOUNCE_S,
                lambda: self._apply_op(f.op, ref, {f.arg.name: _value(f, handle.value)}),
            )

        return changed

    def _action_handler(
        self, op: Operation, ref: Ref | None, fields: tuple[Field, ...], handles: list[Any]
    ) -> Callable[[Any], None]:
        def clicked(_: Any) -> None:
            values = {f.arg.name: _value(f, h.value) for f, h in zip(fields, handles, strict=True)}
            self._guarded(lambda: self._apply_op(op, ref, values))

        return clicked

    def _later(self, key: str, delay: float, action: Callable[[], None]) -> None:
        """Run ``action`` once typing in ``key`` pauses ``delay`` s (the newest text wins)."""
        with self._lock:
            old = self._timers.pop(key, None)
            if old is not None:
                old[0].cancel()
            if delay <= 0:
                self._guarded(action)
                return
            timer = threading.Timer(delay, lambda: self._guarded(lambda: self._fire(key, timer)))
            timer.daemon = True
            self._timers[key] = (timer, action)
            timer.start()

    def _fire(self, key: str, timer: threading.Timer) -> None:
        """The pause in ``key`` is over: its action, unless it ran already (flushed)."""
        pending = self._timers.get(key)
        if pending is not None and pending[0] is timer:
            del self._timers[key]
            pending[1]()

    def _flush_typing(self) -> None:
        """Apply now what was typed and waits for its pause (a click elsewhere came first)."""
        with self._lock:
            pending, self._timers = list(self._timers.values()), {}
            for timer, action in pending:
                timer.cancel()
                action()

    # ------------------------------------------------------------ the source view

    def _source_typed(self, event: Any) -> None:
        if getattr(event, "client", None) is None:
            return
        text = str(self.source.value)

        def apply_text() -> None:
            if text == self._source_text or self.session is None:
                return
            self._source_text = text
            self.change(lambda s: s.apply(SetSource(text)), from_source=True)

        self._later("source", DEBOUNCE_S, apply_text)


# ---------------------------------------------------------------- helpers


def _located(
    chart: Chart, symbols: SymbolTable | None, blocks: ProgramBlocks | None = None
) -> Located:
    """``check``'s diagnostics of ``chart`` as the source view writes it (line, column),
    its reads of the FBs' variables of the CPU's blocks ``blocks`` and its calls of those
    blocks checked in them (``sequencer.change.edit.diagnostics_of``)."""
    text = format_chart(chart)
    try:
        read = parse_chart(text, chart.file or "chart.s7g")
    except ChartSyntaxError as exc:  # pragma: no cover - the writer's text parses
        return Located(tuple(exc.diagnostics), None)
    try:
        return Located(diagnostics_of(read, symbols, blocks), read)
    except RecursionError:  # pragma: no cover - the session bounds the nesting
        return Located((), read)


def _title(chart: Chart, ref: Ref | None) -> str:
    if ref is None:
        return f"chart {chart.name}"
    element = find(chart, ref)
    name = getattr(element, "name", "")
    if isinstance(ref, StepRef):
        return f"step S{ref.number} {name}".rstrip()
    if isinstance(ref, TransitionRef):
        return f"transition T{ref.number} {name}".rstrip()
    return f"sequencer {getattr(ref, 'number', '')} {name}".rstrip()


def _shown(f: Field) -> object:
    """A field's value as its input shows it (None as 0)."""
    if f.value is None:
        return 0 if f.arg.type.startswith("int") else ""
    return f.value


def _value(f: Field, raw: object) -> object:
    """An input's value as the edit takes it (0 for ``int | None``: None)."""
    if f.arg.type.startswith("int"):
        n = int(raw)  # type: ignore[call-overload]
        return None if n == 0 and f.arg.type == "int | None" else n
    if f.arg.type == "bool":
        return bool(raw)
    return str(raw)
