"""The page's Diagnostics folder: the CPU's RUN/STOP state with why it stopped, and its
diagnostic buffer as STEP 7's "Module Information → Diagnostic Buffer" lists it (docs/view.md,
"Diagnostics").

:class:`DiagSource` keeps what the bus says — the buffer (``diag``, then each ``diag/new``
publication; fetched again after a gap or when the CPU's process restarted), the state and
the STOP's entries (``status``); :class:`DiagnosticsPanel` gives every page of a viser
server a Diagnostics folder and keeps it current from a thread of its own (a page whose
websocket came from a foreign ``Origin`` gets none). Every text from the bus is escaped.
"""

from __future__ import annotations

import contextlib
import html
import threading
import time
from collections.abc import Callable

import viser

from s7graph.web.bus.client import BusClient
from s7graph.web.bus.protocol import CpuStatus, DiagBuffer, DiagEvent
from s7graph.web.view.guard import OriginGuard, page_open

__all__ = ["DiagSource", "DiagnosticsPanel", "diagnostics_html", "event_html", "state_html"]

SHOWN = 100
"""Entries the folder lists at most (the CPU's buffer holds 100 by default)."""
MAX_FPS = 5.0
LAST = 1e9
"""The folder's place on a page: below the others, those built later too (a Force folder
at login)."""


def _small(body: str) -> str:
    return f'<div style="font-size:0.8em;line-height:1.45">{body}</div>'


def _when(event: DiagEvent) -> str:
    if event.wall_ms:
        seconds, ms = divmod(event.wall_ms, 1000)
        return time.strftime("%Y-%m-%d %H:%M:%S", time.localtime(seconds)) + f".{ms:03d}"
    return f"CPU clock {event.t_ms / 1000:.3f} s"


def event_html(event: DiagEvent, no: int | None = None) -> str:
    """One entry: (its number,) time, ``16#xxxx``, OB and priority class, text, and what
    it says (block, address, message) below."""
    head = [f"<b>{no}</b>"] if no is not None else []
    head += [html.escape(_when(event)), f"<code>16#{event.event_id:04X}</code>"]
    if event.ob:
        head.append(f"OB{event.ob} · priority class {event.priority}")
    where = " ".join(p for p in (event.block, f"@{event.address}" if event.address else "") if p)
    said = f"{where}: {event.info}" if where and event.info else where or event.info
    body = f"<b>{html.escape(event.text)}</b>"
    if said:
        body += f"<br>{html.escape(said)}"
    return f"{' · '.join(head)}<br>{body}"


def state_html(status: CpuStatus | None) -> str:
    """The CPU's RUN/STOP state, and in STOP why: the reason, the STOP's entry and the
    error entry that caused it."""
    if status is None:
        return _small('<span style="color:#777">waiting for the CPU…</span>')
    colour = "#080" if status.state == "RUN" else "#c00"
    parts = [f'<b style="color:{colour}">{html.escape(status.state)}</b>']
    if status.state == "STOP" and status.reason:
        parts.append(f'<div style="color:#c00">{html.escape(status.reason)}</div>')
    for what, event in (("STOP entry", status.stop), ("caused by", status.cause)):
        if event is not None and status.state == "STOP":
            style = "border-left:3px solid #c00;padding-left:4px;margin-top:3px"
            parts.append(f'<div style="{style}"><i>{what}</i> · {event_html(event)}</div>')
    return _small("".join(parts))


def diagnostics_html(buffer: DiagBuffer | None, status: CpuStatus | None) -> str:
    """The folder's content: the state (``state_html``), then the buffer, newest first
    (No. 1 the newest, as a programming device numbers them)."""
    top = state_html(status)
    if buffer is None:
        return top + _small('<span style="color:#777">diagnostic buffer: no answer yet</span>')
    if not buffer.entries:
        return top + _small('<span style="color:#777">the diagnostic buffer is empty</span>')
    stop_number = status.stop.number if status is not None and status.stop is not None else -1
    rows = []
    for no, event in enumerate(buffer.entries[:SHOWN], 1):
        colour = (
            "#c00" if event.number == stop_number or event.event_id >> 8 in (0x25, 0x45) else "#999"
        )
        style = f"border-left:3px solid {colour};padding-left:4px;margin-bottom:4px"
        rows.append(f'<div style="{style}">{event_html(event, no)}</div>')
    box = "max-height:420px;overflow-y:auto;margin-top:6px"
    return top + _small(f'<div style="{box}">{"".join(rows)}</div>')


class DiagSource:
    """The diagnostic buffer and the CPU's state as the bus gives them (thread-safe):
    ``changed`` is set on every change. ``fetch()`` asks for the whole buffer (None: no
    answer), called at the start and after a gap in the publications."""

    def __init__(self, fetch: Callable[[], DiagBuffer | None]) -> None:
        self._fetch = fetch
        self._lock = threading.Lock()
        self.buffer: DiagBuffer | None = None
        self.status: CpuStatus | None = None
        self.changed = threading.Event()
        self._stale = True

    def apply_new(self, new: DiagBuffer) -> None:
        """A ``diag/new`` publication: its entries go on top, unless some were missed or
        the numbering began again (another CPU process): then fetch it all."""
        with self._lock:
            have = self.buffer
            if have is None or new.total - len(new.entries) != have.total:
                self._stale = True
            else:
                entries = (new.entries + have.entries)[:SHOWN]
                self.buffer = DiagBuffer(total=new.total, capacity=new.capacity, entries=entries)
        self.changed.set()

    def apply_status(self, status: CpuStatus) -> None:
        with self._lock:
            before = self.status
            self.status = status
            if before is not None and status.cycle < before.cycle:  # a new CPU process
                self._stale = True
        if before is None or (before.state, before.reason, before.stop) != (
            status.state,
            status.reason,
            status.stop,
        ):
            self.changed.set()

    def refresh(self) -> None:
        """Fetch the whole buffer if a gap asked for it (not on a zenoh thread)."""
        with self._lock:
            stale, self._stale = self._stale, False
        if not stale:
            return
        try:
            fetched = self._fetch()
        except Exception:
            fetched = None
        with self._lock:
            if fetched is None:
                self._stale = True
            else:
                self.buffer = fetched
        self.changed.set()

    def html(self) -> str:
        with self._lock:
            buffer, status = self.buffer, self.status
        return diagnostics_html(buffer, status)


class DiagnosticsPanel:
    """A Diagnostics folder on every page of ``server`` for the CPU ``client`` reads;
    :meth:`close` stops its thread (the server and the client stay the caller's)."""

    def __init__(
        self,
        server: viser.ViserServer,
        client: BusClient,
        *,
        guard: OriginGuard | None = None,
        expand: bool = False,
    ) -> None:
        self.source = DiagSource(lambda: client.diag(SHOWN))
        self._guard = guard
        self._expand = expand
        self._lock = threading.Lock()
        self._pages: dict[int, viser.GuiHtmlHandle] = {}
        self._shown = ""
        self._closed = False
        client.on_diag(self.source.apply_new)
        client.on_status(self.source.apply_status)
        server.on_client_connect(self._connect)
        server.on_client_disconnect(self._disconnect)
        self._thread = threading.Thread(target=self._loop, name="s7graph-diag", daemon=True)
        self._thread.start()

    def _connect(self, page: viser.ClientHandle) -> None:
        if self._guard is not None and self._guard.refused(page.client_id):
            return
        folder = page.gui.add_folder("Diagnostics", order=LAST, expand_by_default=self._expand)
        with folder:
            handle = page.gui.add_html(self.source.html())
        with self._lock:
            if page_open(page):  # not one closed while its folder was built
                self._pages[page.client_id] = handle

    def _disconnect(self, page: viser.ClientHandle) -> None:
        with self._lock:
            self._pages.pop(page.client_id, None)

    def _loop(self) -> None:
        while not self._closed:
            self.source.changed.wait(timeout=2.0)
            self.source.changed.clear()
            if self._closed:
                return
            self.source.refresh()
            content = self.source.html()
            with self._lock:
                pages = list(self._pages.values())
                fresh = content != self._shown
                self._shown = content
            for handle in pages if fresh else ():
                with contextlib.suppress(Exception):  # a page gone meanwhile
                    handle.content = content
            time.sleep(1.0 / MAX_FPS)

    def close(self) -> None:
        self._closed = True
        self.source.changed.set()
        self._thread.join(timeout=2.0)
