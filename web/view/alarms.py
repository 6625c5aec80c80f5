"""The Alarms folder of one page: the CPU's message list, filtered, with *Acknowledge all*.

The list shows every message or only the unacknowledged ones, of every sequence or of one
(a sequencer message names its step; a message of no step is listed under every sequence
only). Each unacknowledged message listed has its own *Acknowledge* button; *Acknowledge
all* acknowledges every unacknowledged message listed, as the page's user, one ``ack_msg``
command per message (each checked and audited by the CPU on its own, as if its button had
been clicked), and says in one notice how many were acknowledged and why any was not.
"""

from __future__ import annotations

import functools
import threading
from collections.abc import Callable
from typing import Any, Final, Protocol

import msgspec
import viser

from s7graph.web.bus.protocol import AlarmEntry, AlarmList, ChartLayout, CommandReply
from s7graph.web.commands import AckMsg, Command, MessageArgs
from s7graph.web.view import texts

__all__ = ["ALL", "UNACKNOWLEDGED", "AlarmPage", "AlarmView", "listed"]

ALL: Final = "all"
UNACKNOWLEDGED: Final = "unacknowledged"
EVERY_SEQUENCE: Final = "every sequence"


class AlarmPage(Protocol):
    """What the folder needs of its page (``web.view.panel.ClientPanel``)."""

    client: viser.ClientHandle

    @property
    def fb(self) -> str: ...

    def send_quiet(self, command: Command) -> CommandReply: ...

    def command(self, command: Command) -> CommandReply: ...

    def notify(self, title: str, body: str, *, ok: bool) -> None: ...


def listed(
    alarms: AlarmList | None, layout: ChartLayout, show: str, sequence: int | None
) -> list[AlarmEntry]:
    """The messages the list shows: all or the unacknowledged ones (``show``), of every
    sequence or of sequence number ``sequence`` (by the step each names)."""
    if alarms is None:
        return []
    steps = None
    if sequence is not None:
        steps = {n for q in layout.sequences if q.number == sequence for n in q.steps}
    out = []
    for e in alarms.entries:
        if show == UNACKNOWLEDGED and not (e.ack_required and not e.acked):
            continue
        if steps is not None and e.step not in steps:
            continue
        out.append(e)
    return out


def _sequence_label(number: int, name: str) -> str:
    return texts.clip(f"{number} {name}".strip(), 40)


class AlarmView:
    """The Alarms folder of ``page`` for the chart ``layout`` (built with the panel)."""

    def __init__(self, page: AlarmPage, layout: ChartLayout, *, order: float | None = None):
        self.page = page
        self.layout = layout
        self._lock = threading.RLock()
        self._alarms: AlarmList | None = None
        self._buttons: dict[int | str, viser.GuiButtonHandle] = {}
        self._may_ack = False
        self._shown_html = ""
        gui = page.client.gui
        with gui.add_folder("Alarms", order=order) as self.folder:
            self.show_choice = gui.add_dropdown(
                "Show", (ALL, UNACKNOWLEDGED), initial_value=ALL, hint="which messages to list"
            )
            self.sequence_choice = gui.add_dropdown(
                "Sequence",
                self._sequence_options(layout),
                initial_value=EVERY_SEQUENCE,
                hint="only the messages of one sequence's steps",
                visible=len(layout.sequences) > 1,
            )
            self.ack_all = gui.add_button(
                "Acknowledge all",
                color="red",
                disabled=True,
                hint="acknowledge every unacknowledged message listed here, each on its own "
                "(the audit log shows one acknowledgement per message)",
            )
            self.html = gui.add_html(texts.alarms_html(None))
        self.show_choice.on_update(lambda _: self.refresh())
        self.sequence_choice.on_update(lambda _: self.refresh())
        self.ack_all.on_click(self._on_ack_all)

    @staticmethod
    def _sequence_options(layout: ChartLayout) -> tuple[str, ...]:
        return (EVERY_SEQUENCE, *(_sequence_label(q.number, q.name) for q in layout.sequences))

    def _sequence(self) -> int | None:
        chosen = str(self.sequence_choice.value)
        for q in self.layout.sequences:
            if _sequence_label(q.number, q.name) == chosen:
                return q.number
        return None

    # ------------------------------------------------------------ showing

    def chart_changed(self, layout: ChartLayout) -> None:
        """Another chart version: its sequences to choose from."""
        with self._lock:
            self.layout = layout
            options = self._sequence_options(layout)
            if tuple(self.sequence_choice.options) != options:
                if str(self.sequence_choice.value) not in options:
                    self.sequence_choice.value = EVERY_SEQUENCE  # type: ignore[misc]
                self.sequence_choice.options = options
            self.sequence_choice.visible = len(layout.sequences) > 1
        self.refresh()

    def set_alarms(self, alarms: AlarmList | None) -> None:
        """The CPU's message list changed (render thread)."""
        with self._lock:
            self._alarms = alarms
        self.refresh()

    def enable(self, may_ack: bool) -> None:
        """Whether this page's role may acknowledge messages."""
        with self._lock:
            self._may_ack = may_ack
            for button in self._buttons.values():
                button.disabled = not may_ack
        self.refresh()

    @property
    def alarms(self) -> AlarmList | None:
        """The CPU's message list as it came, unfiltered."""
        with self._lock:
            return self._alarms

    def shown(self) -> list[AlarmEntry]:
        """The messages listed now."""
        with self._lock:
            return listed(self._alarms, self.layout, str(self.show_choice.value), self._sequence())

    def refresh(self) -> None:
        """List the messages the filter lets through, a button per unacknowledged one."""
        with self._lock:
            entries = self.shown()
            show = str(self.show_choice.value)
            shown = msgspec.structs.replace(self._alarms, entries=entries) if self._alarms else None
            empty = "no unacknowledged messages" if show == UNACKNOWLEDGED else "no messages"
            content = texts.alarms_html(shown, empty=empty)
            if content != self._shown_html:
                self.html.content = content
                self._shown_html = content
            pending = [e for e in entries if e.ack_required and not e.acked]
            self._buttons_for(pending)
            self.ack_all.disabled = not (self._may_ack and pending)
            label = f"Acknowledge all ({len(pending)})" if pending else "Acknowledge all"
            self.ack_all.label = label

    def _buttons_for(self, pending: list[AlarmEntry]) -> None:
        wanted = {e.msg_id: e for e in pending}
        for mid in [m for m in self._buttons if m not in wanted]:
            self._buttons.pop(mid).remove()
        gui = self.page.client.gui
        with self.folder:
            for mid, entry in wanted.items():
                if mid not in self._buttons:
                    button = gui.add_button(
                        texts.ack_label(entry),
                        color="red",
                        hint=texts.clip(entry.text, 200),
                        disabled=not self._may_ack,
                    )
                    button.on_click(self._click(functools.partial(self._ack, mid)))
                    self._buttons[mid] = button

    def _click(self, make: Callable[[], Command]) -> Callable[[Any], None]:
        def click(_: Any) -> None:
            self.page.command(make())

        return click

    def _ack(self, msg_id: int | str) -> AckMsg:
        return AckMsg(fb=self.page.fb, args=MessageArgs(msg_id=msg_id))

    # ------------------------------------------------------------ acknowledge all

    def _on_ack_all(self, _: Any) -> None:
        self.acknowledge_all()

    def acknowledge_all(self) -> list[CommandReply]:
        """Acknowledge every unacknowledged message listed, one command each (callback
        thread); one notice for them all."""
        pending = [e for e in self.shown() if e.ack_required and not e.acked]
        replies = [self.page.send_quiet(self._ack(e.msg_id)) for e in pending]
        done = sum(r.applied for r in replies)
        refused = [r.reason for r in replies if not r.applied]
        if not replies:
            self.page.notify("acknowledge all", "no unacknowledged message listed", ok=False)
        elif not refused:
            noun = "message" if done == 1 else "messages"
            self.page.notify("acknowledge all", f"{done} {noun} acknowledged", ok=True)
        else:
            body = f"{done} of {len(replies)} acknowledged; refused: {refused[0]}"
            self.page.notify("acknowledge all", body, ok=False)
        return replies
