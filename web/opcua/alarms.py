"""The CPU's message list as OPC UA Alarms & Conditions (docs/opcua.md, "Alarms and
conditions").

Each message of the list (``alarms`` on the bus) is an ``AlarmConditionType`` condition:
a step's interlock or supervision message the condition node under that step
(``cpu1/Seq_drill/S2/Supervision``), any other message one under the CPU's ``Messages``
folder, made when it first comes. Whenever a message's state changes — it comes, goes,
is acknowledged — its condition's event goes out from the ``Server`` object, with
``ActiveState``, ``AckedState`` and ``Retain`` (active, or waiting for its
acknowledgement); a message that has left the list sends its last event with ``Retain``
false. ``ConditionRefresh`` replays the retained ones (asyncua's subscription service).
Just before an event goes out, the condition node's state children take what it says
(``web.opcua.conditions``), for a client that reads rather than subscribes.

``Acknowledge`` on a condition sends ``ack_msg`` for its message under the OPC UA
session's own login — the gate checks the role and audits it under that user, the
comment with it, and a supervision message acknowledged so releases its step, as from
any other face. The EventId must be one the condition sent. An applied acknowledgement's
comment becomes the condition's ``Comment`` (a Null one leaves it as it was, an empty
text with a locale empties it: OPC UA Part 9, "Acknowledge"), stamped with when it was
given; an event carries it (one of its own when the acknowledgement's event went out
first). A face started again takes each condition's last comment back from the CPU's
audit rows (``web.opcua.conditions.acked_comments``) when it makes the condition; a
running face takes another client's from each audit row as it comes
(:meth:`Alarms.audited`). Called on an object that is no condition it is
``BadMethodInvalid``, on the condition type ``BadNodeIdInvalid`` (Part 9, "Acknowledge").
"""

from __future__ import annotations

import collections
import logging
import uuid
from collections.abc import Awaitable, Callable
from dataclasses import dataclass, field
from datetime import UTC, datetime
from typing import Any, Final

from asyncua import ua
from asyncua.common.event_objects import AlarmCondition
from asyncua.crypto.permission_rules import UserRole
from msgspec import UNSET

from s7graph.engine.errors import internal_error
from s7graph.web.bus.protocol import AlarmEntry, AlarmList, AuditEntry, CommandReply
from s7graph.web.commands import AckMsg, Args, Command, MessageArgs
from s7graph.web.opcua.conditions import acked_comment, event_values, show
from s7graph.web.opcua.nodes import Nodes
from s7graph.web.opcua.sessions import caller
from s7graph.web.opcua.statuses import is_condition, node_class
from s7graph.web.opcua.typed import ObjectIds, Server, StatusCodes, ua_id, ua_status

__all__ = ["Alarms", "Send", "condition_name"]

_log = logging.getLogger("s7graph.web.opcua")

SEVERITY: Final = {"SV": 700, "IL": 500, "": 600}
"""An event's severity (1–1000): a supervision fault, an interlock error, any other
message of the list."""
_NAMES: Final = {"SV": "Supervision", "IL": "Interlock"}
_TIME_FIELDS: Final = (
    "ActiveState/TransitionTime",
    "AckedState/TransitionTime",
    "EnabledState/TransitionTime",
    "LastSeverity/SourceTimestamp",
    "Comment/SourceTimestamp",
)
_KEPT_EVENT_IDS: Final = 32

Send = Callable[[Any, type[Command], str, Args], Awaitable[tuple[int, CommandReply | None]]]
"""``send(user, kind, fb, args)``: a command under the user's login; (status, reply)."""


def condition_name(kind: str) -> str:
    """The condition node's browse name under a step for a message kind (``SV``, ``IL``)."""
    return _NAMES[kind]


def _ms(ms: int | None) -> datetime | None:
    return None if ms is None else datetime.fromtimestamp(ms / 1000, UTC)


@dataclass
class _Condition:
    """One condition: its node, the node and name of its source, the FB its ``ack_msg``
    goes to, its event, and the message it shows now."""

    nid: ua.NodeId
    source: ua.NodeId
    source_name: str
    name: str
    fb: str
    event: Any
    msg_id: int | str | None = None
    shown: tuple[object, ...] | None = None
    event_ids: collections.deque[bytes] = field(
        default_factory=lambda: collections.deque(maxlen=_KEPT_EVENT_IDS)
    )


def _event(cond_nid: ua.NodeId, source: ua.NodeId, source_name: str, name: str) -> Any:
    made: Callable[..., Any] = AlarmCondition  # asyncua's event classes are untyped
    event = made(sourcenode=source)
    event.add_property("NodeId", cond_nid, ua.VariantType.NodeId)  # the ConditionId
    for name_ in _TIME_FIELDS:
        event.data_types[name_] = ua.VariantType.DateTime
    event.SourceName = source_name
    event.ConditionName = name
    event.ConditionClassId = ua_id(ObjectIds.ProcessConditionClassType)
    event.ConditionClassName = ua.LocalizedText("Process")
    event.BranchId = ua.NodeId()
    event.EnabledState = ua.LocalizedText("Enabled")
    setattr(event, "EnabledState/Id", True)
    event.Quality = ua_status(StatusCodes.Good)
    event.SuppressedOrShelved = False
    event.LastSeverity = 0  # the severity never changes: no previous one (Part 9)
    event.emitting_node = ua_id(ObjectIds.Server)
    return event


class Alarms:
    """The conditions of one CPU's message list in ``server``; ``locate(entry)`` says
    where a message's condition is (its node, source node, source name, name, FB), or
    None for one under ``messages`` (made here); ``send`` sends an ``ack_msg``; ``nodes``
    writes the conditions' state children (``web.opcua.conditions.show``)."""

    def __init__(
        self,
        server: Server,
        nodes: Nodes,
        *,
        messages: Callable[[AlarmEntry], Awaitable[tuple[ua.NodeId, ua.NodeId, str, str, str]]],
        locate: Callable[[AlarmEntry], tuple[ua.NodeId, ua.NodeId, str, str, str] | None],
        send: Send,
    ) -> None:
        self.server = server
        self.nodes = nodes
        self._messages = messages
        self._locate = locate
        self._send = send
        self._by_node: dict[ua.NodeId, _Condition] = {}
        self._live: dict[str, _Condition] = {}  # message key -> its condition
        self._restored: dict[str, tuple[ua.LocalizedText, datetime]] = {}
        self._made: dict[str, _Condition] = {}  # message key -> its condition, once made
        self._own: dict[str, str] = {}  # message key -> the comment this face is sending
        self.triggered = 0

    def restore(self, comments: dict[str, tuple[ua.LocalizedText, datetime]]) -> None:
        """The comments given before this face started, per message key
        (``web.opcua.conditions.acked_comments``): each becomes its condition's ``Comment``
        when the condition is made."""
        self._restored = dict(comments)

    async def apply(self, alarms: AlarmList) -> None:
        """Send an event for each message whose state changed, and a last one for each
        message that left the list."""
        seen: set[str] = set()
        for entry in alarms.entries:
            key = str(entry.msg_id)
            seen.add(key)
            cond = self._live.get(key) or await self._condition(entry)
            self._live[key] = cond
            await self._show(cond, entry)
        for key in [k for k in self._live if k not in seen]:
            cond = self._live.pop(key)
            await self._gone(cond)

    async def _condition(self, entry: AlarmEntry) -> _Condition:
        where = self._locate(entry) or await self._messages(entry)
        nid, source, source_name, name, fb = where
        cond = self._by_node.get(nid)
        if cond is None:
            event = _event(nid, source, source_name, name)
            restored = self._restored.pop(str(entry.msg_id), None)
            if restored is not None:
                event.Comment = restored[0]
                setattr(event, "Comment/SourceTimestamp", restored[1])
            cond = _Condition(nid, source, source_name, name, fb, event)
            self._by_node[nid] = cond
        self._made[str(entry.msg_id)] = cond
        return cond

    async def audited(self, row: AuditEntry) -> None:
        """An audit row as the CPU writes it (``audit``): the comment of an applied
        acknowledgement from another client — a page, a shell, another face — becomes its
        condition's ``Comment``, stamped with the row's time, with an event of its own
        when the condition says acknowledged already (as :meth:`_comment`); emptied, the
        condition has none. A condition not made yet gets it when it is. This face's own
        acknowledgements are left to :meth:`_comment` (their locale kept)."""
        given = acked_comment(row)
        if given is None:
            return
        key, text, when = given
        cond = self._made.get(key)
        if cond is None:
            if text:
                self._restored[key] = (ua.LocalizedText(text), when)
            else:
                self._restored.pop(key, None)
            return
        ev = cond.event
        now = ev.Comment.Text if isinstance(ev.Comment, ua.LocalizedText) else ""
        if self._own.get(key) == text or (now or "") == text:
            return
        ev.Comment = ua.LocalizedText(text) if text else None
        setattr(ev, "Comment/SourceTimestamp", when)
        if cond.event_ids and ev.AckedState.Text == "Acknowledged":
            await self._trigger(cond, None)

    async def _show(self, cond: _Condition, e: AlarmEntry) -> None:
        shown = (e.msg_id, e.event_id, e.state, e.acked, e.ack_required, e.text, e.ack_user)
        if cond.shown == shown:
            return
        cond.shown, cond.msg_id = shown, e.msg_id
        active = e.state == "incoming"
        acked = e.acked or not e.ack_required
        ev = cond.event
        ev.Message = ua.LocalizedText(e.text or cond.name)
        ev.Severity = SEVERITY.get(e.kind, SEVERITY[""])
        ev.Retain = active or not acked
        ev.ActiveState = ua.LocalizedText("Active" if active else "Inactive")
        setattr(ev, "ActiveState/Id", active)
        ev.AckedState = ua.LocalizedText("Acknowledged" if acked else "Unacknowledged")
        setattr(ev, "AckedState/Id", acked)
        ev.ClientUserId = e.ack_user or None
        came, went, ack = _ms(e.came_ms), _ms(e.went_ms), _ms(e.ack_ms)
        setattr(ev, "ActiveState/TransitionTime", went if not active and went else came)
        if ack is not None:
            setattr(ev, "AckedState/TransitionTime", ack)
        latest = max((t for t in (came, went, ack) if t is not None), default=None)
        await self._trigger(cond, latest)

    async def _gone(self, cond: _Condition) -> None:
        """The message left the list (gone and acknowledged): the last event."""
        ev = cond.event
        ev.Retain = False
        ev.ActiveState = ua.LocalizedText("Inactive")
        setattr(ev, "ActiveState/Id", False)
        ev.AckedState = ua.LocalizedText("Acknowledged")
        setattr(ev, "AckedState/Id", True)
        cond.shown, cond.msg_id = None, None
        await self._trigger(cond, None)

    async def _trigger(self, cond: _Condition, when: datetime | None) -> None:
        ev = cond.event
        event_id = uuid.uuid4().bytes
        cond.event_ids.append(event_id)
        now = datetime.now(UTC)
        ev.EventId = event_id
        ev.Time = when or now
        ev.ReceiveTime = now
        await self._state(cond)  # first: a client reading on the event reads its state
        try:
            await self.server.iserver.subscription_service.trigger_event(ev)
        except Exception as exc:  # one client's broken filter must not stop the others
            why = internal_error("while sending an alarm event", exc)
            _log.warning("opcua: an alarm event was not sent: %s", why)
        self.triggered += 1

    async def _state(self, cond: _Condition) -> None:
        """The condition node's state children as its last event says."""
        try:
            await show(self.nodes, cond.nid, event_values(cond.event))
        except Exception as exc:  # the event goes out all the same
            why = internal_error(f"while writing the state of {cond.nid.to_string()}", exc)
            _log.warning("opcua: a condition's state was not written: %s", why)

    async def restate(self) -> None:
        """Write every condition's state children again (an online change made a step's
        condition node anew, or the CPU is back on the bus: each holds its last event's
        state again, with a good status)."""
        for cond in self._by_node.values():
            if cond.event_ids:
                await self._state(cond)

    # ------------------------------------------------------------ Acknowledge

    async def acknowledge(self, parent: ua.NodeId, *inputs: Any) -> ua.CallMethodResult:
        """``Acknowledge(EventId, Comment)`` on condition ``parent``: ``ack_msg`` of its
        message under the caller's login."""
        result = ua.CallMethodResult()
        cond = self._by_node.get(parent)
        status = self._ack_problem(parent, cond, inputs)
        if status is None and cond is not None and cond.msg_id is not None:
            comment = inputs[1].Value
            given = isinstance(comment, ua.LocalizedText) and (comment.Text or comment.Locale)
            text = (comment.Text or "") if given else UNSET  # "": emptied (audited so)
            args = MessageArgs(msg_id=cond.msg_id, comment=text)
            key = str(cond.msg_id)
            if isinstance(text, str):
                self._own[key] = text  # its audit row may come back before the reply
            try:
                status, _ = await self._send(caller(), AckMsg, cond.fb, args)
            finally:
                self._own.pop(key, None)
            if status == StatusCodes.Good and isinstance(comment, ua.LocalizedText):
                await self._comment(cond, comment)
        result.StatusCode = ua_status(status if status is not None else StatusCodes.Good)
        result.InputArgumentResults = [ua.StatusCode() for _ in inputs]
        return result

    async def _comment(self, cond: _Condition, comment: ua.LocalizedText) -> None:
        """An applied acknowledgement's ``comment`` as the condition's ``Comment`` (Part 9,
        "Acknowledge": a Null one — no text, no locale — leaves it as it was, an empty text
        with a locale empties it), stamped now when it changed; an event of its own when
        the acknowledgement's already went out."""
        ev = cond.event
        if not comment.Text and not comment.Locale:
            return
        if ev.Comment != comment:
            ev.Comment = comment
            setattr(ev, "Comment/SourceTimestamp", datetime.now(UTC))
        if cond.event_ids and ev.AckedState.Text == "Acknowledged":
            await self._trigger(cond, None)

    def _ack_problem(
        self, parent: ua.NodeId, cond: _Condition | None, inputs: tuple[Any, ...]
    ) -> int | None:
        """Why ``Acknowledge`` is refused before the CPU is asked, in this order: on what
        (OPC UA Part 9, "Acknowledge": a type node ``BadNodeIdInvalid``, an object that is
        no condition ``BadMethodInvalid``), who may (an anonymous session never), how many
        arguments, their types (an EventId's ByteString, a Comment's LocalizedText or
        nothing), then which event: one the condition did not send — a condition of no
        message yet sent none — is ``BadEventIdUnknown``."""
        problem = self._target_problem(parent)
        if problem is not None:
            return problem
        if caller().role is UserRole.Anonymous:
            return StatusCodes.BadUserAccessDenied
        if len(inputs) < 2:
            return StatusCodes.BadArgumentsMissing
        if len(inputs) > 2:
            return StatusCodes.BadTooManyArguments
        event_id, comment = inputs
        if not isinstance(event_id, ua.Variant) or not isinstance(event_id.Value, bytes):
            return StatusCodes.BadTypeMismatch
        if not isinstance(comment, ua.Variant) or not (
            comment.Value is None or isinstance(comment.Value, ua.LocalizedText)
        ):
            return StatusCodes.BadTypeMismatch
        if cond is None or event_id.Value not in cond.event_ids:
            return StatusCodes.BadEventIdUnknown
        if cond.msg_id is None or cond.event.AckedState.Text == "Acknowledged":
            return StatusCodes.BadConditionBranchAlreadyAcked
        return None

    def _target_problem(self, parent: ua.NodeId) -> int | None:
        """Why ``parent`` is no object to acknowledge on (None: it is a condition)."""
        aspace = self.server.iserver.aspace
        kind = node_class(aspace, parent)
        if kind is None:
            return StatusCodes.BadNodeIdUnknown
        if kind is not ua.NodeClass.Object:
            return StatusCodes.BadNodeIdInvalid  # the condition type itself, or no object
        if not is_condition(aspace, parent):
            return StatusCodes.BadMethodInvalid
        return None
