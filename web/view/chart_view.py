"""The live browser view: a viser scene drawing the chart as S7-GRAPH does, and a side panel.

The scene shows steps as boxes (the initial step double-framed, ``C``/``V`` marks for an
interlock/supervision), transitions as bars with their number, lines, jumps and stops;
it is coloured live (active green, disturbed or latched red, inactive grey). The panel
"Control Sequencer" turns clicks into :class:`Command` s handed to ``send`` — in the app
that is :meth:`web.bus.BusClient.send`, so the view reaches the CPU only over the bus.
"Alarms" lists the CPU's message list (:meth:`ChartView.apply_alarms`) with an Acknowledge
button per unacknowledged message (``ack_msg`` as the operator); "Step details" shows one
step's state, times, interlock and supervision contacts and, per valid transition leaving
it, each contact ✓/✗ (from ``StepStateUpdate.details``) — which contact blocks.
Every dynamic text goes through ``html.escape`` before ``add_html``.
"""

from __future__ import annotations

import functools
import html
import itertools
import math
import threading
import time
from collections import deque
from collections.abc import Callable
from typing import Any

import numpy as np
import viser
from PIL import Image, ImageDraw, ImageFont

from s7graph.web.bus.protocol import (
    AlarmEntry,
    AlarmList,
    ChartLayout,
    Command,
    CommandReply,
    Contact,
    CpuStatus,
    CycleStats,
    StepDetail,
    StepStateUpdate,
)
from s7graph.web.view.layout import Placement, place

__all__ = ["ACTIVE", "DISTURBED", "INACTIVE", "ChartView", "make_server"]

ACTIVE = (40, 170, 60)
DISTURBED = (220, 40, 40)
INACTIVE = (205, 205, 205)
INK = (30, 30, 30)
LANE = 3.0  # scene units per lane
ROW = 0.8  # scene units per row
BOX_W, BOX_H = 1.5, 0.55
BAR_W = 0.55
TEXT_PX = 90  # text layer pixels per scene unit
MAX_FPS = 20.0
LOG_LINES = 40

Sender = Callable[[Command], CommandReply]


def make_server(
    host: str = "127.0.0.1", port: int = 8080, *, label: str = "s7graph"
) -> viser.ViserServer:
    """A viser server bound to ``host`` (loopback by default); read ``get_port()`` after."""
    return viser.ViserServer(host=host, port=port, label=label, verbose=False)


def _xy(x: float, y: float) -> tuple[float, float]:
    return x * LANE, -y * ROW


def _rect(cx: float, cy: float, w: float, h: float) -> list[list[list[float]]]:
    x0, x1, y0, y1 = cx - w / 2, cx + w / 2, cy - h / 2, cy + h / 2
    corners = [(x0, y0), (x1, y0), (x1, y1), (x0, y1), (x0, y0)]
    return [[[a[0], a[1], 0.03], [b[0], b[1], 0.03]] for a, b in itertools.pairwise(corners)]


@functools.cache
def _font(px: int) -> ImageFont.FreeTypeFont | ImageFont.ImageFont:
    return ImageFont.load_default(size=max(px, 6))


def _clip(text: str, n: int) -> str:
    return text if len(text) <= n else text[: n - 1] + "…"


class ChartView:
    """Draws one FB's chart in ``server``'s scene and runs its Control Sequencer panel."""

    def __init__(
        self,
        server: viser.ViserServer,
        layout: ChartLayout,
        send: Sender,
        *,
        user: str = "operator",
    ) -> None:
        self.server = server
        self.layout = layout
        self.placement: Placement = place(layout)
        self._send = send
        self._lock = threading.Lock()
        self._latest: StepStateUpdate | None = None
        self._shown: StepStateUpdate | None = None
        self._wake = threading.Event()
        self._closed = False
        self._log: deque[str] = deque(maxlen=LOG_LINES)
        self._cpu_cycle = 0
        self._cpu_state = "RUN"
        self._cpu_stats: CycleStats | None = None
        self._step_colour: dict[int, tuple[int, int, int]] = {}
        self._alarms: AlarmList | None = None
        self._alarms_shown: AlarmList | None = None
        self._alarm_buttons: dict[int | str, viser.GuiButtonHandle] = {}
        self.replies: list[CommandReply] = []  # every answer the CPU gave this view
        self._draw_chart()
        self._build_panel(user)
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
            self._text(_title("S", s.number, s.name, 12), x, y, "center-center", 0.25)
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
            text = _title("T", t.number, t.name, 12)
            if t.condition:
                text += f"\n{_clip(t.condition, 28)}"
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
            self._text(
                f"Sequence {q.number}  {_clip(q.name, 24)}", x - BOX_W / 2, 0.75, "bottom-left", 0.2
            )
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

    # ------------------------------------------------------------ panel

    def _build_panel(self, user: str) -> None:
        gui = self.server.gui
        gui.set_panel_label(f"S7-GRAPH {self.layout.fb}")
        with gui.add_folder("Control Sequencer"):
            self.status = gui.add_html(self._status_html(None))
            self.mode_buttons = gui.add_button_group("Mode", ["AUTO", "MAN", "TAP", "TOP"])
            self.mode_buttons.on_click(
                lambda ev: self._command(ev, "mode", {"mode": self.mode_buttons.value})
            )
            self.buttons = {
                "init": gui.add_button("Initialize", hint="INIT_SQ: activate the initial steps"),
                "off": gui.add_button("Disable (OFF)", hint="OFF_SQ: deactivate every step"),
                "ack": gui.add_button("Acknowledge", color="red", hint="ACK_EF"),
                "t_push": gui.add_button("T_PUSH (Continue)", hint="Switch a ready transition"),
            }
            for op, button in self.buttons.items():
                button.on_click(self._make_handler(op))
            first = self.layout.steps[0].number if self.layout.steps else 1
            self.step_number = gui.add_number("Step", first, min=1, max=65535, step=1)
            self.activate = gui.add_button("Activate", hint="S_ON: activate the step (MAN)")
            self.deactivate = gui.add_button("Deactivate", hint="S_OFF: deactivate the step")
            self.activate.on_click(
                lambda ev: self._command(ev, "step_on", {"step": int(self.step_number.value)})
            )
            self.deactivate.on_click(
                lambda ev: self._command(ev, "step_off", {"step": int(self.step_number.value)})
            )
            self.operator = gui.add_text("Operator", user)
        with gui.add_folder("Alarms") as self.alarm_folder:
            self.alarm_html = gui.add_html(_alarms_html(None))
        with gui.add_folder("Step details"):
            self.detail_step = gui.add_number(
                "Show step", 0, min=0, max=65535, step=1,
                hint="0: follow the first disturbed, else the first active step",
            )  # fmt: skip
            self.detail_html = gui.add_html(self._detail_html(None))
        self.detail_step.on_update(lambda _: self._refresh())
        with gui.add_folder("Events"):
            self.event_log = gui.add_html(self._log_html())

    def _make_handler(self, op: str) -> Callable[[viser.GuiEvent[viser.GuiButtonHandle]], None]:
        return lambda ev: self._command(ev, op, {})

    def _clicked_step(self, number: int) -> Callable[[object], None]:
        def handler(_: object) -> None:
            # viser defines the value setter apart from its getter, so mypy sees no setter
            self.step_number.value = number  # type: ignore[misc]
            self.detail_step.value = number  # type: ignore[misc]

        return handler

    def _command(self, ev: viser.GuiEvent[Any] | None, op: str, args: dict[str, object]) -> None:
        """Build, send and log one command (runs in viser's callback thread pool)."""
        user = _clip(str(self.operator.value), 64)
        try:
            command = Command(op=op, fb=self.layout.fb, user=user, args=args)  # type: ignore[arg-type]
        except (TypeError, ValueError) as exc:
            reply = CommandReply(applied=False, reason=str(exc), op=op, fb=self.layout.fb)
        else:
            reply = self._send(command)
        self.replies.append(reply)
        verdict = "applied" if reply.applied else f"refused: {reply.reason}"
        self._append_log(f"{op} {_describe(args)} by {user or '?'}: {verdict}")
        if ev is not None and ev.client is not None:
            ev.client.add_notification(
                f"{op} {'applied' if reply.applied else 'refused'}",
                reply.reason or "OK",
                auto_close_seconds=4.0,
                color="green" if reply.applied else "red",
            )

    # ------------------------------------------------------------ live state

    def apply(self, update: StepStateUpdate) -> None:
        """Show ``update`` (thread-safe; the newest one wins, drawn at most ``MAX_FPS``/s)."""
        with self._lock:
            self._latest = update
        for event, step in update.events:
            info = self.layout.step(step)
            name = f" {info.name}" if info and info.name else ""
            self._append_log(f"cycle {update.cycle}: {event} S{step}{name}", render=False)
        self._wake.set()

    def apply_alarms(self, alarms: AlarmList) -> None:
        """Show the CPU's message list (thread-safe; drawn by the render thread)."""
        with self._lock:
            self._alarms = alarms
        self._refresh()

    def _refresh(self) -> None:
        self._shown = None
        self._wake.set()

    def apply_status(self, status: CpuStatus) -> None:
        """Keep the cycle in the status line current between deltas (status comes at 1 Hz)."""
        with self._lock:
            self._cpu_cycle = status.cycle
            self._cpu_state = status.state
            self._cpu_stats = status.stats
        self._shown = None
        self._wake.set()

    def close(self) -> None:
        """Stop the render thread (the server stays the caller's)."""
        self._closed = True
        self._wake.set()
        self._thread.join(timeout=2.0)

    def _render_loop(self) -> None:
        while not self._closed:
            self._wake.wait()
            self._wake.clear()
            if self._closed:
                return
            self._render()
            time.sleep(1.0 / MAX_FPS)

    def _render(self) -> None:
        with self._lock:
            update = self._latest
            alarms = self._alarms
        if alarms is not self._alarms_shown:
            self._render_alarms(alarms)
        if update is None or update is self._shown:
            return
        detail = self._detail_html(update)
        active, bad = set(update.active), set(update.disturbed) | set(update.latched)
        with self.server.atomic():
            for number, box in self.boxes.items():
                colour = DISTURBED if number in bad else ACTIVE if number in active else INACTIVE
                if self._step_colour.get(number) != colour:
                    box.color = colour
                    self._step_colour[number] = colour
            # only what changed goes to the page (a step's T alone changes ten times a second)
            for handle, content in (
                (self.status, self._status_html(update)),
                (self.event_log, self._log_html()),
                (self.detail_html, detail),
            ):
                if handle.content != content:
                    handle.content = content
        self._shown = update

    def _render_alarms(self, alarms: AlarmList | None) -> None:
        """The alarm list and one Acknowledge button per unacknowledged message."""
        self._alarms_shown = alarms
        pending = alarms.pending() if alarms is not None else []
        wanted = {e.msg_id: e for e in pending}
        with self.server.atomic():
            self.alarm_html.content = _alarms_html(alarms)
            for mid in [m for m in self._alarm_buttons if m not in wanted]:
                self._alarm_buttons.pop(mid).remove()
            with self.alarm_folder:
                for mid, entry in wanted.items():
                    if mid not in self._alarm_buttons:
                        button = self.server.gui.add_button(
                            _ack_label(entry), color="red", hint=_clip(entry.text, 200)
                        )
                        button.on_click(self._ack_handler(mid))
                        self._alarm_buttons[mid] = button

    def _ack_handler(
        self, msg_id: int | str
    ) -> Callable[[viser.GuiEvent[viser.GuiButtonHandle]], None]:
        return lambda ev: self._command(ev, "ack_msg", {"msg_id": msg_id})

    def _detail_html(self, update: StepStateUpdate | None) -> str:
        """The "Step details" of the chosen step: why it does (not) switch."""
        number = int(self.detail_step.value) if hasattr(self, "detail_step") else 0
        if number == 0:  # follow: the first disturbed, else the first active step
            if update is None or not update.active:
                return _small("no active step (choose one with <i>Show step</i>)")
            number = (sorted(set(update.disturbed) & set(update.active)) or update.active)[0]
        info = self.layout.step(number)
        if info is None:
            return _small(f"no step S{number} in {self.layout.fb}")
        title = f"<b>{html.escape(_title('S', number, info.name, 24))}</b>"
        if update is None:
            return _small(f"{title}: waiting for the CPU…")
        detail = next((d for d in update.details if d.number == number), None)
        if detail is None:
            rows = [f"{title}: inactive"]
            for t in self.layout.transitions:
                if number in t.sources:
                    cond = html.escape(t.condition or "TRUE")
                    name = html.escape(_title("T", t.number, t.name, 24))
                    rows.append(f"{name}: {cond} <i>(evaluated while the step is active)</i>")
            return _small("<br>".join(rows))
        return _small("<br>".join([title + ": " + _step_state(detail), *_step_rows(detail)]))

    def _append_log(self, line: str, *, render: bool = True) -> None:
        with self._lock:
            self._log.appendleft(line)
        if render:
            self.event_log.content = self._log_html()

    def _log_html(self) -> str:
        with self._lock:
            lines = list(self._log)
        if not lines:
            return '<div style="font-size:0.8em;color:#777">no events yet</div>'
        body = "<br>".join(html.escape(line) for line in lines)
        style = "font-family:monospace;font-size:0.75em;max-height:14em;overflow:auto"
        return f'<div style="{style}">{body}</div>'

    def _status_html(self, update: StepStateUpdate | None) -> str:
        if update is None:
            return '<div style="font-size:0.85em">waiting for the CPU…</div>'
        active = ", ".join(f"S{n}" for n in update.active) or "none"
        parts = [
            f"<b>{html.escape(update.mode)}</b>",
            f"cycle {max(update.cycle, self._cpu_cycle)}",
            f"active: {html.escape(active)}",
        ]
        stats = self._cpu_stats
        if stats is not None and stats.max_ms > 0:
            parts.append(f"cycle time {stats.last_ms:.1f} ms (max {stats.max_ms:.1f})")
        bad = sorted(set(update.disturbed) | set(update.latched))
        if bad:
            errors = ", ".join(f"S{n}" for n in bad)
            parts.append(f'<span style="color:#c00">error: {html.escape(errors)}</span>')
        if self._cpu_state != "RUN":
            parts.insert(0, f'<b style="color:#c00">{html.escape(self._cpu_state)}</b>')
        return f'<div style="font-size:0.85em">{" · ".join(parts)}</div>'


def _title(prefix: str, number: int, name: str, width: int) -> str:
    """``S3  Fill``; just ``S3`` when the name is empty or only repeats the number."""
    short = f"{prefix}{number}"
    return short if name in ("", short) else f"{short}  {_clip(name, width)}"


def _small(body: str) -> str:
    return f'<div style="font-size:0.8em;line-height:1.5">{body}</div>'


def _clock(ms: int | None) -> str:
    return "" if ms is None else time.strftime("%H:%M:%S", time.localtime(ms / 1000))


def _ack_label(entry: AlarmEntry) -> str:
    if entry.step is not None and entry.kind:
        what = "supervision" if entry.kind == "SV" else "interlock"
        return f"Acknowledge S{entry.step} {what}"
    return _clip(f"Acknowledge message {entry.msg_id}", 64)


def _alarms_html(alarms: AlarmList | None) -> str:
    """Every listed message: time, state, text, step, who acknowledged it and when."""
    if alarms is None or not alarms.entries:
        return _small('<span style="color:#777">no messages</span>')
    rows = []
    for e in reversed(alarms.entries):  # newest first
        colour = "#c00" if e.state == "incoming" else "#a60"
        where = f" · S{e.step}" if e.step is not None else ""
        ack = (
            f"acknowledged by {html.escape(e.ack_user or '?')} {_clock(e.ack_ms)}"
            if e.acked
            else "<b>unacknowledged</b>"
        )
        rows.append(
            f'<div style="border-left:3px solid {colour};padding-left:4px;margin-bottom:4px">'
            f'{_clock(e.came_ms)} <span style="color:{colour}">{e.state}</span>'
            f"{html.escape(where)} · {ack}<br>{html.escape(e.text)}</div>"
        )
    return _small("".join(rows))


def _mark(c: Contact) -> str:
    tick = '<span style="color:#080">✓</span>' if c.ok else '<span style="color:#c00">✗</span>'
    return f"&nbsp;&nbsp;{tick} {html.escape(c.text)}"


def _step_state(d: StepDetail) -> str:
    parts = ["active", f"T {d.t_ms / 1000:.1f} s", f"U {d.u_ms / 1000:.1f} s"]
    if d.interlock_error:
        parts.append('<span style="color:#c00">interlock error</span>')
    if d.supervision_fault:
        parts.append('<span style="color:#c00">supervision fault</span>')
    return " · ".join(parts)


def _step_rows(d: StepDetail) -> list[str]:
    rows = []
    if d.interlock:
        state = "holds" if d.interlock_ok else '<span style="color:#c00">lost</span>'
        rows += [f"Interlock (C): {state}", *map(_mark, d.interlock)]
    if d.supervision:
        state = '<span style="color:#c00">fault</span>' if d.supervision_fault else "ok"
        rows += [f"Supervision (V): {state}", *map(_mark, d.supervision)]
    for t in d.transitions:
        holds = "holds" if t.holds else '<span style="color:#c00">does not hold</span>'
        name = html.escape(_title("T", t.number, t.name, 24))
        rows += [f"<b>{name}</b>: {holds}", *map(_mark, t.contacts)]
    if not d.transitions:
        rows.append("no valid transition leaves it (a step before it is inactive)")
    return rows


def _describe(args: dict[str, object]) -> str:
    return " ".join(f"{k}={v}" for k, v in args.items())
