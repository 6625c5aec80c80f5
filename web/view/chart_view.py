"""The live browser view: a viser scene drawing the chart as S7-GRAPH does, and a panel per page.

The scene shows steps as boxes (the initial step double-framed, ``C``/``V`` marks for an
interlock/supervision), transitions as bars with their number, lines, jumps and stops;
it is coloured live (active green, disturbed or latched red, inactive grey) and greyed out
with a "disconnected" banner while the CPU is unreachable (its ``alive`` token gone).
The scene is shared by every page; each page has its own side panel
(``web.view.panel.ClientPanel``: login, Control Sequencer, alarms, alarm history, audit,
step details, events), built when the page connects — a page whose websocket came from a
foreign ``Origin`` gets none (``web.view.guard``). Every dynamic text is escaped
(``web.view.texts``).
"""

from __future__ import annotations

import contextlib
import functools
import itertools
import math
import threading
import time
from collections import deque
from collections.abc import Callable, Iterable
from typing import Any

import numpy as np
import viser
from PIL import Image, ImageDraw, ImageFont

from s7graph.web.bus.protocol import (
    AlarmHistory,
    AlarmList,
    AuditEntry,
    ChartLayout,
    Command,
    CommandReply,
    CpuStatus,
    CycleStats,
    LoginReply,
    StepStateUpdate,
)
from s7graph.web.view import texts
from s7graph.web.view.guard import OriginGuard, guard_server
from s7graph.web.view.layout import Placement, place
from s7graph.web.view.panel import ClientPanel, PageState, Wiring

__all__ = ["ACTIVE", "DISCONNECTED", "DISTURBED", "INACTIVE", "ChartView", "make_server"]

ACTIVE = (40, 170, 60)
DISTURBED = (220, 40, 40)
INACTIVE = (205, 205, 205)
DISCONNECTED = (238, 238, 238)  # every step, while the CPU is unreachable
INK = (30, 30, 30)
LANE = 3.0  # scene units per lane
ROW = 0.8  # scene units per row
BOX_W, BOX_H = 1.5, 0.55
BAR_W = 0.55
TEXT_PX = 90  # text layer pixels per scene unit
MAX_FPS = 20.0
LOG_LINES = 40
AUDIT_ROWS = 50

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
    return server, guard_server(server, allowed_origins)


def _refuse_login(user: str, password: str, origin: str) -> LoginReply:
    return LoginReply(ok=False, reason="this view cannot log in")


def _xy(x: float, y: float) -> tuple[float, float]:
    return x * LANE, -y * ROW


def _rect(cx: float, cy: float, w: float, h: float) -> list[list[list[float]]]:
    x0, x1, y0, y1 = cx - w / 2, cx + w / 2, cy - h / 2, cy + h / 2
    corners = [(x0, y0), (x1, y0), (x1, y1), (x0, y1), (x0, y0)]
    return [[[a[0], a[1], 0.03], [b[0], b[1], 0.03]] for a, b in itertools.pairwise(corners)]


@functools.cache
def _font(px: int) -> ImageFont.FreeTypeFont | ImageFont.ImageFont:
    return ImageFont.load_default(size=max(px, 6))


class ChartView:
    """Draws one FB's chart in ``server``'s scene and gives every page its own panel.

    ``send`` carries a page's commands to the CPU (``BusClient.send``), ``login`` /
    ``logout`` its logins (``BusClient.login``/``logout`` as ``(user, secret, origin)``);
    ``demo``: the CPU has no users file (names are claimed). ``history`` fetches the
    alarm history (called from the render thread when the alarm list changed)."""

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
        self._log: deque[str] = deque(maxlen=LOG_LINES)
        self._cpu_cycle = 0
        self._cpu_state = "RUN"
        self._cpu_stats: CycleStats | None = None
        self._step_colour: dict[int, tuple[int, int, int]] = {}
        self._alarms: AlarmList | None = None
        self._alarms_html = texts.alarms_html(None)
        self._history: AlarmHistory | None = None
        self._history_stale = history is not None
        self._audit: deque[AuditEntry] = deque(maxlen=AUDIT_ROWS)
        self.connected = True
        self.replies: list[CommandReply] = []  # every answer the CPU gave this view
        self.panels: dict[int, ClientPanel] = {}
        self._wiring = Wiring(layout, cpu, send, login, logout, demo, self.replies.append)
        self._draw_chart()
        server.on_client_connect(self._connect)
        server.on_client_disconnect(self._disconnect)
        self._thread = threading.Thread(target=self._render_loop, name="s7graph-view", daemon=True)
        self._thread.start()

    # ------------------------------------------------------------ scene

    def _draw_chart(self) -> None:
        sc = self.server.scene
        p = self.placement
        sc.set_up_direction("+y")
        sc.world_axes.visible = False
        self._aim_camera()
        self.server.initial_camera.up = (0.0, 1.0, 0.0)

        self._texts: list[tuple[str, float, float, str, float]] = []
        segments: list[list[list[float]]] = []
        double: list[list[list[float]]] = []
        for link in p.links:
            pts = [_xy(x, y) for x, y in link.points]
            for (ax, ay), (bx, by) in itertools.pairwise(pts):
                if link.double and ay == by:
                    for d in (-0.035, 0.035):
                        double.append([[ax, ay + d, 0.0], [bx, by + d, 0.0]])
                else:
                    segments.append([[ax, ay, 0.0], [bx, by, 0.0]])

        self.boxes = {}
        for s in p.steps.values():
            x, y = _xy(s.x, s.y)
            box = sc.add_box(
                f"/chart/step/S{s.number}",
                color=INACTIVE,
                dimensions=(BOX_W, BOX_H, 0.04),
                position=(x, y, 0.0),
            )
            box.on_click(self._clicked_step(s.number))
            self.boxes[s.number] = box
            segments += _rect(x, y, BOX_W, BOX_H)
            if s.initial:  # S7-GRAPH draws the initial step with a double frame
                segments += _rect(x, y, BOX_W + 0.12, BOX_H + 0.12)
            self._text(texts.title("S", s.number, s.name, 12), x, y, "center-center", 0.25)
            if s.interlock:
                segments += _rect(x - BOX_W / 2 - 0.14, y, 0.22, 0.28)
                self._text("C", x - BOX_W / 2 - 0.14, y, "center-center", 0.2)
            if s.supervision:
                segments += _rect(x + BOX_W / 2 + 0.14, y, 0.22, 0.28)
                self._text("V", x + BOX_W / 2 + 0.14, y, "center-center", 0.2)

        for t in p.transitions.values():
            x, y = _xy(t.x, t.y)
            sc.add_box(
                f"/chart/trans/T{t.number}",
                color=INK,
                dimensions=(BAR_W, 0.07, 0.04),
                position=(x, y, 0.0),
            )
            text = texts.title("T", t.number, t.name, 12)
            if t.condition:
                text += f"\n{texts.clip(t.condition, 28)}"
            self._text(text, x + BAR_W / 2 + 0.08, y + 0.12, "top-left", 0.19)

        for j in p.jumps:
            x, y = _xy(j.x, j.y)
            tip = y - 0.32
            segments += [
                [[x, y + 0.35, 0.0], [x, tip, 0.0]],
                [[x - 0.1, tip + 0.14, 0.0], [x, tip, 0.0]],
                [[x + 0.1, tip + 0.14, 0.0], [x, tip, 0.0]],
            ]
            self._text(f"S{j.target}", x + 0.12, tip + 0.05, "center-left", 0.22)
        sources: dict[int, list[int]] = {}
        for inc in p.incoming_jumps:
            sources.setdefault(inc.step, []).append(inc.transition)
        for number, transitions in sources.items():
            target = p.steps[number]
            sx, y = _xy(target.x, target.y)
            end = sx - BOX_W / 2 - (0.3 if target.interlock else 0.04)
            start = end - 0.55
            segments += [
                [[start, y, 0.0], [end, y, 0.0]],
                [[end - 0.12, y + 0.08, 0.0], [end, y, 0.0]],
                [[end - 0.12, y - 0.08, 0.0], [end, y, 0.0]],
            ]
            names = ", ".join(f"T{t}" for t in sorted(set(transitions)))
            self._text(names, start - 0.04, y, "center-right", 0.19)
        for stop in p.stops:
            x, y = _xy(stop.x, stop.y)
            segments += [
                [[x, y + 0.4, 0.0], [x, y - 0.1, 0.0]],
                [[x - 0.2, y - 0.1, 0.0], [x + 0.2, y - 0.1, 0.0]],
            ]
            self._text("STOP", x + 0.25, y - 0.1, "center-left", 0.18)
        for q in p.sequences:
            x, _ = _xy(q.x0, 0)
            title = f"Sequence {q.number}  {texts.clip(q.name, 24)}"
            self._text(title, x - BOX_W / 2, 0.75, "bottom-left", 0.2)
        if segments:
            sc.add_line_segments(
                "/chart/lines",
                np.array(segments, np.float32),
                colors=INK,
                thickness=2.0,
                thickness_units="screen",
            )
        if double:
            sc.add_line_segments(
                "/chart/double",
                np.array(double, np.float32),
                colors=INK,
                thickness=1.5,
                thickness_units="screen",
            )
        self._draw_text_layer()

    def _text(self, text: str, x: float, y: float, anchor: str, height: float) -> None:
        """Queue one text for the text layer (scene coordinates, anchor as viser's labels)."""
        self._texts.append((text, x, y, anchor, height))

    def _draw_text_layer(self) -> None:
        """Every text of the chart on one transparent image just above the chart.

        One texture rather than a viser label per text: labels take tens of seconds to
        appear under software WebGL (SwiftShader), an image appears with the chart."""
        if not self._texts:
            return
        rendered = []
        for text, x, y, anchor, height in self._texts:
            font = _font(round(height * TEXT_PX))
            lines = text.split("\n")
            w = max(font.getlength(line) for line in lines) / TEXT_PX
            h = height * 1.25 * len(lines)
            vertical, _, horizontal = anchor.partition("-")
            left = x - {"left": 0.0, "center": w / 2, "right": w}[horizontal]
            top = y + {"top": 0.0, "center": h / 2, "bottom": h}[vertical]
            rendered.append((lines, font, left, top, height))
        x0 = min(r[2] for r in rendered) - 0.1
        x1 = max(r[2] + max(r[1].getlength(t) for t in r[0]) / TEXT_PX for r in rendered) + 0.1
        y1 = max(r[3] for r in rendered) + 0.1
        y0 = min(r[3] - r[4] * 1.25 * len(r[0]) for r in rendered) - 0.1
        size = (round((x1 - x0) * TEXT_PX), round((y1 - y0) * TEXT_PX))
        image = Image.new("RGBA", size, (255, 255, 255, 0))
        draw = ImageDraw.Draw(image)
        for lines, font, left, top, height in rendered:
            for i, line in enumerate(lines):
                px = (left - x0) * TEXT_PX
                py = (y1 - top + i * height * 1.25) * TEXT_PX
                draw.text((px, py), line, font=font, fill=(0, 0, 0, 255))
        self.server.scene.add_image(
            "/chart/text",
            np.ascontiguousarray(np.asarray(image)[::-1]),  # the plane shows rows bottom-up
            render_width=x1 - x0,
            render_height=y1 - y0,
            format="png",
            position=((x0 + x1) / 2, (y0 + y1) / 2, 0.05),
            cast_shadow=False,
            receive_shadow=False,
        )

    def _aim_camera(self, aspect: float = 1.6, panel: float = 0.28) -> None:
        """Look straight down at the chart so it fits the part of the page left of the panel."""
        p = self.placement
        xs = [x for s in p.steps.values() for x in (s.x * LANE - 2.3, s.x * LANE + BOX_W / 2)]
        xs += [t.x * LANE + 1.6 for t in p.transitions.values()]  # room for the bar's text
        ys = [-y * ROW for y in (0.0, p.height + 0.2)]
        ys.append(1.0)  # the sequence titles
        x0, x1, y0, y1 = min(xs, default=0.0), max(xs, default=1.0), min(ys), max(ys)
        tan = math.tan(self.server.initial_camera.fov / 2)
        z = max((y1 - y0) / 2 / tan, (x1 - x0) / 2 / (tan * aspect * (1 - panel))) * 1.08
        visible_width = 2 * z * tan * aspect
        cx, cy = (x0 + x1) / 2 + visible_width * panel / 2, (y0 + y1) / 2
        cam = self.server.initial_camera
        cam.position, cam.look_at, cam.up = (cx, cy, z), (cx, cy, 0.0), (0.0, 1.0, 0.0)

    def _clicked_step(self, number: int) -> Callable[[Any], None]:
        def handler(event: Any) -> None:
            client = getattr(event, "client", None)
            panel = self.panels.get(client.client_id) if client is not None else None
            if panel is not None:  # the clicking page's Step and Show step fields
                # viser defines the value setter apart from its getter: mypy sees no setter
                panel.step_number.value = number  # type: ignore[misc]
                panel.detail_step.value = number  # type: ignore[misc]
                self._wake.set()

        return handler

    # ------------------------------------------------------------ pages

    def _connect(self, client: viser.ClientHandle) -> None:
        if self._guard is not None and self._guard.refused(client.client_id):
            return  # closed for its foreign Origin: no panel, nothing sent
        panel = ClientPanel(client, self._wiring)
        with self._lock:
            self.panels[client.client_id] = panel
        self._wake.set()

    def _disconnect(self, client: viser.ClientHandle) -> None:
        with self._lock:
            panel = self.panels.pop(client.client_id, None)
        if panel is not None:
            panel.forget()

    # ------------------------------------------------------------ live state

    def apply(self, update: StepStateUpdate) -> None:
        """Show ``update`` (thread-safe; the newest one wins, drawn at most ``MAX_FPS``/s)."""
        with self._lock:
            self._latest = update
            for event, step in update.events:
                info = self.layout.step(step)
                name = f" {info.name}" if info and info.name else ""
                self._log.appendleft(f"cycle {update.cycle}: {event} S{step}{name}")
        self._wake.set()

    def apply_alarms(self, alarms: AlarmList) -> None:
        """Show the CPU's message list (thread-safe; drawn by the render thread)."""
        html = texts.alarms_html(alarms)
        with self._lock:
            self._alarms, self._alarms_html = alarms, html
            self._history_stale = self._history_source is not None
        self._wake.set()

    def apply_audit(self, entry: AuditEntry) -> None:
        """Add one audit row (the CPU publishes each as it writes it)."""
        with self._lock:
            if not self._audit or entry.id > self._audit[-1].id:
                self._audit.append(entry)
        self._wake.set()

    def apply_audit_list(self, entries: Iterable[AuditEntry]) -> None:
        """Start the Audit panel from the CPU's last rows."""
        with self._lock:
            merged = {e.id: e for e in [*entries, *self._audit]}
            self._audit.clear()
            self._audit.extend(merged[k] for k in sorted(merged)[-AUDIT_ROWS:])
        self._wake.set()

    def apply_status(self, status: CpuStatus) -> None:
        """Keep the cycle in the status line current between deltas (status comes at 1 Hz)."""
        with self._lock:
            self._cpu_cycle = status.cycle
            self._cpu_state = status.state
            self._cpu_stats = status.stats
        self._wake.set()

    def set_connected(self, connected: bool) -> None:
        """The CPU's ``alive`` token came or went: grey the chart and say so, or recover."""
        with self._lock:
            self.connected = connected
            self._step_colour.clear()  # repaint every box
        self._wake.set()

    def close(self) -> None:
        """Stop the render thread (the server stays the caller's)."""
        self._closed = True
        self._wake.set()
        self._thread.join(timeout=2.0)

    def _render_loop(self) -> None:
        while not self._closed:
            self._wake.wait(timeout=1.0)
            self._wake.clear()
            if self._closed:
                return
            with contextlib.suppress(Exception):  # a page gone mid-update must not stop it
                self._render()
            time.sleep(1.0 / MAX_FPS)

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
                status=texts.status_html(
                    update, self._cpu_cycle, self._cpu_state, self._cpu_stats
                )
                if connected
                else texts.small("no live state"),
                mode=update.mode if update is not None and connected else None,
                alarms=self._alarms,
                alarms_html=self._alarms_html,
                history=texts.history_html(self._history),
                audit=texts.audit_html(list(self._audit)),
                events=texts.log_html(list(self._log)),
            )
            panels = list(self.panels.values())
        self._paint(update, connected)
        detail = functools.lru_cache(maxsize=8)(
            lambda number: texts.detail_html(self.layout, update, number)
        )
        halted = bool(update is not None and update.halted)
        for panel in panels:
            try:
                panel.show(page, detail, halted)
            except Exception:
                continue

    def _paint(self, update: StepStateUpdate | None, connected: bool) -> None:
        if update is None and connected:
            return
        active = set(update.active) if update is not None else set()
        bad = set(update.disturbed) | set(update.latched) if update is not None else set()
        with self.server.atomic():
            for number, box in self.boxes.items():
                if not connected:
                    colour = DISCONNECTED
                elif number in bad:
                    colour = DISTURBED
                else:
                    colour = ACTIVE if number in active else INACTIVE
                if self._step_colour.get(number) != colour:
                    box.color = colour
                    self._step_colour[number] = colour
