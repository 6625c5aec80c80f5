"""The CPU's message list on the bus, for any CPU that keeps one (``sfb.alarms``).

:class:`AlarmFeed` turns the list (ALARM_S / ALARM_SQ messages of a program of blocks, the
interlock and supervision messages of a sequencer) into the published :class:`AlarmList`
whenever it changed, its times as wall-clock ms, and carries out ``ack_msg``: a message is
acknowledged as the command's user at once (``MessageList.acknowledge``); an unknown or
already acknowledged message is refused with the reason, and so is the user name
``program`` (reserved for ACK_EF). What an acknowledgement does to a GraphFB's latched
step is the FB's (``web.bus.live``).
"""

from __future__ import annotations

import time
from collections.abc import Callable

from s7graph.sequencer.messages import PROGRAM_USER, parse_message_id
from s7graph.sfb.alarms import Message, MessageList
from s7graph.web.bus.protocol import AlarmEntry, AlarmList, Refusal

__all__ = ["AlarmFeed"]


class AlarmFeed:
    """The message list ``messages`` as published; ``wall_ns`` gives the wall clock."""

    def __init__(self, messages: MessageList, *, wall_ns: Callable[[], int] = time.time_ns):
        self.messages = messages
        self._wall_ns = wall_ns
        self._entries: tuple[Message, ...] | None = None

    def changed(self, t_ns: int, cycle: int) -> AlarmList | None:
        """The list if it changed since the last call (first call: always), else None;
        ``t_ns`` is the CPU time of scan ``cycle``: an entry's time becomes wall-clock ms,
        ``wall_ns`` now minus its age on the CPU clock."""
        entries = self.messages.entries()
        if entries == self._entries:
            return None
        self._entries = entries
        offset = self._wall_ns() - t_ns

        def wall(at_ns: int | None) -> int | None:
            return None if at_ns is None else max((at_ns + offset) // 1_000_000, 0)

        out = []
        for m in entries:
            where = parse_message_id(m.msg_id)
            fb, db, step, kind = where if where is not None else ("", None, None, "")
            out.append(
                AlarmEntry(
                    msg_id=m.msg_id,
                    event_id=m.event_id,
                    state=m.state.value,
                    text=m.text[:4096],
                    source=m.source[:256],
                    came_ms=wall(m.came_ns) or 0,
                    went_ms=wall(m.went_ns),
                    ack_required=m.ack_required,
                    acked=m.acked,
                    ack_user=m.ack_user[:64],
                    ack_ms=wall(m.ack_ns),
                    fb=fb,
                    db=db,
                    step=step,
                    kind=kind,  # type: ignore[arg-type]
                )
            )
        return AlarmList(cycle=max(cycle, 0), entries=out)

    def acknowledge(
        self, msg_id: int | str | None, user: str, t_ns: int
    ) -> tuple[Message | None, str]:
        """Acknowledge ``msg_id`` as ``user`` at CPU time ``t_ns``: the message as it was,
        or None and why not."""
        if user == PROGRAM_USER:
            return None, Refusal("access", f"the user name {PROGRAM_USER!r} is reserved for ACK_EF")
        msg = self.messages.get(msg_id) if msg_id is not None else None
        if msg is None:
            return None, Refusal("no_event", f"no message {msg_id!r} in the message list")
        if msg.acked:
            how = f" by {msg.ack_user}" if msg.ack_user else ""
            return None, Refusal("acked", f"message {msg_id!r} is already acknowledged{how}")
        self.messages.acknowledge(msg.msg_id, user, t_ns)
        return msg, ""
