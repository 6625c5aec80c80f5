"""The editor's commands to the CPU: Save, Open, New, Download and Undo download; and
Save to this computer (the chart being edited, downloaded by the browser).

The chart is checked as the CPU compiles a download of it: with the interfaces of the
user blocks the CPU runs (:func:`cpu_blocks`: the S7-SCL sources of its chart's source,
compiled here, or the interfaces it sends when those do not give them all — a Python
program's blocks), whose FBs' variables it reads by name (``"Motor_DB".Running``) and
whose blocks it calls (a call that does not fit its block is E047 in the page, as the
download refuses it).

Each is the engineer's command on the bus (checked and audited in the CPU); a download and
its undo ask the CPU for the change summary first and confirm it in a modal. ``CpuCommands``
is a part of ``web.view.editor.Editor``, which owns the attributes it declares.
"""

from __future__ import annotations

import contextlib
import functools
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import PurePath
from typing import TYPE_CHECKING, Any, Final

import msgspec
import viser

from s7graph.engine.errors import S7Error
from s7graph.engine.symbols import SymbolTable
from s7graph.sequencer.change.base import EditRefused, Refusal
from s7graph.sequencer.change.edit import Session, new_chart
from s7graph.sequencer.change.typed import parse_source
from s7graph.sequencer.checks.diagnostics import Diagnostic
from s7graph.sequencer.checks.interfaces import ProgramBlocks
from s7graph.sequencer.text.format import format_chart
from s7graph.sequencer.text.model import Chart
from s7graph.sequencer.text.parse import ChartSyntaxError
from s7graph.web.bus.protocol import ChartSource, CommandReply, ProtocolError
from s7graph.web.commands import (
    Command,
    Download,
    DownloadArgs,
    Open,
    OpenArgs,
    Save,
    SaveArgs,
    UndoArgs,
    UndoDownload,
)
from s7graph.web.harness.project import CHART_CHOICE, chart_file
from s7graph.web.harness.scl import ChartBlocks, SclLoadError
from s7graph.web.harness.session import add_chart_symbols
from s7graph.web.view import texts
from s7graph.web.view.confirm import question
from s7graph.web.view.engineering import EditorPage

__all__ = ["MAX_DIAGNOSTIC_BUTTONS", "CpuCommands", "Located", "cpu_blocks", "refused"]

MAX_DIAGNOSTIC_BUTTONS: Final = 25


@dataclass(frozen=True, slots=True)
class Located:
    """The diagnostics of the chart as the source view shows it (lines and columns of that
    text), and the chart read back from it (to find the element of a diagnostic)."""

    diagnostics: tuple[Diagnostic, ...]
    chart: Chart | None


class CpuCommands:
    """Files and downloads of the chart being edited, and how the CPU's answers show."""

    panel: EditorPage
    client: viser.ClientHandle
    eng: Any
    host: Any
    session: Session | None
    base: ChartSource | None
    symbols: SymbolTable | None
    interfaces: ProgramBlocks | None  # of the CPU's S7-SCL blocks (``cpu_blocks``)
    located: Located
    note: str
    file: viser.GuiTextHandle
    open_choice: viser.GuiDropdownHandle[Any]
    chart_choices: dict[str, tuple[str, str]]  # an Open file choice → (file, chart)
    _modal: Any

    if TYPE_CHECKING:

        def _show(self, *, source_changed: bool) -> None: ...

        def _click(self, action: Callable[[], object]) -> Callable[[Any], None]: ...

        def leave(self) -> None: ...

        def _place_aside(self) -> None: ...

    def leave_asked(self) -> None:
        """Leave edit mode — after a yes when the chart edited is not the one the CPU runs
        (what was not downloaded would be dropped without a word)."""
        if not self._unsent():
            self.leave()
            return
        if self._modal is not None:
            with contextlib.suppress(Exception):
                self._modal.close()
            self._modal = None
        question(
            self.client.gui,
            "Leave edit mode",
            "The chart edited is not the one the CPU runs: leaving drops the edits not "
            "downloaded (*Save to this computer* keeps them in a file).",
            "Leave and drop the edits",
            functools.partial(self._click(self.leave), None),
            no="Stay in edit mode",
        )

    def _unsent(self) -> bool:
        """Whether the chart edited differs from the one the CPU runs (by their text as the
        editor writes charts)."""
        s = self.session
        if s is None or s.undo_label is None:
            return False
        if self.base is None:
            return True
        try:
            running = parse_source(self.base.text, self.base.file or "chart.s7g")
        except EditRefused:
            return True
        return format_chart(s.chart) != format_chart(running)

    def _refresh_files(self) -> None:
        listed = self.eng.project()
        names = [f.name for f in listed.files] if listed is not None else []
        self.chart_choices = {}
        self.open_choice.options = names or ["(none)"]

    def _offer_charts(self, file: str, reply: CommandReply) -> bool:
        """A file that holds several charts: each chart (``file » chart``, the CPU's
        refusal lists them) becomes a choice of *Open file*, right after the file, the
        first one chosen; False when the refusal is another one."""
        head = CHART_CHOICE.format(file=file, chart="")
        offered = {line: (file, line[len(head) :]) for line in reply.lines if line.startswith(head)}
        if not offered:
            return False
        self.chart_choices = {**self.chart_choices, **offered}
        options = [o for o in self.open_choice.options if o not in offered]
        at = options.index(file) + 1 if file in options else len(options)
        self.open_choice.options = [*options[:at], *offered, *options[at:]]
        self.open_choice.value = next(iter(offered))  # type: ignore[misc]
        self._notify(f"{file}: choose a chart", f"{reply.reason} in Open file", ok=True)
        return True

    def save(self) -> None:
        if self.session is None:
            return
        name = str(self.file.value).strip()
        source = format_chart(self.session.chart)
        reply = self._command(Save(fb=self.panel.fb, args=SaveArgs(file=name, source=source)))
        self._report("save", reply)
        if reply.applied:
            self._refresh_files()

    def save_here(self) -> None:
        """The chart being edited, as a file the browser saves (named as *File*, or
        ``<FB>.s7g``): the page's "Upload from device", with the edits so far."""
        if self.session is None:
            return
        stem = PurePath(str(self.file.value).strip().replace("\\", "/")).stem
        name = f"{stem or self.panel.fb}.s7g"
        text = format_chart(self.session.chart).encode()
        self.client.send_file_download(name, text, save_immediately=True)

    def open(self) -> None:
        name = str(self.open_choice.value)
        if name == "(none)":
            self._refresh_files()
            return
        file, pou = self.chart_choices.get(name, (name, None))
        args = OpenArgs(file=file) if pou is None else OpenArgs(file=file, pou=pou)
        reply = self._command(Open(fb=self.panel.fb, args=args))
        if not reply.applied:
            if not self._offer_charts(file, reply):
                self._report("open", reply)
            return
        try:
            chart = parse_source(reply.text, name if name.endswith(".s7g") else f"{name}.s7g")
            session = Session.open(chart, self.symbols, self.interfaces)
        except EditRefused as exc:
            self._notify("open refused", exc.reason, ok=False)
            return
        self.session = session
        self.file.value = chart_file(file, pou, ".s7g")  # type: ignore[misc]
        self.note = "opened " + name + ("".join(f"; {x}" for x in reply.lines[:3]))
        self._place_aside()  # another chart: the page aims at it, the form waits aside
        self._show(source_changed=True)

    def new(self) -> None:
        running = self.session.chart if self.session is not None else None
        name = running.name if running is not None else self.host.layout.fb
        try:
            chart = new_chart(
                name, running.fb_number if running else None, running.db_number if running else None
            )
            self.session = Session.open(chart, self.symbols, self.interfaces)
        except EditRefused as exc:
            self._notify("new refused", exc.reason, ok=False)
            return
        self.note = "a new chart: S1 and T1 (Insert: select T1, Step + Transition)"
        self._place_aside()
        self._show(source_changed=True)

    def download(self) -> None:
        """Compile (here: the diagnostics), ask the CPU for the change summary, confirm."""
        s = self.session
        if s is None:
            return
        if s.has_errors:
            errors = [texts.diagnostic_line(d) for d in self.located.diagnostics if d.is_error]
            self.note = f"download refused: the chart has {len(errors)} error(s)"
            self._notify("download refused", "; ".join(errors[:3]) or self.note, ok=False)
            self._show(source_changed=False)
            return
        text = format_chart(s.chart)
        fb = self.panel.fb
        # the version this edit was made from: a CPU that runs another one (someone else
        # downloaded meanwhile) refuses, rather than the edit silently undoing theirs
        args = DownloadArgs(source=text, preview=True)
        if self.base is not None:
            args = msgspec.structs.replace(args, base=self.base.version)
        reply = self._command(Download(fb=fb, args=args))
        if not reply.applied:
            self._report("download", reply)
            return
        self._confirm(
            "Download into the CPU", reply, Download(fb=fb, args=DownloadArgs(source=text))
        )

    def undo_download(self) -> None:
        fb = self.panel.fb
        reply = self._command(UndoDownload(fb=fb, args=UndoArgs(preview=True)))
        if not reply.applied:
            self._report("undo download", reply)
            return
        self._confirm("Undo the last download", reply, UndoDownload(fb=fb))

    def _confirm(self, title: str, preview: CommandReply, command: Download | UndoDownload) -> None:
        """The change summary and the choice; ``command`` (with the version the summary is
        of, and the choice) on confirmation."""
        gui = self.client.gui
        if self._modal is not None:
            with contextlib.suppress(Exception):
                self._modal.close()
        base = preview.version
        removed = list(preview.removed)
        with gui.add_modal(title) as modal:
            self._modal = modal
            gui.add_html(texts.lines_html(preview.lines, heading="What changes"))
            done = "Download to the CPU" if isinstance(command, Download) else "Undo the download"
            choices: list[tuple[str, str | None]] = (
                [("Keep the other steps", "keep"), ("Initialize the sequencer", "init")]
                if removed
                else [(done, None)]
            )
            for label, choice in choices:
                button = gui.add_button(label, color="orange")
                button.on_click(
                    self._click(functools.partial(self._confirmed, command, base, choice))
                )
            gui.add_button("Cancel").on_click(lambda _: modal.close())

    def _confirmed(
        self, command: Download | UndoDownload, base: int | None, removed: str | None
    ) -> None:
        if self._modal is not None:
            with contextlib.suppress(Exception):
                self._modal.close()
            self._modal = None
        args = command.args
        if base is not None:
            args = msgspec.structs.replace(args, base=base)
        if removed is not None:
            args = msgspec.structs.replace(args, removed=removed)
        reply = self._command(msgspec.structs.replace(command, args=args))
        self._report(command.op.replace("_", " "), reply)
        if reply.applied:
            source, why = self._source()
            if why:
                self._notify("chart source", why, ok=False)
            if source is not None:
                self._blocks_of(source)
                self.base = source
                if isinstance(command, UndoDownload):
                    with contextlib.suppress(EditRefused, ChartSyntaxError):
                        chart = parse_source(source.text, source.file or "chart.s7g")
                        self.session = Session.open(chart, self.symbols, self.interfaces)
            self.note = f"the CPU runs version {reply.version}" + (
                f": {reply.lines[0]}" if reply.lines else ""
            )
            self._show(source_changed=isinstance(command, UndoDownload))

    def _blocks_of(self, source: ChartSource) -> None:
        """The interfaces of the user blocks the CPU runs now, when they are not those
        of the chart source read before (an undo, someone else's download): the session
        checked against them from now on."""
        if self.base is not None and (self.base.blocks, self.base.interfaces) == (
            source.blocks,
            source.interfaces,
        ):
            return
        with contextlib.suppress(EditRefused, ChartSyntaxError):
            running = parse_source(source.text, source.file or "chart.s7g")
            self.interfaces, note = cpu_blocks(source, running)
            if note:
                self._notify("S7-SCL blocks", note, ok=False)
            if self.session is not None:
                self.session = self.session.with_blocks(self.interfaces)

    def _source(self) -> tuple[ChartSource | None, str]:
        """The chart the CPU runs (``fb/<fb>/source``), or None and why when its answer does
        not decode (a broken or hostile CPU: the page goes on); None and "" when it does not
        answer."""
        try:
            return self.eng.source(), ""
        except ProtocolError as exc:
            return None, f"the CPU's chart cannot be read: {exc}"

    def _command(self, command: Command) -> CommandReply:
        return self.panel.engineer_command(command)

    def _report(self, what: str, reply: CommandReply) -> None:
        verdict = "applied" if reply.applied else "refused"
        body = reply.reason or (reply.lines[0] if reply.lines else "OK")
        self._notify(f"{what} {verdict}", body, ok=reply.applied)
        if not reply.applied:
            self.note = f"{what} refused: {reply.reason}"
            if self.session is not None:
                diags = reply.lines[:MAX_DIAGNOSTIC_BUTTONS]
                self.session = refused(
                    self.session,
                    EditRefused(
                        f"{what} refused: {reply.reason}" + ("".join(f"; {x}" for x in diags[:5]))
                    ),
                )
            self._show(source_changed=False)

    def _notify(self, title: str, body: str, *, ok: bool) -> None:
        with contextlib.suppress(Exception):
            self.client.add_notification(
                title,
                texts.clip(body, 400),
                auto_close_seconds=6.0,
                color="green" if ok else "red",
            )


def cpu_blocks(source: ChartSource, chart: Chart) -> tuple[ProgramBlocks | None, str]:
    """The interfaces of the user blocks the CPU runs beside its ``chart``: those it sends
    with its chart ``source`` when its S7-SCL sources do not give them all (a Python
    program's blocks, sources too large to come along); else its sources, compiled here
    as the CPU compiled them (``web.harness.scl.ChartBlocks``, with its symbol table and
    the chart's ``SYMBOLS``) — or None (no blocks) and a note saying why when they cannot
    be (a source too large to come with the chart from a CPU that sends no interfaces,
    one that does not compile)."""
    if source.interfaces is not None:  # those the CPU holds, as its download reads them
        return source.interfaces.program(), ""
    if not source.blocks and not source.left_out:
        return None, ""
    if source.left_out:
        files = ", ".join(source.left_out)
        return None, (
            f"the CPU's S7-SCL sources {files} are too large to come with its chart: its "
            "reads of their FBs' variables by name (E048) and its calls of their blocks "
            "(E047) cannot be checked here"
        )
    try:
        table = SymbolTable.from_text(source.symbols) if source.symbols else SymbolTable()
        add_chart_symbols(chart, table)
        program = ChartBlocks.of_texts(list(source.blocks.items()))(table)
    except SclLoadError as exc:
        first = exc.lines[0] if exc.lines else str(exc)
        return None, f"the CPU's S7-SCL sources do not compile here: {first}"
    except (S7Error, RecursionError) as exc:
        return None, f"the CPU's S7-SCL sources do not compile here: {exc}"
    return program, ""


def refused(session: Session, exc: EditRefused) -> Session:
    """``session`` with ``exc`` as its refusal (the edit or command changed nothing)."""
    return replace(session, refusal=Refusal(exc.reason, exc.diagnostics))
