"""The page of a CPU without a chart (a program of blocks, docs/view.md, "A program's page"):
its state and why it stopped, its RUN/STOP switch and memory reset, the messages of its
ALARM_S / ALARM_SQ calls with *Acknowledge* (``web.view.alarms``: an operator's
``ack_msg``), a watch table, its blocks' S7-SCL sources and its diagnostic buffer — no
scene.

Every page has its own login (as the chart's page: ``web.view.page_login``), its own watch
table — operands typed into ``Operands`` (``MW0:INT, Q4.0, DB20.avg``), read at the CPU's
scan boundaries about twice a second while the page is open (``web.bus.watch``), signed by
the page's login while it has one (``web.view.watch_table``) — and the
buttons its role allows (``stop``, ``start``, ``mres``: an engineer's). The Blocks folder
lists the blocks the CPU has a source of (``s7graph/<cpu>/blocks``, read once when the page
opens, again every ``BLOCKS_RETRY_S`` while the CPU does not answer); each button opens the
block's text read-only, read when pressed (``web.view.block_links``); *Cross-references*
lists where each operand of those blocks is used (``web.view.uses_list``). The Diagnostics
folder is :class:`~web.view.diagnostics.DiagnosticsPanel`'s. Every text from the bus or a
user is escaped.
"""

from __future__ import annotations

import contextlib
import functools
import threading
import time
from collections.abc import Callable, Sequence
from typing import Any

import msgspec
import viser

from s7graph.engine.errors import internal_error
from s7graph.sequencer.xref import Use, block_references
from s7graph.web.access.roles import allowed
from s7graph.web.bus.client import BusClient
from s7graph.web.bus.protocol import (
    AlarmList,
    BlockSources,
    ChartLayout,
    Command,
    CommandReply,
    CpuStatus,
    LoginReply,
    WatchValues,
)
from s7graph.web.commands import (
    AckMsg,
    Modify,
    ModifyArgs,
    Mres,
    Start,
    Stop,
    checked,
    op_of,
)
from s7graph.web.view import texts
from s7graph.web.view.alarms import AlarmView
from s7graph.web.view.block_links import BlockButtons, listed_blocks
from s7graph.web.view.confirm import ask
from s7graph.web.view.diagnostics import state_html
from s7graph.web.view.guard import OriginGuard, page_open
from s7graph.web.view.page_login import PageLogin
from s7graph.web.view.uses_list import UsesList, block_key, parsed_blocks
from s7graph.web.view.watch_table import TIMEOUT_S, WatchTable, refresh, watch_html

__all__ = ["ProgramPage", "ProgramView", "blocks_html", "watch_html"]

POLL_S = 0.5
BLOCKS_RETRY_S = 5.0  # the block list asked again while the CPU does not answer
_BUTTONS: tuple[tuple[type[Command], str, dict[str, Any]], ...] = (
    (Stop, "CPU to STOP", {}),
    (Start, "CPU to RUN", {}),
    (Mres, "Memory reset (MRES)", {"color": "red"}),
)


def blocks_html(sources: BlockSources | None) -> str:
    """The line above the Blocks folder's buttons: how many, or why there are none."""
    if sources is None:
        return texts.small('<span style="color:#c00">the CPU does not answer</span>')
    count = len(sources.blocks) + len(sources.left_out)
    if count == 0:
        return texts.small('<span style="color:#777">no S7-SCL blocks (a Python program)</span>')
    return texts.small(f"{count} block{'s' if count != 1 else ''} · the sources, read-only")


class ProgramPage(PageLogin):
    """One browser page of a program's CPU: login, switch, alarms, watch table."""

    def __init__(self, page: viser.ClientHandle, view: ProgramView) -> None:
        self.page, self.view = page, view
        self.client = page  # the AlarmView's page
        self._init_login(page, view.demo)
        gui = page.gui
        gui.set_panel_label(f"s7graph CPU {view.cpu} (a program)")
        self.banner = gui.add_html("")
        self._build_login()
        with gui.add_folder("CPU"):
            self.status = gui.add_html(state_html(None))
            self.buttons = {
                op_of(kind): gui.add_button(label, hint=kind.does.replace("`", ""), **style)
                for kind, label, style in _BUTTONS
            }
        for kind, _, _ in _BUTTONS:
            self.buttons[op_of(kind)].on_click(functools.partial(self._clicked, kind))
        self.alarms = AlarmView(
            self, ChartLayout(fb=view.cpu, steps=[], transitions=[], sequences=[])
        )
        self.alarms_shown: AlarmList | None = None
        self.watch_table = WatchTable(gui, login=self.watch_token)
        with gui.add_folder("Blocks") as folder:
            self.blocks_line = gui.add_html(texts.small("reading the CPU's blocks…"))
        self.blocks = BlockButtons(
            page, folder, view.read_blocks, lambda t, b: self._notify(t, b, ok=False)
        )
        with gui.add_folder("Cross-references", expand_by_default=False):
            self.uses = UsesList(
                page,
                hint="An operand of the program's blocks: where is it used?",
                go=self._open_use,
                guard=self._guarded,
            )
        self.blocks_due: float | None = 0.0  # when to ask for the list (None: listed)
        self._enable()

    def list_blocks(self, sources: BlockSources | None, now: float) -> None:
        """A button per block of ``sources`` (render thread); None: asked again later."""
        self.update_html(self.blocks_line, "blocks", blocks_html(sources))
        if sources is None:
            self.blocks_due = now + BLOCKS_RETRY_S
            return
        self.blocks_due = None
        self.blocks.place(listed_blocks(sources))
        self.uses.show(block_references(parsed_blocks(sources)))

    def _open_use(self, use: Use) -> None:
        """Open the source of the block a use of the cross-references stands in."""
        key = block_key(use.element)
        if key is not None:
            self.blocks.open(key, use.element)

    def _guarded(self, action: Callable[[], object]) -> None:
        """Run a click's action; an unexpected error is a notice, never a dead callback."""
        try:
            action()
        except Exception as exc:
            why = internal_error("in the cross-references", exc)
            self._notify("cross-references", why, ok=False)

    def _enable(self) -> None:
        role = self.role if self.token else "viewer"
        for op, button in self.buttons.items():
            button.disabled = not allowed(role, op)
        self.alarms.enable(allowed(role, op_of(AckMsg)))
        may = allowed(role, op_of(Modify))
        self.watch_table.enable_modify(self._modify if may else None)
        self._show_login()

    def _modify(self, operand: str, value: str) -> None:
        self.command(Modify(fb=self.view.cpu, args=ModifyArgs(address=operand, value=value)))

    def _login(self, user: str, password: str) -> LoginReply:
        return self.view.client.login(user, password, origin=self.origin)

    def _logout(self, token: str, user: str) -> None:
        self.view.client.logout(token, user=user, origin=self.origin)

    def forget(self) -> None:
        """The page went away: revoke its token."""
        self._revoke()

    @property
    def fb(self) -> str:
        """What this page's commands name: the CPU (it runs no FB)."""
        return self.view.cpu

    def _clicked(self, kind: type[Command], _: object) -> None:
        ask(self.page.gui, kind, lambda: self.command(kind))  # STOP, MRES: after a yes

    def command(self, command: Command | type[Command]) -> CommandReply:
        """Send ``command`` (or op ``kind`` without arguments) as this page's user (viser's
        callback thread), with a notice of how it went."""
        if isinstance(command, type):
            command = command(fb=self.view.cpu)
        reply = self.send_quiet(command)
        verdict = "applied" if reply.applied else "refused"
        title = f"{texts.command_words(command)} {verdict}"
        self._notify(title, reply.reason or "OK", ok=reply.applied)
        return reply

    def send_quiet(self, command: Command | type[Command]) -> CommandReply:
        """Send ``command`` as this page's user without a notice."""
        with self._lock:
            user, token = self.user, self.token
        if isinstance(command, type):
            command = command(fb=self.view.cpu)
        made = msgspec.structs.replace(command, user=user, token=token, origin=self.origin)
        try:
            return self.view.client.send(checked(made))
        except (TypeError, ValueError) as exc:
            return CommandReply(applied=False, reason=str(exc), op=made.op)

    def notify(self, title: str, body: str, *, ok: bool) -> None:
        """A notice on this page only."""
        self._notify(title, body, ok=ok)


class ProgramView:
    """The pages of ``server`` for CPU ``cpu`` (no chart), reached through ``client``;
    :meth:`close` stops its thread."""

    def __init__(
        self,
        server: viser.ViserServer,
        client: BusClient,
        *,
        cpu: str,
        demo: bool = True,
        guard: OriginGuard | None = None,
    ) -> None:
        self.server, self.client, self.cpu, self.demo = server, client, cpu, demo
        self._guard = guard
        self._lock = threading.Lock()
        self.pages: dict[int, ProgramPage] = {}
        self.status: CpuStatus | None = None
        self.connected = True
        self._wake = threading.Event()
        self._closed = False
        self.alarms: AlarmList | None = None
        client.on_status(self.apply_status)
        client.on_alarms(self.apply_alarms)
        client.on_alive(self.set_connected)
        server.on_client_connect(self._connect)
        server.on_client_disconnect(self._disconnect)
        server.scene.world_axes.visible = False  # no chart: an empty scene
        self._thread = threading.Thread(target=self._loop, name="s7graph-program", daemon=True)
        self._thread.start()

    def apply_status(self, status: CpuStatus) -> None:
        with self._lock:
            self.status = status
        self._wake.set()

    def apply_alarms(self, alarms: AlarmList) -> None:
        with self._lock:
            self.alarms = alarms
        self._wake.set()

    def set_connected(self, connected: bool) -> None:
        with self._lock:
            self.connected = connected
        self._wake.set()

    def read_blocks(self) -> BlockSources | None:
        """The CPU's S7-SCL sources, or None if it does not answer (or answers garbage)."""
        try:
            return self.client.blocks()
        except Exception:  # an unreadable answer: as no answer, the page says so
            return None

    def _connect(self, page: viser.ClientHandle) -> None:
        if self._guard is not None and self._guard.refused(page.client_id):
            return
        built = ProgramPage(page, self)
        with self._lock:
            gone = not page_open(page)
            if not gone:
                self.pages[page.client_id] = built
        if gone:  # closed while its page was built: never kept
            built.forget()
        self._wake.set()

    def _disconnect(self, page: viser.ClientHandle) -> None:
        with self._lock:
            gone = self.pages.pop(page.client_id, None)
        if gone is not None:
            gone.forget()

    def _loop(self) -> None:
        while not self._closed:
            self._wake.wait(timeout=POLL_S)
            self._wake.clear()
            if self._closed:
                return
            with contextlib.suppress(Exception):  # a page gone mid-update must not stop it
                self._render()

    def _render(self) -> None:
        with self._lock:
            status, connected, pages = self.status, self.connected, list(self.pages.values())
            alarms = self.alarms
        top = texts.banner_html(connected, self.cpu)
        line = _status_html(status) if connected else texts.small("no live state")
        now = time.monotonic()
        due = [p for p in pages if p.blocks_due is not None and p.blocks_due <= now]
        sources = self.read_blocks() if due and connected else None  # no bus: no wait
        for page in due:
            page.list_blocks(sources, now)
        for page in pages:
            page.update_html(page.banner, "banner", top)
            page.update_html(page.status, "status", line)
            if page.alarms_shown is not alarms:
                page.alarms_shown = alarms
                page.alarms.set_alarms(alarms)
        refresh((page.watch_table for page in pages), self._watch)

    def _watch(self, operands: Sequence[str], token: str) -> WatchValues:
        """``operands`` read at the CPU's next scan boundary, signed by the login of
        ``token`` ("": unsigned)."""
        return self.client.watch(operands, timeout=TIMEOUT_S, token=token)

    def close(self) -> None:
        self._closed = True
        self._wake.set()
        self._thread.join(timeout=3.0)


def _status_html(status: CpuStatus | None) -> str:
    """The state (and why it stopped), the cycle, the FORCE mark and the cycle time."""
    if status is None:
        return state_html(None)
    parts = [f"cycle {status.cycle}"]
    stats = status.stats
    if stats is not None and stats.max_ms > 0:
        parts.append(f"cycle time {stats.last_ms:.1f} ms (max {stats.max_ms:.1f})")
    line = texts.small(texts.force_mark(status.forces) + " · ".join(parts))
    return state_html(status) + line
