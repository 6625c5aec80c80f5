"""The CPU message list, SFC17 ALARM_SQ / SFC18 ALARM_S / SFC19 ALARM_SC (docs/runtime.md, "The
block runtime"; docs/semantics.md, "Messages").

A ``MessageList`` holds the messages the CPU currently shows: each has a message number
``msg_id`` (EV_ID for the SFCs, any hashable-as-text key for the sequencer's interlock and
supervision messages), an ``event_id`` that numbers every incoming occurrence, associated
values, its state (incoming / outgoing) and its acknowledgement state. A message needing
acknowledgement (ALARM_SQ, sequencer faults) stays listed after it went until someone
acknowledges it; ``acknowledge(msg_id, user, now_ns)`` records who and when. Times are the
injected clock's ``now_ns``. Every change is also appended to a bounded log and to
``pop_events()`` (what a scan reports). ``snapshot()``/``restore()`` persist it as plain data.

The SFCs (STEP7 comprehensive guide vol. 2, ch. 12, ``[K]`` Siemens system-function manual): a
message is generated on each **edge** of SIG (1 = incoming, 0 = outgoing); a call with an unchanged
SIG returns ``W#16#8084``; EV_ID 0 is illegal (``8081``); an associated value above 12 bytes is cut
and reported with warning ``0001``. ALARM_S messages are acknowledged implicitly.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, replace
from enum import StrEnum
from typing import TYPE_CHECKING, Any, cast
from weakref import WeakKeyDictionary

from s7graph.engine import blocks
from s7graph.engine.errors import S7Error
from s7graph.sfb.catalogue import OK, engine_sections, lookup, specific_error
from s7graph.sfb.sfc_memory import parse_any

if TYPE_CHECKING:
    from s7graph.engine.context import CallContext

MsgId = int | str

RET_SD_TOO_LONG = 0x0001
RET_EV_ID_RANGE = specific_error(0x8081)
RET_NOT_OCCUPIED = specific_error(0x8082)
RET_SIG_UNCHANGED = specific_error(0x8084)
SD_MAX_BYTES = 12


class MessageState(StrEnum):
    INCOMING = "incoming"
    OUTGOING = "outgoing"


@dataclass(frozen=True, slots=True)
class Message:
    """One listed message; replaced (never mutated) on every change."""

    msg_id: MsgId
    event_id: int
    state: MessageState
    came_ns: int
    text: str = ""
    source: str = ""
    values: tuple[object, ...] = ()
    ack_required: bool = True
    acked: bool = False
    ack_user: str = ""
    ack_ns: int | None = None
    went_ns: int | None = None
    reason: str = ""
    """Why it went when not by its own cause (a restart that cleared the fault)."""

    @property
    def pending(self) -> bool:
        """Still listed: incoming, or gone but not yet acknowledged."""
        return self.state is MessageState.INCOMING or (self.ack_required and not self.acked)


@dataclass(frozen=True, slots=True)
class MessageEvent:
    """One change in the list: ``incoming``, ``outgoing`` or ``acknowledged``."""

    kind: str
    msg_id: MsgId
    event_id: int
    t_ns: int
    user: str = ""
    text: str = ""
    reason: str = ""


class MessageList:
    """The CPU's message memory (reusable by the sequencer for interlock/supervision faults)."""

    def __init__(self, *, log_size: int = 500) -> None:
        self._active: dict[MsgId, Message] = {}
        self._sig: dict[MsgId, bool] = {}
        self._log: deque[MessageEvent] = deque(maxlen=log_size)
        self._new: list[MessageEvent] = []
        self._next_event = 1
        self.changes = 0  # counts every change (a cheap "did it change?" for persistence)

    # --- changes ------------------------------------------------------------------------

    def raise_(
        self,
        msg_id: MsgId,
        now_ns: int,
        *,
        text: str = "",
        values: Sequence[object] = (),
        ack_required: bool = True,
        source: str = "",
    ) -> Message:
        """Message ``msg_id`` comes (again); an already incoming one is returned unchanged."""
        current = self._active.get(msg_id)
        if current is not None and current.state is MessageState.INCOMING:
            return current
        msg = Message(
            msg_id,
            self._next_event,
            MessageState.INCOMING,
            now_ns,
            text,
            source,
            tuple(values),
            ack_required,
            acked=not ack_required,
        )
        self._next_event += 1
        self._active[msg_id] = msg
        self._record(MessageEvent("incoming", msg_id, msg.event_id, now_ns, text=text))
        return msg

    def clear(
        self,
        msg_id: MsgId,
        now_ns: int,
        *,
        values: Sequence[object] | None = None,
        reason: str = "",
    ) -> Message | None:
        """Message ``msg_id`` goes; it leaves the list unless it still awaits acknowledgement.
        ``reason``: why, when not by its own cause (``warm restart (OB100)``)."""
        current = self._active.get(msg_id)
        if current is None or current.state is MessageState.OUTGOING:
            return None
        msg = replace(
            current,
            state=MessageState.OUTGOING,
            went_ns=now_ns,
            values=current.values if values is None else tuple(values),
            reason=reason,
        )
        self._store(msg)
        self._record(
            MessageEvent("outgoing", msg_id, msg.event_id, now_ns, text=msg.text, reason=reason)
        )
        return msg

    def acknowledge(self, msg_id: MsgId, user: str, now_ns: int) -> Message | None:
        """Acknowledge ``msg_id`` as ``user``; None when there is nothing to acknowledge."""
        current = self._active.get(msg_id)
        if current is None or current.acked:
            return None
        msg = replace(current, acked=True, ack_user=user, ack_ns=now_ns)
        self._store(msg)
        self._record(MessageEvent("acknowledged", msg_id, msg.event_id, now_ns, user, msg.text))
        return msg

    # --- queries ------------------------------------------------------------------------

    def entries(self) -> tuple[Message, ...]:
        """Listed messages, oldest occurrence first."""
        return tuple(sorted(self._active.values(), key=lambda m: m.event_id))

    def get(self, msg_id: MsgId) -> Message | None:
        return self._active.get(msg_id)

    def log(self) -> tuple[MessageEvent, ...]:
        """The last ``log_size`` changes, oldest first."""
        return tuple(self._log)

    def pop_events(self) -> tuple[MessageEvent, ...]:
        """Changes since the last call (the CPU puts them into the scan's record)."""
        new, self._new = tuple(self._new), []
        return new

    # --- persistence --------------------------------------------------------------------

    def snapshot(self, *, with_log: bool = True) -> dict[str, object]:
        """Plain data for ``restore``; without the change log when ``with_log`` is False (a
        state file keeps the log in its own append-only table)."""
        data: dict[str, object] = {
            "next_event": self._next_event,
            "active": [asdict(m) for m in self.entries()],
            "sig": [[k, v] for k, v in self._sig.items()],
        }
        if with_log:
            data["log"] = [asdict(e) for e in self._log]
        return data

    def restore(self, data: Mapping[str, Any]) -> None:
        """Load a ``snapshot()`` (plain data, e.g. read back from JSON)."""
        self._next_event = int(data["next_event"])
        self._active = {}
        for raw in data["active"]:
            fields = dict(raw)
            fields["state"] = MessageState(fields["state"])
            fields["values"] = tuple(fields["values"])
            msg = Message(**fields)
            self._active[msg.msg_id] = msg
        self._sig = {k: bool(v) for k, v in data["sig"]}
        self._log.clear()
        self._log.extend(MessageEvent(**e) for e in data.get("log", ()))
        self._new = []
        self.changes += 1

    # --- SFC17 / SFC18 / SFC19 ----------------------------------------------------------

    def alarm(
        self,
        sig: bool,
        ev_id: int,
        now_ns: int,
        *,
        sd: Sequence[object] = (),
        sd_bytes: int = 0,
        ack: bool = True,
        text: str = "",
    ) -> int:
        """ALARM_SQ (``ack=True``) / ALARM_S (``ack=False``): a message per SIG edge; RET_VAL."""
        if not 0 < ev_id <= 0xFFFFFFFF:
            return RET_EV_ID_RANGE
        sig = bool(sig)
        if self._sig.get(ev_id, False) == sig:
            return RET_SIG_UNCHANGED
        self._sig[ev_id] = sig
        self.changes += 1
        source = "SFC17 ALARM_SQ" if ack else "SFC18 ALARM_S"
        if sig:
            self.raise_(ev_id, now_ns, text=text, values=sd, ack_required=ack, source=source)
        else:
            self.clear(ev_id, now_ns, values=sd)
        return RET_SD_TOO_LONG if sd_bytes > SD_MAX_BYTES else OK

    def alarm_sc(self, ev_id: int) -> tuple[int, bool, bool]:
        """SFC19 ALARM_SC: ``(RET_VAL, STATE, Q_STATE)`` — last SIG and acknowledgement state."""
        if not 0 < ev_id <= 0xFFFFFFFF:
            return RET_EV_ID_RANGE, False, False
        msg = self._active.get(ev_id)
        if msg is None:
            return RET_NOT_OCCUPIED, self._sig.get(ev_id, False), False
        return OK, self._sig.get(ev_id, False), msg.acked

    def _store(self, msg: Message) -> None:
        if msg.pending:
            self._active[msg.msg_id] = msg
        else:
            self._active.pop(msg.msg_id, None)

    def _record(self, event: MessageEvent) -> None:
        self.changes += 1
        self._log.append(event)
        self._new.append(event)


# --- Engine adapters: one message list per CPU -------------------------------------------

_LISTS: WeakKeyDictionary[object, MessageList] = WeakKeyDictionary()


def message_list(cpu: object) -> MessageList:
    """The message list of ``cpu`` (shared by ALARM_SQ/ALARM_S and the sequencer)."""
    found = _LISTS.get(cpu)
    if found is None:
        found = _LISTS[cpu] = MessageList()
    return found


def _associated(ctx: CallContext, sd: object) -> tuple[tuple[object, ...], int]:
    """SD as associated values: the bytes an ANY pointer names, else the text itself."""
    text = str(sd or "").strip()
    if not text:
        return (), 0
    try:
        ptr = parse_any(text)
        n = ptr.bits // 8
        data = bytes(ctx.mem.area_bytes(ptr.area, ptr.db)[ptr.byte : ptr.byte + n])
    except S7Error:
        return (text,), 0
    return (data[:SD_MAX_BYTES].hex(),), n


def _alarm_body(ack: bool) -> blocks.FCBody:
    def body(ctx: CallContext, params: dict[str, object]) -> int:
        values, n = _associated(ctx, params.get("SD"))
        messages = message_list(ctx.cpu)
        ret = messages.alarm(
            params["SIG"] is True,
            cast(int, params["EV_ID"]),
            ctx.cpu.clock.now_ns(),
            sd=values,
            sd_bytes=n,
            ack=ack,
        )
        for event in messages.pop_events():
            ctx.alarm(event)
        return ret

    return body


def _alarm_sc(ctx: CallContext, params: dict[str, object]) -> int:
    ret, params["STATE"], params["Q_STATE"] = message_list(ctx.cpu).alarm_sc(
        cast(int, params["EV_ID"])
    )
    return ret


def _declare(name: str, body: blocks.FCBody) -> blocks.FC:
    entry = lookup(name)
    sections, ret = engine_sections(entry)
    return blocks.sfc(entry.number, entry.name, RET=ret, **sections)(body)


SFC17 = _declare("ALARM_SQ", _alarm_body(ack=True))
SFC18 = _declare("ALARM_S", _alarm_body(ack=False))
SFC19 = _declare("ALARM_SC", _alarm_sc)
BLOCKS = (SFC17, SFC18, SFC19)
