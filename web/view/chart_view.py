"""The live browser view: a viser scene drawing the chart as S7-GRAPH does, and a panel per page.

The scene shows steps as boxes (the initial step double-framed, ``C``/``V`` marks for an
interlock/supervision) with their action tables and conditions, transitions as bars with
their number, lines, jumps and stops; it is coloured live (active green, disturbed or
latched red, inactive grey), with S7-GRAPH's status over it — the active steps' times and
operand values, the contacts of the conditions evaluated (``web.view.status_layer``) — and
greyed out with a "disconnected" banner while the CPU is unreachable (its ``alive`` token
gone). The side panel is docked right of the chart (nothing is drawn under it), viser's
notice about software WebGL is not shown over the chart, and notices show at its bottom-left.
The scene is shared by every page; each page has its own side panel
(``web.view.panel.ClientPanel``: login, Control Sequencer, alarms, alarm history, audit,
step details, events; an engineer's Force folder), built when the page connects — a page
whose websocket came from a foreign ``Origin`` gets none (``web.view.guard``). Every
dynamic text is escaped (``web.view.texts``).
"""

from __future__ import annotations

import contextlib
import functools
import threading
import time
from collections import deque
from collections.abc import Callable, Iterable
from dataclasses import dataclass, replace
from typing import Any

import viser

from s7graph.web.bus.protocol import (
    AlarmHistory,
    AlarmList,
    AuditEntry,
    BlockSources,
    ChartLayout,
    Command,
    CommandReply,
    CpuStatus,
    CycleStats,
    ForceList,
    LoginReply,
    StepStateUpdate,
)
from s7graph.web.view import texts
from s7graph.web.view.drawing import (
    ACTIVE,
    DISCONNECTED,
    DISTURBED,
    FLAT_LIGHT,
    INACTIVE,
    PANEL_W,
    Drawing,
    camera_for,
    picture,
)
from s7graph.web.view.engineering import Engineering
from s7graph.web.view.guard import OriginGuard, guard_server, page_open
from s7graph.web.view.layout import Placement, place
from s7graph.web.view.panel import ClientPanel, PageState, Wiring
from s7graph.web.view.status_layer import StatusLayer
from s7graph.web.view.sync_view import Sync
from s7graph.web.view.watch_table import POLL_S as WATCH_POLL_S
from s7graph.web.view.watch_table import Watch, refresh

__all__ = ["ACTIVE", "DISCONNECTED", "DISTURBED", "INACTIVE", "ChartView", "make_server"]

MAX_FPS = 20.0
LOG_LINES = 40
AUDIT_ROWS = 50
# viser shows a notice (its DOM id below) when the browser draws WebGL in software; it
# covered the chart's top-left corner and has no theme option, so a page's style hides it.
# viser 1.1.1 also puts every notification (a command's verdict) at the top-left, where the
# chart opens with its first step, with no option to place it elsewhere; the page's style
# moves them to the bottom-left (viser still shifts them right of a panel docked left).
PAGE_STYLE = (
    "<style>#webgl-software-rendering{display:none !important}"
    ".mantine-Notifications-root{top:auto !important;bottom:1em !important}</style>"
)

Sender = Callable[[Command], CommandReply]
LoginCall = Callable[[str, str, str], LoginReply]


def make_server(
    host: str = "127.0.0.1",
    port: int = 8080,
    *,
    label: str = "s7graph",
    allowed_origins: Iterable[str] = (),
) -> tuple[viser.ViserServer, OriginGuard]:
    """A viser server bound to ``host`` (loopback by default) that refuses foreign-Origin
    websockets and has no share tunnel; read ``get_port()`` after."""
    server = viser.ViserServer(host=host, port=port, label=label, verbose=False)
    guard = guard_server(server, allowed_origins)
    server.gui.configure_theme(show_share_button=False, show_logo=False)
    return server, guard


def _refuse_login(user: str, password: str, origin: str) -> LoginReply:
    return LoginReply(ok=False, reason="this view cannot log in")


@dataclass(frozen=True, slots=True)
class _Logged:
    """One line of the event list: a step event and the step's name (None: a step the
    chart known when it came does not have, named when its chart comes)."""

    cycle: int
    event: str
    step: int
    name: str | None = None

    def named(self, layout: ChartLayout) -> _Logged:
        info = layout.step(self.step)
        return self if info is None else replace(self, name=info.name)

    def line(self) -> str:
        name = f" {self.name}" if self.name else ""
        return f"cycle {self.cycle}: {self.event} S{self.step}{name}"


class ChartView:
    """Draws one FB's chart in ``server``'s scene and gives every page its own panel.

    ``send`` carries a page's commands to the CPU (``BusClient.send``), ``login`` /
    ``logout`` its logins (``BusClient.login``/``logout`` as ``(user, secret, origin)``);
    ``demo``: the CPU has no users file (names are claimed). ``history`` fetches the
    alarm history (called from the render thread when the alarm list changed); ``blocks``
    reads the CPU's S7-SCL sources (``BusClient.blocks``) for *Details*' links; ``watch``
    reads operands (``BusClient.watch``) for each page's watch table; ``sync`` judges the
    FB's steps (``BusClient.synchronization``) for each page's *Synchronization*."""

    def __init__(
        self,
        server: viser.ViserServer,
        layout: ChartLayout,
        send: Sender,
        *,
        login: LoginCall = _refuse_login,
        logout: LoginCall = _refuse_login,
        cpu: str = "cpu1",
        demo: bool = True,
        guard: OriginGuard | None = None,
        history: Callable[[], AlarmHistory | None] | None = None,
        engineering: Engineering | None = None,
        blocks: Callable[[], BlockSources | None] | None = None,
        watch: Watch | None = None,
        sync: Sync | None = None,
    ) -> None:
        self.server = server
        self.layout = layout
        self.placement: Placement = place(layout)
        self.cpu = cpu
        self._guard = guard
        self._history_source = history
        self._lock = threading.Lock()
        self._latest: StepStateUpdate | None = None
        self._wake = threading.Event()
        self._closed = False
        self._log: deque[_Logged] = deque(maxlen=LOG_LINES)  # newest first
        self._cpu_cycle = 0
        self._cpu_state = "RUN"
        self._cpu_reason = ""
        self._cpu_stats: CycleStats | None = None
        self._forces: ForceList | None = None
        self._force_count = 0  # force jobs active: the status line's FORCE mark
        self.drawing: Drawing | None = None
        self.status: StatusLayer | None = None
        self._next_layout: ChartLayout | None = None
        self._alarms: AlarmList | None = None
        self._history: AlarmHistory | None = None
        self._history_stale = history is not None
        self._audit: deque[AuditEntry] = deque(maxlen=AUDIT_ROWS)
        self.connected = True
        self.replies: list[CommandReply] = []  # every answer the CPU gave this view
        self.panels: dict[int, ClientPanel] = {}
        self._wiring = Wiring(
            layout,
            cpu,
            send,
            login,
            logout,
            demo,
            self.replies.append,
            engineering,
            self,
            blocks,
            watch,
            sync,
        )
        self._set_scene()
        self._draw_chart()
        server.gui.main_panel.dock_right()  # the canvas ends where the panel starts
        server.gui.main_panel.set_width(PANEL_W)
        server.on_client_connect(self._connect)
        server.on_client_disconnect(self._disconnect)
        self._thread = threading.Thread(target=self._render_loop, name="s7graph-view", daemon=True)
        self._thread.start()
        self._watch = watch
        if watch is not None:  # the watch tables wait for the CPU: never the render thread
            name = "s7graph-view-watch"
            threading.Thread(target=self._watch_loop, name=name, daemon=True).start()

    # ------------------------------------------------------------ scene

    def _set_scene(self) -> None:
        """Up, lights and axes of the scene, once: viser puts every page's camera back to
        its initial pose when the up direction is set, so a redraw must not set it again
        (an editor's page, aimed at the chart it edits, would be turned to the live one)."""
        sc = self.server.scene
        sc.set_up_direction("+y")
        sc.world_axes.visible = False
        sc.configure_default_lights(enabled=False, cast_shadow=False)  # a flat chart: FLAT_LIGHT
        sc.configure_environment_map(None)
        sc.add_light_ambient("/light", intensity=FLAT_LIGHT)

    def _draw_chart(self) -> None:
        """Draw the current chart (once per chart version) and aim new pages' camera at it
        (a page already open keeps its camera)."""
        sc = self.server.scene
        pic = picture(self.placement)
        if self.drawing is not None:
            self.drawing.remove()
        if self.status is not None:
            self.status.remove()
        drawing = Drawing(
            sc, pic, on_step=self._clicked_step, on_transition=self._clicked_transition
        )
        self.picture, self.drawing = pic, drawing
        self.status = StatusLayer(sc, pic)
        cam = self.server.initial_camera
        cam.position, cam.look_at = camera_for(pic)
        cam.up = (0.0, 1.0, 0.0)

    @property
    def boxes(self) -> dict[int, Any]:
        """The live chart's step boxes by step number."""
        return self.drawing.boxes if self.drawing is not None else {}

    def _panel_of(self, event: Any) -> ClientPanel | None:
        client = getattr(event, "client", None)
        return self.panels.get(client.client_id) if client is not None else None

    def _clicked_step(self, number: int, event: Any) -> None:
        panel = self._panel_of(event)
        if panel is not None:  # the clicking page's Step and Show step fields
            panel.show_step(number)
            self._wake.set()

    def _clicked_transition(self, number: int, event: Any) -> None:
        panel = self._panel_of(event)
        if panel is not None:  # the clicking page's details
            panel.show_transition(number)
            self._wake.set()

    def apply_chart(self, layout: ChartLayout) -> None:
        """The CPU runs another chart (a download): draw it (in the render thread). Events
        of steps the old chart did not have (the CPU may publish the new chart's first
        scans before its layout) are named from it."""
        with self._lock:
            if layout.fb == self.layout.fb and layout.version != self.layout.version:
                self._next_layout = layout
                if any(e.name is None for e in self._log):
                    named = [e if e.name is not None else e.named(layout) for e in self._log]
                    self._log = deque(named, maxlen=LOG_LINES)
        self._wake.set()

    def _switch_chart(self) -> None:
        with self._lock:
            layout, self._next_layout = self._next_layout, None
            if layout is None:
                return
            self.layout = layout  # with _next_layout: apply names events from one of them
        self.placement = place(layout)
        with self.server.atomic():
            self._draw_chart()
        with self._lock:
            panels = list(self.panels.values())
        for panel in panels:
            panel.chart_changed(layout)  # and fitted to the chart as it is now

    def latest(self) -> StepStateUpdate | None:
        """The newest state shown (for an editor: the active steps of the running chart)."""
        with self._lock:
            return self._latest

    # ------------------------------------------------------------ pages

    def _connect(self, client: viser.ClientHandle) -> None:
        if self._guard is not None and self._guard.refused(client.client_id):
            return  # closed for its foreign Origin: no panel, nothing sent
        client.gui.add_html(PAGE_STYLE)
        with self._lock:
            status = self._status_line()
        panel = ClientPanel(client, self._wiring, status)
        panel.opened_at(self.server.initial_camera.position)  # fitted once it says its canvas
        with self._lock:
            gone = not page_open(client)
            if not gone:
                self.panels[client.client_id] = panel
        if gone:  # closed while its panel was built: never kept
            panel.forget()
        self._wake.set()

    def _disconnect(self, client: viser.ClientHandle) -> None:
        with self._lock:
            panel = self.panels.pop(client.client_id, None)
        if panel is not None:
            panel.forget()

    # ------------------------------------------------------------ live state

    def apply(self, update: StepStateUpdate) -> None:
        """Show ``update`` (thread-safe; the newest one wins: its step colours at once, the
        rest at most ``MAX_FPS`` times a second)."""
        with self._lock:
            self._latest = update
            layout = self._next_layout or self.layout  # the newest chart known
            for event, step in update.events:
                self._log.appendleft(_Logged(update.cycle, event, step).named(layout))
        self._wake.set()

    def events(self) -> list[str]:
        """The event list as the pages show it, newest first."""
        with self._lock:
            return self._event_lines()

    def _event_lines(self) -> list[str]:
        return [e.line() for e in self._log]

    def apply_alarms(self, alarms: AlarmList) -> None:
        """Show the CPU's message list (thread-safe; drawn by the render thread)."""
        with self._lock:
            self._alarms = alarms
            self._history_stale = self._history_source is not None
        self._wake.set()

    def apply_audit(self, entry: AuditEntry) -> None:
        """Add one audit row (the CPU publishes each as it writes it), or count it up: a
        row of refusals is published again, with its ``id``, as its count grows."""
        with self._lock:
            if not self._audit or entry.id > self._audit[-1].id:
                self._audit.append(entry)
            else:
                for i, shown in enumerate(self._audit):
                    if shown.id == entry.id and entry.count > shown.count:
                        self._audit[i] = entry
        self._wake.set()

    def apply_audit_list(self, entries: Iterable[AuditEntry]) -> None:
        """Start the Audit panel from the CPU's last rows (of two of one row: the higher
        count)."""
        with self._lock:
            merged: dict[int, AuditEntry] = {}
            for e in [*entries, *self._audit]:
                if e.id not in merged or e.count > merged[e.id].count:
                    merged[e.id] = e
            self._audit.clear()
            self._audit.extend(merged[k] for k in sorted(merged)[-AUDIT_ROWS:])
        self._wake.set()

    def apply_status(self, status: CpuStatus) -> None:
        """Keep the cycle in the status line current between deltas (status comes at 1 Hz)."""
        with self._lock:
            self._cpu_cycle = status.cycle
            self._cpu_state = status.state
            self._cpu_reason = status.reason
            self._cpu_stats = status.stats
            self._force_count = status.forces
        self._wake.set()

    def apply_forces(self, forces: ForceList) -> None:
        """Show the CPU's force jobs (the FORCE mark and an engineer's list)."""
        with self._lock:
            self._forces = forces
            self._force_count = len(forces.entries)
        self._wake.set()

    def set_connected(self, connected: bool) -> None:
        """The CPU's ``alive`` token came or went: grey the chart and say so, or recover."""
        with self._lock:
            self.connected = connected
            if self.drawing is not None:
                self.drawing.forget_colours()  # repaint every box
        self._wake.set()

    def close(self) -> None:
        """Stop the render thread (the server stays the caller's)."""
        self._closed = True
        self._wake.set()
        self._thread.join(timeout=2.0)

    def _render_loop(self) -> None:
        """Each wake-up paints the step boxes at once (``_paint_steps``: a change of the
        active steps is in the pages one websocket frame later); the rest — the live layer,
        the bars, every page's panel — at most ``MAX_FPS`` times a second, counted from the
        start of the last full render, and once a second without a wake-up."""
        due = 0.0  # the earliest start of the next full render
        pending = False
        while not self._closed:
            wait = max(0.0, due - time.monotonic()) if pending else 1.0
            woke = self._wake.wait(timeout=wait)
            if self._closed:
                return
            if woke:
                self._wake.clear()
                pending = True
                with contextlib.suppress(Exception):  # a page gone mid-update
                    self._paint_steps()
            if pending and time.monotonic() < due:
                continue
            pending = False
            due = time.monotonic() + 1.0 / MAX_FPS
            with contextlib.suppress(Exception):  # a page gone mid-update must not stop it
                self._render()

    def _watch_loop(self) -> None:
        """Every ``POLL_S`` the pages' watch tables read (``web.view.watch_table``)."""
        watch = self._watch
        assert watch is not None
        while not self._closed:
            with self._lock:
                tables = [p.watch_table for p in self.panels.values() if p.watch_table]
            with contextlib.suppress(Exception):  # a page gone mid-update must not stop it
                refresh(tables, watch)
            time.sleep(WATCH_POLL_S)

    def _render(self) -> None:
        if self._history_stale and self._history_source is not None:
            self._history_stale = False
            try:
                self._history = self._history_source()
            except Exception:
                self._history_stale = True
        with self._lock:
            update, connected = self._latest, self.connected
            page = PageState(
                banner=texts.banner_html(connected, self.cpu),
                status=self._status_line(),
                mode=update.mode if update is not None and connected else None,
                alarms=self._alarms,
                history=texts.history_html(self._history),
                audit=texts.audit_html(list(self._audit)),
                events=texts.log_html(self._event_lines()),
                forces=texts.forces_html(self._forces),
                step=texts.followed_step(update) if connected else 0,
                permanent=texts.permanent_html(self.layout, update if connected else None),
            )
            panels = list(self.panels.values())
        self._switch_chart()
        self._paint(update, connected)
        layout = self.layout

        def describe(key: tuple[str, int]) -> str:
            kind, number = key
            if kind == "T":
                return texts.transition_html(layout, update, number)
            return texts.detail_html(layout, update, number)

        detail = functools.lru_cache(maxsize=8)(describe)
        halted = bool(update is not None and update.halted)
        for panel in panels:
            try:
                panel.show(page, detail, halted)
                panel.client.flush()  # its panel now, not at the end of viser's window
            except Exception:
                continue

    def _status_line(self) -> str:
        """The status line as the pages show it now (call with the lock held)."""
        if not self.connected:
            return texts.small("no live state")
        return texts.status_html(
            self._latest,
            self._cpu_cycle,
            self._cpu_state,
            self._cpu_stats,
            self._force_count,
            self._cpu_reason,
        )

    def _colours(self, update: StepStateUpdate | None, connected: bool) -> dict[int, Any]:
        """Each step box's colour but inactive grey (every box's when disconnected)."""
        assert self.drawing is not None
        if not connected:
            return dict.fromkeys(self.drawing.boxes, DISCONNECTED)
        if update is None:
            return {}
        bad = set(update.disturbed) | set(update.latched)
        colours = {n: ACTIVE for n in update.active if n in self.drawing.boxes}
        colours.update({n: DISTURBED for n in bad if n in self.drawing.boxes})
        return colours

    def _paint_steps(self) -> None:
        """Send the step boxes' colours now, if they changed (a few bytes: the boxes that
        changed), and have viser send them without its 1/60 s window."""
        with self._lock:
            update, connected = self._latest, self.connected
        if (update is None and connected) or self.drawing is None:
            return
        if self.drawing.paint_steps(self._colours(update, connected)):
            self.server.flush()

    def _paint(self, update: StepStateUpdate | None, connected: bool) -> None:
        if (update is None and connected) or self.drawing is None:
            return
        colours = self._colours(update, connected)
        with self.server.atomic():
            holds = (
                self.status.show(update, connected, time.monotonic())
                if self.status is not None
                else set()
            )
            self.drawing.paint(colours, dict.fromkeys(holds, ACTIVE))
        self.server.flush()
