"""The OPC UA face of one CPU, in the server's event loop: it builds the address space
from what the CPU serves (``web.opcua.space``), keeps it up to date from what the bus
publishes, and carries the clients' method calls, writes and acknowledgements to the CPU
as commands (docs/opcua.md).

Every command goes through the same gate as a page's or a shell's: it is sent under the
OPC UA session's own login (``web.opcua.sessions``), the CPU checks the user's role,
applies it at a scan boundary, writes the audit row and answers once that is durable;
the face answers the client then — ``Good`` with the method's outputs, or the refusal as
a status code (``web.opcua.methods.refusal_status``), the reason in the face's log. An
anonymous session sends nothing: ``BadUserAccessDenied``. At most ``MAX_COMMANDS``
commands wait for their answers at once, ``MAX_SESSION_COMMANDS`` of one session; past
that, ``BadTooManyOperations``. ``Synchronize`` on each FB's object is a read
(``web.opcua.sync``): any session may call it.

A write is a command too: an FB's ``Mode`` sends ``mode``, ``Halted`` ``halt``,
``InterlocksEnabled``/``SupervisionsEnabled`` ``en_il``/``en_sv``, a symbol on an input,
output or flag a ``force`` job, or with ``writes="modify"`` a symbol on an input, output,
flag or data block and a chart's own variable a ``modify`` (both an engineer's;
``web.opcua.space.WRITES``). The variable shows the CPU's value once the CPU publishes
it, never the value written.
"""

from __future__ import annotations

import asyncio
import contextlib
import functools
import json
import logging
from collections.abc import Callable, Coroutine
from typing import Any, Final

from asyncua import ua
from asyncua.crypto.permission_rules import User, UserRole
from asyncua.server.address_space import AddressSpace, AttributeService

from s7graph.engine.errors import internal_error
from s7graph.web.bus.protocol import (
    AlarmEntry,
    AlarmList,
    AuditList,
    ChartLayout,
    CommandReply,
    CpuStatus,
    DiagBuffer,
    OperandValues,
    ProtocolError,
    StepStateUpdate,
)
from s7graph.web.commands import (
    MODES,
    Args,
    Command,
    EnIl,
    EnSv,
    Force,
    ForceArgs,
    Halt,
    ModeArgs,
    Modify,
    ModifyArgs,
    OnArgs,
    SetMode,
    make_command,
    op_of,
)
from s7graph.web.opcua import sync
from s7graph.web.opcua.alarms import Alarms, condition_name
from s7graph.web.opcua.conditions import acked_comments
from s7graph.web.opcua.diag import DIAG_ENTRIES, DiagNodes
from s7graph.web.opcua.link import BusLink, Inbox
from s7graph.web.opcua.methods import (
    CallError,
    MethodSpec,
    arguments_of,
    method_specs,
    outputs,
    refusal_status,
)
from s7graph.web.opcua.model import from_variant, ua_type
from s7graph.web.opcua.sessions import FaceUser, caller
from s7graph.web.opcua.space import Space
from s7graph.web.opcua.typed import AttributeIds, ObjectIds, Server, StatusCodes, ua_id, ua_status

__all__ = ["MAX_COMMANDS", "MAX_SESSION_COMMANDS", "Face", "FaceAttributes"]

_log = logging.getLogger("s7graph.web.opcua")

MAX_COMMANDS: Final = 16
MAX_SESSION_COMMANDS: Final = 4
_LEVELS: Final[dict[str, type[Command]]] = {"halt": Halt, "en_il": EnIl, "en_sv": EnSv}
_SYMBOL_OPS: Final[dict[str, tuple[type[Command], type[ForceArgs] | type[ModifyArgs]]]] = {
    "force": (Force, ForceArgs),
    "modify": (Modify, ModifyArgs),
}
"""A symbol's or a chart variable's write as each op of ``WRITES`` sends it: the command
and its args."""
_COLLAPSED: Final = frozenset({"status", "alarms", "operands", "chart"})
"""Kinds of which only the newest of a batch counts (a state delta: each, in order)."""


class Face:
    """CPU ``space.cpu`` in ``server``, over ``link``."""

    def __init__(self, server: Server, link: BusLink, space: Space) -> None:
        self.server = server
        self.link = link
        self.space = space
        self.alarms = Alarms(
            server,
            space.nodes,
            messages=self._message_where,
            locate=self._locate,
            send=self.send,
        )
        self.diag = DiagNodes(space.nodes, space.nid, space.root)
        self.first_fb = ""
        self.status: CpuStatus | None = None
        self.latest: dict[str, StepStateUpdate] = {}
        self.layouts: dict[str, ChartLayout] = {}
        self.applied = 0  # messages from the bus applied (the tests wait on it)
        self.rebuilt: Callable[[], None] = lambda: None
        """Called after the address space was rebuilt (``web.collector.quiet_collector``)."""
        self._waiting: dict[int, int] = {}  # id of a session's user -> commands waiting
        self._inbox: Inbox | None = None
        self._task: asyncio.Task[None] | None = None

    # ------------------------------------------------------------ start

    async def start(self, status: CpuStatus) -> None:
        """Build the address space of the CPU as ``status`` and the bus show it, then
        follow the bus."""
        self.status = status
        specs = method_specs()
        fbs = list(status.fbs)
        self.first_fb = fbs[0] if fbs else ""
        space, link = self.space, self.link
        space.online = True
        await space.build_cpu(status, [(s, self._method(s, "")) for s in specs if s.where == "cpu"])
        self.diag.build()
        await space.nodes.flush()
        for fb in fbs:
            layout = await link.ask(link.reader.chart, fb)
            if layout is None:
                _log.warning("opcua: FB %s has no chart on the bus: left out", fb)
                continue
            self.layouts[fb] = layout
            methods = [(s, self._method(s, fb)) for s in specs if s.where == "fb"]
            await space.build_fb(fb, layout, methods, self._synchronize(fb))
        catalog = await link.ask(link.reader.operand_catalog)
        if catalog is not None:
            await space.build_operands(catalog)
        ack = ua_id(ObjectIds.AcknowledgeableConditionType_Acknowledge)
        self.server.iserver.isession.add_method_callback(ack, self.alarms.acknowledge)
        await self._restore_comments()
        inbox = self._inbox = Inbox(asyncio.get_running_loop())
        link.watch_alive(inbox)
        await link.ask(link.follow, inbox, list(space.fbs))
        await self._diag_anew()  # after following: an entry between the two is not lost
        self._task = asyncio.create_task(self._pump(inbox), name="s7graph-opcua-face")

    async def _restore_comments(self) -> None:
        """The conditions' comments given before this start, however old: each message's
        newest applied acknowledgement with a comment (``audit/acked``). A CPU that does
        not answer that (one from before it) gives its last 50 audit rows (``audit/list``);
        one that answers neither, none (one line in the log)."""
        rows: AuditList | None = None
        try:
            rows = await self.link.ask(self.link.reader.acked)
        except ProtocolError as exc:  # an SQLite without JSON functions, a disk error
            _log.warning("opcua: comments of acknowledgements from the last 50 rows: %s", exc)
        if rows is None:
            try:
                rows = await self.link.ask(self.link.reader.audit)
            except ProtocolError as exc:
                _log.warning("opcua: no comments of acknowledgements restored: %s", exc)
                return
        if rows is not None:
            self.alarms.restore(acked_comments(rows.entries))

    async def stop(self) -> None:
        if self._task is not None:
            self._task.cancel()
            with contextlib.suppress(asyncio.CancelledError, Exception):
                await self._task
            self._task = None

    # ------------------------------------------------------------ from the bus

    async def _pump(self, inbox: Inbox) -> None:
        while True:
            batch = await inbox.take()
            last = {(kind, key): i for i, (kind, key, _) in enumerate(batch) if kind in _COLLAPSED}
            for i, (kind, key, message) in enumerate(batch):
                if kind in _COLLAPSED and last[(kind, key)] != i:
                    continue
                try:
                    await self._apply(kind, key, message)
                except asyncio.CancelledError:
                    raise
                except Exception as exc:  # one bad message must not stop the face
                    where = f"while applying {kind} of {key or 'the CPU'}"
                    _log.warning("opcua: not applied: %s", internal_error(where, exc))
                self.applied += 1

    async def _apply(self, kind: str, key: str, message: Any) -> None:
        space = self.space
        if kind == "state":
            self.latest[key] = message
            await space.apply_state(key, message)
        elif kind == "status":
            self.status = message
            await space.apply_status(message)
        elif kind == "alarms":
            await self._alarms(message)
        elif kind == "operands":
            await self._operands(message)
        elif kind == "chart":
            await self._chart(key, message)
        elif kind == "diag":
            await self._diag(message)
        elif kind == "alive":
            await self._alive(bool(message))
        elif kind == "audit":
            await self.alarms.audited(message)

    async def _diag(self, new: DiagBuffer) -> None:
        if self.diag.shown.merge(new):
            await self.diag.write()
        else:  # an entry missed, or the CPU counts anew
            await self._diag_anew()

    async def _diag_anew(self) -> None:
        """The diagnostic buffer as the CPU's ``diag`` answers now."""
        buffer = await self.link.ask(self.link.reader.diag, DIAG_ENTRIES)
        if buffer is not None:
            self.diag.shown.replace(buffer)
            await self.diag.write()

    async def _alarms(self, alarms: AlarmList) -> None:
        await self.alarms.apply(alarms)

    async def _operands(self, values: OperandValues) -> None:
        if values.catalog != self.space.catalog_version:
            catalog = await self.link.ask(self.link.reader.operand_catalog)
            if catalog is not None:
                await self.space.build_operands(catalog)
                self.rebuilt()
        await self.space.apply_operands(values)

    async def _chart(self, fb: str, layout: ChartLayout) -> None:
        if fb not in self.space.fbs:
            return
        if self.layouts.get(fb) != layout:
            self.space.fbs[fb].version = -1  # another chart, whatever its number
        self.layouts[fb] = layout
        await self.space.build_chart(fb, layout)
        await self.alarms.restate()  # a step made anew: its conditions' state again
        self.rebuilt()
        latest = self.latest.get(fb)
        if latest is not None:
            await self.space.apply_state(fb, latest)

    async def _alive(self, up: bool) -> None:
        level = ua.Variant(255 if up else 0, ua.VariantType.Byte)
        await self.server.write_attribute_value(
            ua_id(ObjectIds.Server_ServiceLevel), ua.DataValue(level)
        )
        if up == self.space.online:
            return
        _log.info("opcua: CPU %s %s the bus", self.space.cpu, "is back on" if up else "left")
        await self.space.set_online(up)
        if up:
            await self.alarms.restate()  # the conditions' state children good again
        if not up or self._inbox is None:
            return
        link = self.link
        for fb in list(self.space.fbs):  # it may run another chart now: from the start
            layout = await link.ask(link.reader.chart, fb)
            if layout is not None:
                await self._chart(fb, layout)
        self.latest.clear()
        await link.ask(link.follow, self._inbox, list(self.space.fbs))
        await self._diag_anew()
        status = await link.ask(link.reader.status)
        if status is not None:
            await self.space.apply_status(status)

    # ------------------------------------------------------------ where alarms are

    def _locate(self, entry: AlarmEntry) -> tuple[ua.NodeId, ua.NodeId, str, str, str] | None:
        if entry.step is None or entry.kind not in ("IL", "SV") or not entry.fb:
            return None
        cond = self.space.condition(entry.fb, entry.step, entry.kind)
        source = self.space.step_node(entry.fb, entry.step)
        if cond is None or source is None:
            return None
        name = f"{self.space.cpu}/{entry.fb}/S{entry.step}"
        return cond, source, name, condition_name(entry.kind), entry.fb

    async def _message_where(self, entry: AlarmEntry) -> tuple[ua.NodeId, ua.NodeId, str, str, str]:
        key = str(entry.msg_id)
        nid = await self.space.message_condition(key, entry.text, entry.kind)
        fb = entry.fb if entry.fb in self.space.fbs else self.first_fb
        return nid, self.space.root, entry.source or self.space.cpu, f"Message {key}", fb

    # ------------------------------------------------------------ commands

    def _method(
        self, spec: MethodSpec, fb: str
    ) -> Callable[..., Coroutine[Any, Any, ua.CallMethodResult]]:
        """The callback of ``spec``'s method on FB ``fb`` ("": the CPU's first)."""

        async def call(parent: ua.NodeId, *inputs: Any) -> ua.CallMethodResult:
            result = ua.CallMethodResult()
            try:
                args = arguments_of(spec, inputs)
            except CallError as exc:
                result.StatusCode = ua_status(exc.status)
                result.InputArgumentResults = [ua_status(c) for c in exc.arguments]
                return result
            status, reply = await self.send(caller(), spec.kind, fb or self.first_fb, args)
            result.StatusCode = ua_status(status)
            result.InputArgumentResults = [ua.StatusCode() for _ in inputs]
            if status == StatusCodes.Good and reply is not None:
                result.OutputArguments = outputs(spec, reply)
            return result

        return call

    def _synchronize(self, fb: str) -> Callable[..., Coroutine[Any, Any, ua.CallMethodResult]]:
        """The callback of FB ``fb``'s ``Synchronize``: the CPU's judgement, for any
        session (a read)."""

        async def call(parent: ua.NodeId, *inputs: Any) -> ua.CallMethodResult:
            result = ua.CallMethodResult()
            if inputs:
                result.StatusCode = ua_status(StatusCodes.BadTooManyArguments)
                return result
            ask = functools.partial(self.link.reader.synchronization, fb, timeout=sync.TIMEOUT_S)
            status, out = sync.sync_result(await self.link.ask(ask))
            result.StatusCode = ua_status(status)
            result.OutputArguments = out
            return result

        return call

    async def send(
        self, user: User, kind: type[Command], fb: str, args: Args
    ) -> tuple[int, CommandReply | None]:
        """``kind`` with ``args`` for FB ``fb`` under ``user``'s login: (status code,
        the CPU's answer)."""
        op = op_of(kind)
        if not isinstance(user, FaceUser):
            _log.debug("opcua: %s refused: an anonymous session sends no command", op)
            return StatusCodes.BadUserAccessDenied, None
        if not fb:
            return StatusCodes.BadInvalidState, None
        mine = id(user)
        if (
            sum(self._waiting.values()) >= MAX_COMMANDS
            or self._waiting.get(mine, 0) >= MAX_SESSION_COMMANDS
        ):
            return StatusCodes.BadTooManyOperations, None
        try:
            command = make_command(
                op=op,
                fb=fb,
                user=user.name or "",
                token=user.token,
                origin=user.origin,
                args=args.given(),
            )
        except ValueError:
            return StatusCodes.BadInvalidArgument, None
        self._waiting[mine] = self._waiting.get(mine, 0) + 1
        try:
            reply = await self.link.send(user, command)
        finally:
            self._waiting[mine] -= 1
            if not self._waiting[mine]:
                del self._waiting[mine]
        shown = json.dumps(args.given(), default=str)[:200]
        outcome = "applied" if reply.applied else f"refused: {reply.reason}"
        _log.info("opcua: %s %s %s %s: %s", user.name, op, fb, shown, outcome)
        if reply.applied:
            return StatusCodes.Good, reply
        return refusal_status(reply.reason, reply.kind), reply

    async def write(self, user: User, value: ua.WriteValue) -> int:
        """One value a client writes: the command it stands for, its answer's status."""
        nid = value.NodeId
        target = self.space.writes.get(nid)
        if target is None or value.AttributeId != AttributeIds.Value:
            known = self.server.iserver.aspace.get(nid) is not None
            return StatusCodes.BadNotWritable if known else StatusCodes.BadNodeIdUnknown
        if not isinstance(user, FaceUser):
            return StatusCodes.BadUserAccessDenied
        if value.IndexRange:
            return StatusCodes.BadWriteNotSupported
        variant = value.Value.Value if value.Value is not None else None
        if not isinstance(variant, ua.Variant):
            return StatusCodes.BadTypeMismatch
        try:
            kind, fb, args = self._write_command(nid, target, variant)
        except TypeError:
            return StatusCodes.BadTypeMismatch
        except ValueError:
            return StatusCodes.BadOutOfRange
        status, _ = await self.send(user, kind, fb, args)
        return status

    def _write_command(
        self, nid: ua.NodeId, target: tuple[str, str], variant: ua.Variant
    ) -> tuple[type[Command], str, Args]:
        fb, op = target
        if variant.is_array or isinstance(variant.Value, list | tuple):
            raise TypeError("an array written to a scalar")  # bool([False]) would be True
        if op in _SYMBOL_OPS:
            info = self.space.targets[nid]
            value = from_variant(variant, ua_type(info.type))
            kind, make = _SYMBOL_OPS[op]
            return kind, fb or self.first_fb, make(address=info.address, value=value)
        if op == "mode":
            if variant.VariantType is not ua.VariantType.String:
                raise TypeError("mode is text")
            if variant.Value not in MODES:
                raise ValueError(f"mode must be one of {', '.join(MODES)}")
            return SetMode, fb, ModeArgs(mode=variant.Value)
        if variant.VariantType is not ua.VariantType.Boolean:
            raise TypeError(f"{op} takes a Boolean")
        return _LEVELS[op], fb, OnArgs(on=bool(variant.Value))


class FaceAttributes(AttributeService):
    """The write service: a client's write is :meth:`Face.write`; the server's own
    writes (its session is an admin's) go to the address space as before."""

    def __init__(self, aspace: AddressSpace, face: Face) -> None:
        super().__init__(aspace)
        self._face = face

    async def write(
        self,
        params: ua.WriteParameters,
        user: User = User(role=UserRole.Admin),  # noqa: B008  (asyncua's own default)
    ) -> list[ua.StatusCode]:
        if user.role == UserRole.Admin:
            return await super().write(params, user)
        results = []
        for value in params.NodesToWrite:
            try:
                status = await self._face.write(user, value)
            except Exception as exc:  # a hostile write is refused, never a crash
                why = internal_error(f"while writing {value.NodeId}", exc)
                _log.warning("opcua: a write was refused: %s", why)
                status = StatusCodes.BadInternalError
            results.append(ua_status(status))
        return results
