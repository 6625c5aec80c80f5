"""One browser page's side panel: its own login, its own Control Sequencer, its own alarms.

Every page is a session of its own (viser's per-client GUI, ``client.gui``): its ``User``
and ``Password`` fields, ``Log in`` / ``Log out``, and the token the CPU gave it are never
seen by another page. The password goes from the page to this view process only, which
logs in at the CPU by SCRAM-SHA-256 and signs the page's commands with the session key
(``web.bus.client.BusClient``); the CPU never sees it. Until it logs in a page is a
viewer: every command button is disabled (and the CPU refuses commands without a valid
token anyway); after login the buttons its role allows (``web.access.roles``) are
enabled, and a page whose role may ``force`` gets a Force folder (address, value, Force /
Modify (once, not held) / Unforce / Unforce all, the active jobs). The current mode is
highlighted on its button. Command verdicts come back as notifications on this page only.
The Alarms folder (``web.view.alarms``) filters the message list and acknowledges all of
it; *Watch* is the watch table (``web.view.watch_table``); *Synchronization* finds where the
process stands in the chart (``web.view.sync_view``); *Chart view* fits the chart to
the page, and for a chart of several sequences shows one of them or all (an overview).
*Details* links a step's ``CALL`` rows to the S7-SCL source of the blocks they call
(``web.view.block_links``) and offers an engineer *Modify to 1/0* on the contacts it shows
(``web.view.contact_modify``).
"""

from __future__ import annotations

import functools
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Final

import msgspec
import viser

from s7graph.web.access.roles import allowed
from s7graph.web.bus.protocol import (
    AlarmList,
    BlockSources,
    ChartLayout,
    Command,
    CommandReply,
    LoginReply,
)
from s7graph.web.commands import (
    MODES,
    Ack,
    AckStep,
    Force,
    ForceArgs,
    Halt,
    Init,
    Mode,
    ModeArgs,
    Modify,
    ModifyArgs,
    Mres,
    Off,
    OnArgs,
    SetMode,
    SetSteps,
    Start,
    StepArgs,
    StepOff,
    StepOn,
    StepsArgs,
    Stop,
    TPush,
    checked,
    op_of,
)
from s7graph.web.view import texts
from s7graph.web.view.alarms import AlarmView
from s7graph.web.view.block_links import BlockLinks
from s7graph.web.view.confirm import ask
from s7graph.web.view.contact_modify import ContactModify
from s7graph.web.view.drawing import aim_camera, same_canvas
from s7graph.web.view.editor import Editor
from s7graph.web.view.engineering import Engineering, ViewHost
from s7graph.web.view.page_login import PageLogin
from s7graph.web.view.sync_view import Sync, SyncView
from s7graph.web.view.watch_table import Watch, WatchTable

__all__ = ["ClientPanel", "PageState", "Wiring"]

CURRENT_MODE_COLOUR: Final = "green"
# The Control Sequencer's buttons: the op's struct, the label (and a colour); Halt's
# argument is the button's state, the others take none.
_CONTROL_BUTTONS: Final[tuple[tuple[type[Command], str, dict[str, Any]], ...]] = (
    (Init, "Initialize", {}),
    (Off, "Disable (OFF)", {}),
    (Ack, "Acknowledge", {"color": "red"}),
    (TPush, "T_PUSH (Continue)", {}),
    (Halt, "Halt", {}),
    (Stop, "CPU to STOP", {}),
    (Start, "CPU to RUN", {}),
    (Mres, "Memory reset (MRES)", {"color": "red"}),
)
# The step buttons: the op's struct (its argument: the Step field), the label.
_STEP_BUTTONS: Final[tuple[tuple[type[Command], str], ...]] = (
    (StepOn, "Activate"),
    (StepOff, "Deactivate"),
    (SetSteps, "Only this step"),
    (AckStep, "Acknowledge step"),
)


def _hint(kind: type[Command]) -> str:
    """A button's hint: the op's pin and what it does, as the role table says."""
    does = kind.does.replace("`", "")
    return f"{kind.pin}: {does}" if kind.pin else does


@dataclass(frozen=True, slots=True)
class Wiring:
    """What a panel talks to: the FB, the bus calls, the mode (demo: no users file)."""

    layout: ChartLayout
    cpu: str
    send: Callable[[Command], CommandReply]
    login: Callable[[str, str, str], LoginReply]
    logout: Callable[[str, str, str], LoginReply]
    demo: bool
    on_reply: Callable[[CommandReply], None]
    engineering: Engineering | None = None  # None: this view cannot edit (no bus for it)
    host: ViewHost | None = None
    blocks: Callable[[], BlockSources | None] | None = None  # the CPU's S7-SCL sources
    watch: Watch | None = None  # the CPU's watch (BusClient.watch): the watch table
    sync: Sync | None = None  # the FB's synchronization (BusClient.synchronization)


@dataclass(frozen=True, slots=True)
class PageState:
    """What every page shows, computed once per render (HTML already escaped)."""

    banner: str
    status: str
    mode: str | None
    alarms: AlarmList | None  # each page lists it through its own filter (web.view.alarms)
    history: str
    audit: str
    events: str
    forces: str = ""
    step: int = 0  # the step Details follows when none is chosen (0: none active)
    permanent: str = ""  # the permanent instructions with their values ("": none)


class ClientPanel(PageLogin):
    """The side panel of one browser page (``client``)."""

    def __init__(self, client: viser.ClientHandle, wiring: Wiring, status: str = "") -> None:
        """``status``: the status line as the view shows it now (empty: waiting for the
        CPU)."""
        self.client = client
        self.wiring = wiring
        self._init_login(client, wiring.demo)
        self._focus: int | None = None  # the sequence Chart view shows (None: all)
        self._fit: Callable[[], tuple[float, float, float] | None] = lambda: None
        self._ours: deque[tuple[float, ...]] = deque(maxlen=8)  # where the view put the camera
        self._canvas: tuple[int, int] = (0, 0)
        self._mode: str | None = None
        self._alarms: AlarmList | None = None
        self.force_folder: viser.GuiFolderHandle | None = None
        self.contact_modify: ContactModify | None = None  # an engineer's, in Details
        self.permanent_folder: viser.GuiFolderHandle | None = None
        self._build(status or texts.status_html(None, 0, "RUN", None))

    # ------------------------------------------------------------ building

    def _build(self, status: str) -> None:
        """The panel, its status line and controls sent first (a page mounts and paints
        them before the folders below, which take the page longer to mount)."""
        gui = self.client.gui
        w = self.wiring
        gui.set_panel_label(f"S7-GRAPH {w.layout.fb} on {w.cpu}")
        self.banner = gui.add_html("")
        self._build_login()
        with gui.add_folder("Control Sequencer") as self.control_folder:
            self.status = gui.add_html(status)
            self._shown["status"] = status
            self.mode_buttons = {m: gui.add_button(m, hint=f"SW_{m}") for m in MODES}
            for mode, button in self.mode_buttons.items():
                button.on_click(self._on_click(functools.partial(self._switch_mode, mode)))
            # a button per op (web.commands): its hint is the op's pin and what it does
            self.buttons: dict[str, viser.GuiButtonHandle] = {
                op_of(kind): gui.add_button(label, hint=_hint(kind), **style)
                for kind, label, style in _CONTROL_BUTTONS
            }
            for kind, _, _ in _CONTROL_BUTTONS:
                make = self._halt if kind is Halt else functools.partial(self._plain, kind)
                self.buttons[op_of(kind)].on_click(self._on_click(make, kind))
            first = w.layout.steps[0].number if w.layout.steps else 1
            # no min or max: the browser would clamp a number typed out of range silently;
            # the command is refused instead, saying the range
            self.step_number = gui.add_number("Step", first, step=1)
            self.step_buttons = {
                op_of(kind): gui.add_button(label, hint=_hint(kind))
                for kind, label in _STEP_BUTTONS
            }
            for kind, _ in _STEP_BUTTONS:
                make = functools.partial(self._step, kind)
                self.step_buttons[op_of(kind)].on_click(self._on_click(make))
        self._enable_controls()
        self.client.flush()
        self.alarms = AlarmView(self, w.layout)
        self.alarm_folder = self.alarms.folder
        with gui.add_folder("Alarm history", expand_by_default=False):
            self.history_html = gui.add_html(texts.history_html(None))
        with gui.add_folder("Audit", expand_by_default=False):
            self.audit_html = gui.add_html(texts.audit_html([]))
        with gui.add_folder("Details") as self.details_folder:
            self.detail_step = gui.add_number(
                "Show step",
                0,
                min=0,
                max=65535,
                step=1,
                hint="0: follow the first disturbed, else the first active step",
            )
            self.detail_transition = gui.add_number(
                "Show transition",
                0,
                min=0,
                max=65535,
                step=1,
                hint="a transition's whole condition (or click it on the chart); 0: none",
            )
            self.detail_html = gui.add_html(texts.small("waiting for the CPU…"))
            self.detail_step.on_update(lambda _: self._clear_transition())
        self.block_links = BlockLinks(
            self.client,
            self.details_folder,
            w.layout,
            w.blocks,
            lambda t, b: self._notify(t, b, ok=False),
        )
        self._permanent(texts.permanent_html(w.layout, None))
        self.watch_table = (
            WatchTable(gui, expand=False, login=self.watch_token) if w.watch is not None else None
        )
        self.sync_view = (
            SyncView(gui, w.sync, scene=self.client.scene, places=self._step_places)
            if w.sync is not None
            else None
        )
        several = len(w.layout.sequences) > 1
        with gui.add_folder("Chart view", expand_by_default=several) as self.view_folder:
            self.sequence_buttons = self._sequence_buttons(w.layout)
            whole = gui.add_button("Whole chart", hint="zoom out to the whole chart")
            near = gui.add_button("Readable zoom", hint="back to the default zoom")
            whole.on_click(lambda _: self.aim(whole=True))
            near.on_click(lambda _: self.aim(whole=False))
        self.editor: Editor | None = None
        with gui.add_folder("Events"):
            self.event_log = gui.add_html(texts.log_html([]))
        self._halted = False
        self._enable()
        self.client.camera.on_update(self._camera_moved)

    def _enable(self) -> None:
        """Enable exactly the buttons this page's role allows; an engineer gets the editor."""
        role = self.role if self.token else "viewer"
        self._editor_for(role)
        self._force_for(role)
        self._contact_modify_for(role)
        if self.watch_table is not None:
            may = allowed(role, "modify")
            self.watch_table.enable_modify(self._modify_operand if may else None)
        if self.sync_view is not None:
            may = allowed(role, "set_steps")
            self.sync_view.enable_activate(self._activate_step if may else None)
        self._enable_controls()
        self.alarms.enable(allowed(role, "ack_msg"))

    def _enable_controls(self) -> None:
        """The login and *Control Sequencer*'s buttons as this page's role allows."""
        role = self.role if self.token else "viewer"
        for mode_button in self.mode_buttons.values():
            mode_button.disabled = not allowed(role, "mode")
        for op, button in {**self.buttons, **self.step_buttons}.items():
            button.disabled = not allowed(role, op)
        self._show_login()

    def _editor_for(self, role: str) -> None:
        """Build the editor for a page whose role may download; drop it for any other."""
        w = self.wiring
        wanted = allowed(role, "download") and w.engineering is not None and w.host is not None
        if wanted and self.editor is None:
            self.editor = Editor(self)
        elif not wanted and self.editor is not None:
            editor, self.editor = self.editor, None
            editor.close()

    def _force_for(self, role: str) -> None:
        """The Force folder for a page whose role may force; gone for any other."""
        wanted = allowed(role, "force")
        if wanted and self.force_folder is None:
            gui = self.client.gui
            with gui.add_folder("Force", expand_by_default=False) as self.force_folder:
                self.force_address = gui.add_text(
                    "Address", "", hint="I, Q or M: I0.3, QW4, M10.1, or a symbol"
                )
                self.force_value = gui.add_text(
                    "Value", "", hint="TRUE/FALSE, a number or an S7 literal (16#00FF, T#5S)"
                )
                force = gui.add_button("Force", color="yellow", hint="hold it at the value")
                modify = gui.add_button(
                    "Modify", hint="write the value once; the program may write it again"
                )
                unforce = gui.add_button("Unforce", hint="give it back to the program")
                unforce_all = gui.add_button("Unforce all", hint="delete every force job")
                self.force_html = gui.add_html(texts.forces_html(None))
            self._shown.pop("forces", None)
            force.on_click(lambda _: self._force(True))
            modify.on_click(lambda _: self._modify())
            unforce.on_click(lambda _: self._force(False))
            unforce_all.on_click(self._on_click(self._unforce_all))
        elif not wanted and self.force_folder is not None:
            folder, self.force_folder = self.force_folder, None
            folder.remove()

    def _contact_modify_for(self, role: str) -> None:
        """*Modify to 1/0* of a contact in *Details* for a page whose role may modify."""
        wanted = allowed(role, "modify")
        if wanted and self.contact_modify is None:
            layout = self.block_links.layout
            self.contact_modify = ContactModify(
                self.client, self.details_folder, layout, self._modify_operand
            )
        elif not wanted and self.contact_modify is not None:
            shown, self.contact_modify = self.contact_modify, None
            shown.remove()

    def _permanent(self, content: str) -> None:
        """The *Permanent instructions* folder while the chart has some (``content``), with
        their values; gone while it has none."""
        if content and self.permanent_folder is None:
            gui = self.client.gui
            with gui.add_folder("Permanent instructions") as self.permanent_folder:
                self.permanent_html = gui.add_html(content)
            self._shown["permanent"] = content
        elif not content and self.permanent_folder is not None:
            folder, self.permanent_folder = self.permanent_folder, None
            folder.remove()
        elif content:
            self.update_html(self.permanent_html, "permanent", content)

    def _force(self, on: bool) -> None:
        address = str(self.force_address.value).strip()
        value = str(self.force_value.value).strip() if on else None
        self.command(Force(fb=self.fb, args=ForceArgs(address=address, value=value)))

    def _modify(self) -> None:
        self._modify_operand(str(self.force_address.value), str(self.force_value.value))

    def _modify_operand(self, operand: str, value: str) -> None:
        args = ModifyArgs(address=operand.strip(), value=value.strip())
        self.command(Modify(fb=self.fb, args=args))

    # ------------------------------------------------------------ the chart

    def show_step(self, number: int) -> None:
        """A click on step ``number``: it goes into the Step fields and the details."""
        if self.editor is not None and self.editor.editing:
            return
        # viser defines the value setter apart from its getter: mypy sees no setter
        self.step_number.value = number  # type: ignore[misc]
        self.detail_step.value = number  # type: ignore[misc]
        self.detail_transition.value = 0  # type: ignore[misc]

    def show_transition(self, number: int) -> None:
        """A click on transition ``number``: its whole condition goes into the details."""
        if self.editor is not None and self.editor.editing:
            return
        self.detail_transition.value = number  # type: ignore[misc]

    def _clear_transition(self) -> None:
        self.detail_transition.value = 0  # type: ignore[misc]

    def aim(self, *, whole: bool) -> None:
        """Aim this page's camera at the live chart (the sequence chosen in *Chart view*,
        else all of it): the whole of it, or readably."""
        host = self.wiring.host
        pic = getattr(host, "picture", None)
        if pic is None or (self.editor is not None and self.editor.editing):
            if self.editor is not None and self.editor.editing:
                self.editor.aim(whole=whole)
            return
        self.fit(functools.partial(self._aim_live, whole=whole))

    def _aim_live(self, *, whole: bool) -> tuple[float, float, float] | None:
        pic = getattr(self.wiring.host, "picture", None)
        if pic is None:
            return None
        bounds = pic.sequence_bounds.get(self._focus) if self._focus is not None else None
        return aim_camera(self.client, pic, whole=whole, bounds=bounds)

    def fit(self, aim: Callable[[], tuple[float, float, float] | None]) -> None:
        """Aim the page's camera with ``aim``, and again whenever the page's canvas changes
        size (a panel docked or undocked, the window resized) while the camera is still
        where ``aim`` put it: an aim made before the page had docked its panel fits it."""
        self._fit = aim
        aimed = aim()
        if aimed is not None:
            self._ours.append(aimed)

    def opened_at(self, position: Any) -> None:
        """The page opened with its camera at ``position`` (the view's initial camera,
        aimed for the usual canvas): fitted again once the page says its canvas."""
        self._ours.append(tuple(float(v) for v in position))
        self._fit = functools.partial(self._aim_live, whole=False)

    def _camera_moved(self, camera: Any) -> None:
        """The page reported its camera: on a canvas of another size, fit again unless the
        camera is somewhere the user moved it (not where the view put it)."""
        canvas = (int(camera.image_width), int(camera.image_height))
        if canvas == self._canvas or same_canvas(self._canvas, canvas):
            return  # the same canvas, or only drawn at another resolution
        self._canvas = canvas
        at = tuple(float(v) for v in camera.position)
        if any(all(abs(a - b) < 1e-2 for a, b in zip(at, p, strict=True)) for p in self._ours):
            self.fit(self._fit)

    def _sequence_buttons(self, layout: ChartLayout) -> viser.GuiButtonGroupHandle | None:
        """A chart of several sequences: a button per sequence and one for the overview."""
        if len(layout.sequences) < 2:
            return None
        options = _sequence_labels(layout)
        numbers = {label: q.number for label, q in zip(options[1:], layout.sequences, strict=True)}
        shown = next((k for k, n in numbers.items() if n == self._focus), options[0])
        group = self.client.gui.add_button_group(
            f"Sequence: {shown}", options, hint="show one sequence at a readable zoom, or all"
        )

        def chosen(event: Any) -> None:
            value = str(event.target.value)
            self._focus = numbers.get(value)
            group.label = f"Sequence: {value}"  # which one the page shows
            self.aim(whole=self._focus is None)

        group.on_click(chosen)
        return group

    def chart_changed(self, layout: ChartLayout) -> None:
        """The CPU runs another chart version (render thread): the page is fitted to it."""
        if self.editor is not None:
            self.editor.running_changed(layout)
        self.alarms.chart_changed(layout)
        self.block_links.layout = layout
        if self.contact_modify is not None:
            self.contact_modify.layout = layout
        if self._focus not in {q.number for q in layout.sequences}:
            self._focus = None
        wanted = _sequence_labels(layout) if len(layout.sequences) > 1 else []
        shown = self.sequence_buttons
        if (list(shown.options) if shown is not None else []) != wanted:
            if shown is not None:
                shown.remove()
            with self.view_folder:
                self.sequence_buttons = self._sequence_buttons(layout)
        self.aim(whole=False)

    # ------------------------------------------------------------ login

    def _login(self, user: str, password: str) -> LoginReply:
        return self.wiring.login(user, password, self.origin)  # as typed: "olga " is refused

    def _logout(self, token: str, user: str) -> None:
        self.wiring.logout(token, user, self.origin)

    def forget(self) -> None:
        """The page went away: revoke its token (its GUI is gone, nothing to update)."""
        editor, self.editor = self.editor, None
        if editor is not None:
            editor.close(page_gone=True)
        self._revoke()

    # ------------------------------------------------------------ commands

    @property
    def fb(self) -> str:
        """The FB this page commands."""
        return self.wiring.layout.fb

    def _on_click(
        self, make: Callable[[], Command], kind: type[Command] | None = None
    ) -> Callable[[Any], None]:
        """A button's handler: send the command ``make`` builds at the click — after a yes
        to the question of ``kind`` when it has one (CPU to STOP, MRES: ``confirm``)."""

        def click(_: Any) -> None:
            if kind is None:
                self.command(make())
            else:
                ask(self.client.gui, kind, lambda: self.command(make()))

        return click

    def _plain(self, kind: type[Command]) -> Command:
        """The command of an op without arguments."""
        return kind(fb=self.fb)

    def _step(self, kind: type[Command]) -> Command:
        """A step button's command: the step of the Step field (*Only this step*: that
        step alone active in its sequence)."""
        step = int(self.step_number.value)
        if kind is SetSteps:
            return SetSteps(fb=self.fb, args=StepsArgs(steps=[step]))
        return kind(fb=self.fb, args=StepArgs(step=step))

    def _step_places(self) -> dict[int, tuple[float, float]]:
        """Where the chart the page shows draws each step (its box's centre)."""
        host = self.wiring.host
        return dict(host.picture.steps) if host is not None else {}

    def _activate_step(self, step: int) -> CommandReply:
        """*Synchronization*'s *Set in MAN*: ``step`` the active step of its sequence."""
        return self.command(SetSteps(fb=self.fb, args=StepsArgs(steps=[step])))

    def _switch_mode(self, mode: Mode) -> SetMode:
        return SetMode(fb=self.fb, args=ModeArgs(mode=mode))

    def _halt(self) -> Halt:
        """Halt, or resume when halted (the button shows which)."""
        return Halt(fb=self.fb, args=OnArgs(on=not self._halted))

    def _unforce_all(self) -> Force:
        return Force(fb=self.fb, args=ForceArgs(all=True))

    def command(self, command: Command) -> CommandReply:
        """Send ``command`` as this page's user (runs in viser's callback threads)."""
        reply = self._send(command, self.wiring.send)
        verdict = "applied" if reply.applied else "refused"
        title = f"{texts.command_words(command)} {verdict}"
        self._notify(title, reply.reason or "OK", ok=reply.applied)
        return reply

    def send_quiet(self, command: Command) -> CommandReply:
        """Send ``command`` as this page's user without a notice (the caller says how it
        went: *Acknowledge all* sums up its commands in one)."""
        return self._send(command, self.wiring.send)

    def notify(self, title: str, body: str, *, ok: bool) -> None:
        """A notice on this page only."""
        self._notify(title, body, ok=ok)

    def engineer_command(self, command: Command) -> CommandReply:
        """Send one engineering command (download, save …) as this page's user and wait
        longer for its answer; the editor shows the verdict."""
        eng = self.wiring.engineering
        return self._send(command, eng.send if eng is not None else self.wiring.send)

    def _send(self, command: Command, send: Callable[[Command], CommandReply]) -> CommandReply:
        """Send ``command`` as this page's user, checked as the bus checks it: what the bus
        would refuse to decode is refused here, with its reason."""
        w = self.wiring
        with self._lock:
            user, token = self.user, self.token
        try:
            mine = checked(
                msgspec.structs.replace(command, user=user, token=token, origin=self.origin)
            )
        except (TypeError, ValueError) as exc:
            reply = CommandReply(applied=False, reason=str(exc), op=command.op, fb=command.fb)
        else:
            reply = send(mine)
        w.on_reply(reply)
        return reply

    # ------------------------------------------------------------ showing

    def show(self, page: PageState, detail: Callable[[tuple[str, int]], str], halted: bool) -> None:
        """Bring this page up to date (render thread; only what changed is sent)."""
        with self.client.atomic():
            self.update_html(self.banner, "banner", page.banner)
            self.update_html(self.status, "status", page.status)
            self.update_html(self.event_log, "events", page.events)
            self.update_html(self.history_html, "history", page.history)
            self.update_html(self.audit_html, "audit", page.audit)
            if self.force_folder is not None:
                self.update_html(self.force_html, "forces", page.forces)
            self._permanent(page.permanent)
            shown = int(self.detail_transition.value)
            key = ("T", shown) if shown > 0 else ("S", int(self.detail_step.value))
            self.update_html(self.detail_html, "detail", detail(key))
            self.block_links.show(0 if shown > 0 else key[1] or page.step)
            contacts = self.contact_modify
            if contacts is not None:
                contacts.show(key if key[1] > 0 else ("S", page.step))
            if page.mode != self._mode:
                self._mode = page.mode
                for mode, button in self.mode_buttons.items():
                    button.color = CURRENT_MODE_COLOUR if mode == page.mode else None
            if halted != self._halted:
                self._halted = halted
                self.buttons["halt"].label = "Resume (HALT off)" if halted else "Halt"
            if page.alarms is not self._alarms:
                self._alarms = page.alarms
                self.alarms.set_alarms(page.alarms)


def _sequence_labels(layout: ChartLayout) -> list[str]:
    """The buttons of *Chart view*'s Sequence: the overview, then each sequence."""
    return ["Overview", *(texts.clip(f"{q.number} {q.name}".strip(), 24) for q in layout.sequences)]
