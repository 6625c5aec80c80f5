"""The CPU's side of the zenoh bus: :class:`BusPublisher` serves charts and state,
publishes deltas, status, alarms, force jobs and audit rows, and takes commands and logins
(the key space: :mod:`web.bus.keys`).

Valid commands go on a thread-safe queue; the scan loop drains it at a scan boundary,
where the :class:`~web.bus.gate.Gate` checks who sent each and whether their role allows
it, applies and audits it. The reply leaves once the command's effect and its audit row
are durable (``apply_commands(..., durable=runner)``: from the writer thread's callback
when the next scan's state is committed; never does the scan thread wait), or, if the
state file has not confirmed it ``REPLY_WITHIN_S`` after the command came, as not
confirmed. The scan thread only decides and queues; the publisher's
:class:`~web.bus.outbox.Outbox` thread encodes and puts. The FBs' deltas go out one
message per scan (``deltas``; :class:`~web.bus.deltas.DeltaOut`).
"""

from __future__ import annotations

import collections
import contextlib
import functools
import queue
import sqlite3
import threading
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol

import msgspec
import zenoh

from s7graph.engine.errors import internal_error
from s7graph.engine.persistence import sqlite_words
from s7graph.web.bus.deltas import PART, DeltaOut, ScanOut
from s7graph.web.bus.gate import Apply, Gate, claimed_note
from s7graph.web.bus.keys import ROOT, keys
from s7graph.web.bus.login_door import LoginDoor
from s7graph.web.bus.origin import query_origin
from s7graph.web.bus.outbox import Outbox, Sink
from s7graph.web.bus.protocol import (
    AlarmList,
    AuditEntry,
    ChartLayout,
    Command,
    CommandReply,
    CpuStatus,
    CycleStats,
    DiagEvent,
    ForceList,
    ProtocolError,
    Refusal,
    StepStateUpdate,
    decode,
    encode,
    refusal_kind,
    refusal_reply,
    split_layout,
)

__all__ = ["BusPublisher", "Durability", "PendingCommand", "QueryReply"]

COMMAND_QUEUE_SIZE = 256
COMMAND_MAX_AGE_S = 3.0
"""Older commands are refused at the scan boundary: too little of their sender's wait would
be left for the state file to confirm them."""
REPLY_WITHIN_S = 4.5
"""A command applied but not yet confirmed durable this long after it came is answered as
not confirmed (before its sender's ``web.bus.client.CLIENT_TIMEOUT_S`` runs out)."""
_EXPIRED = Refusal("busy", "expired before the scan boundary")
STATUS_PERIOD_S = 1.0
STATUS_PERIOD_NS = int(STATUS_PERIOD_S * 1e9)
_CPU_WIDE = ("cpu", "force")
"""Where the ops are carried out that act on the CPU, not on the FB named (``web.commands``):
a CPU without an FB (a program of blocks) takes them whatever ``fb`` says."""


class QueryReply:
    """A query answered from the outbox's thread (:meth:`BusPublisher.post`): ``put`` replies
    under ``key`` and lets the query go."""

    def __init__(self, query: zenoh.Query, key: str) -> None:
        self.query, self.key = query, key

    def put(self, payload: bytes) -> None:
        try:
            self.query.reply(self.key, payload, encoding=zenoh.Encoding.APPLICATION_JSON)
        except zenoh.ZError:
            pass  # the asker went away
        finally:
            self.query.drop()  # type: ignore[no-untyped-call]  # zenoh's stub


@dataclass(eq=False)
class PendingCommand:
    """A validated command waiting for the scan boundary; :meth:`resolve` sends the reply."""

    command: Command
    query: zenoh.Query | None = None
    received_ns: int = field(default_factory=time.monotonic_ns)
    reply: CommandReply | None = None
    note: str = ""
    """The audit row's note: the origin the sender claimed (``command.origin`` is the
    transport's, ``web.bus.origin``)."""

    def resolve(self, applied: bool, reason: str = "", *, cycle: int | None = None) -> None:
        """Answer the sender once: applied, or refused and why."""
        if self.reply is not None:
            return
        self.reply = CommandReply(
            applied=applied,
            reason=str(reason)[:4096],
            op=self.command.op,
            fb=self.command.fb,
            cycle=cycle,
            kind="" if applied else refusal_kind(reason),
        )
        _answer(self.query, self.reply)
        self.query = None

    def answer(self, reply: CommandReply) -> None:
        """Answer the sender once with ``reply`` (an engineering op's richer answer)."""
        if self.reply is not None:
            return
        self.reply = reply
        _answer(self.query, reply)
        self.query = None


class Durability(Protocol):
    """Who says when what was applied so far is on disk (``engine.runner.Runner``)."""

    def durable_mark(self) -> int: ...

    def when_durable(self, mark: int, fn: Callable[[str | None], None]) -> None: ...


def _unreadable(exc: Exception) -> str:
    """Why a command's message was not taken: the protocol's reason, or an internal error."""
    if isinstance(exc, ProtocolError):
        return Refusal("argument", str(exc))
    return internal_error("in the CPU while reading a command", exc)


def _route_broke(command: Command, exc: Exception) -> str:
    """The refusal of a command whose route (a worker's queue) raised: a defect of ours."""
    where = f"in the CPU while taking {command.op} for {command.fb}"
    return f"command refused: {internal_error(where, exc)}"


class _Awaiting:
    """The commands of one scan boundary, applied and audited, waiting for their commit:
    :meth:`durable` (the writer thread) or :meth:`overdue` (the scan thread, when the
    oldest has waited ``REPLY_WITHIN_S``) answers them, whichever comes first."""

    def __init__(
        self, results: list[tuple[PendingCommand, bool, str]], cycle: int | None, within_ns: int
    ) -> None:
        self.results = results
        self.cycle = cycle
        self.deadline_ns = min(p.received_ns for p, _, _ in results) + within_ns
        self._lock = threading.Lock()
        self.answered = False

    def durable(self, error: str | None) -> None:
        with self._lock:
            if self.answered:
                return
            self.answered = True
        for p, applied, reason in self.results:
            if error is None or not applied:
                p.resolve(applied, reason, cycle=self.cycle)
            else:
                why = f"not confirmed: applied in cycle {self.cycle}, but {error}"
                p.resolve(False, Refusal("timeout", why), cycle=self.cycle)

    def overdue(self, why: str) -> None:
        self.durable(why)


def _answer(query: zenoh.Query | None, reply: CommandReply) -> None:
    if query is None:
        return
    try:
        query.reply(query.key_expr, encode(reply), encoding=zenoh.Encoding.APPLICATION_JSON)
    except zenoh.ZError:
        pass  # the asker went away (timed out); nothing to tell
    finally:
        query.drop()  # type: ignore[no-untyped-call]  # zenoh's stub has no annotations


class BusPublisher:
    """The CPU's face on the bus: serves charts and state, publishes deltas, takes commands.

    Call :meth:`publish_scan` once per scan with the FBs that may have changed (or
    :meth:`publish` once per scan per FB), and :meth:`apply_commands` at the scan
    boundary; :meth:`close` undeclares everything (the session stays the caller's).
    ``gate`` decides who may command (default: the demo, names claimed, no audit kept)."""

    def __init__(
        self,
        session: zenoh.Session,
        cpu: str,
        charts: Mapping[str, ChartLayout],
        *,
        queue_size: int = COMMAND_QUEUE_SIZE,
        max_age_s: float = COMMAND_MAX_AGE_S,
        reply_within_s: float = REPLY_WITHIN_S,
        gate: Gate | None = None,
    ) -> None:
        self._keys = keys(cpu)
        self.gate = gate if gate is not None else Gate()
        self._logins = LoginDoor(self._keys.login, self.gate, self.origin)
        self._session = session
        self._lock = threading.Lock()
        self._charts = dict(charts)
        self._chart_bytes: dict[str, bytes] = {}
        self._chart_parts: dict[str, list[bytes]] = {}
        for name, layout in self._charts.items():
            self._chart_bytes[name], self._chart_parts[name] = _served(layout)
        self.outbox = Outbox()
        self.deltas: DeltaOut | None = None
        """The FBs' deltas and states (``web.bus.deltas``)."""
        self._commands: queue.Queue[PendingCommand] = queue.Queue(maxsize=queue_size)
        self._max_age_ns = int(max_age_s * 1e9)
        self._within_ns = int(reply_within_s * 1e9)
        self._awaiting: collections.deque[_Awaiting] = collections.deque()
        self.comm_limited = 0
        """Scan boundaries whose share for communication ran out with commands waiting."""
        self._status = CpuStatus(
            cpu=cpu, fbs=list(self._charts), login="demo" if self.gate.auth.demo else "users"
        )
        self._status_sent_ns = 0
        self._cycle = (0, 0)  # the cycle and t_ms of the latest scan published
        self._alarms = AlarmList()
        self._forces = ForceList()
        self._declared: list[Any] = []
        self._chart_pubs: dict[str, zenoh.Publisher] = {}
        self._routes: dict[str, Callable[[PendingCommand], None]] = {}
        try:
            for name in self._charts:
                for leaf, read in (("chart", self._chart_of), ("state", self._state_of)):
                    self._serve(self._keys.fb(name, leaf), functools.partial(read, name))
                self._declared.append(
                    session.declare_queryable(
                        self._keys.fb(name, "chart/part"), functools.partial(self._on_part, name)
                    )
                )
                chart_pub = session.declare_publisher(
                    self._keys.fb(name, "chart"), encoding=zenoh.Encoding.APPLICATION_JSON
                )
                self._chart_pubs[name] = chart_pub
                self._declared.append(chart_pub)
            self.deltas = DeltaOut(session, self._keys, self._charts, self.outbox)
            self._declared.append(self.deltas)
            self._declared.append(session.declare_queryable(self._keys.cmd, self._on_cmd))
            login = session.declare_queryable(self._keys.login, self._logins.on_query)
            self._declared.append(login)
            self._serve(self._keys.status, self._status_bytes)
            self._status_pub = session.declare_publisher(
                self._keys.status, encoding=zenoh.Encoding.APPLICATION_JSON
            )
            self._declared.append(self._status_pub)
            self._alarm_pub = session.declare_publisher(
                self._keys.alarms,
                encoding=zenoh.Encoding.APPLICATION_JSON,
                congestion_control=zenoh.CongestionControl.BLOCK,
            )
            self._declared.append(self._alarm_pub)
            self._serve(self._keys.alarm_list, self._alarm_bytes)
            self._force_pub = session.declare_publisher(
                self._keys.forces,
                encoding=zenoh.Encoding.APPLICATION_JSON,
                congestion_control=zenoh.CongestionControl.BLOCK,
            )
            self._declared.append(self._force_pub)
            self._serve(self._keys.forces, self._force_bytes)
            self._serve(self._keys.alarm_history, lambda: encode(self.gate.history()))
            self._serve(self._keys.audit_list, lambda: encode(self.gate.audit_list()))
            self._serve(self._keys.audit_acked, lambda: encode(self.gate.acked_list()))
            self._audit_pub = session.declare_publisher(
                self._keys.audit, encoding=zenoh.Encoding.APPLICATION_JSON
            )
            self._declared.append(self._audit_pub)
            self.gate.on_audit = self._publish_audit
            self._declared.append(session.liveliness().declare_token(self._keys.alive))
        except BaseException:
            self.close()
            raise

    # ------------------------------------------------------------ scan side

    def publish(self, fb: str, update: StepStateUpdate) -> bool:
        """Record one scan of ``fb``; publish a delta if something changed. Returns whether
        a delta went out. ``update.seq`` is replaced by the bus's own change counter (the
        delta is encoded and put by the outbox's thread)."""
        return bool(self.publish_scan(update.cycle, update.t_ms, [(fb, update)]))

    def publish_scan(
        self, cycle: int, t_ms: int, updates: Sequence[tuple[str, StepStateUpdate]]
    ) -> list[str]:
        """Record one scan (``cycle`` at CPU time ``t_ms``) of the FBs in ``updates``, each
        ``(fb, update)`` — an FB left out has not changed (``LiveGraph.changed``); those
        that did change go out in one message on ``deltas`` (``web.bus.deltas``). Returns
        them, in order. ``update.seq`` is replaced by the bus's own change counter."""
        assert self.deltas is not None
        changed = self.deltas.publish(cycle, t_ms, updates)
        self.scanned(cycle, t_ms)
        return changed

    def begin_scan(self, cycle: int, t_ms: int, *, part: int = PART) -> ScanOut:
        """:meth:`publish_scan` with the updates given one by one (``ScanOut``; a message
        every ``part`` changed FBs, 0: one at its ``end``); :meth:`scanned` after that."""
        assert self.deltas is not None
        return self.deltas.begin(cycle, t_ms, part=part)

    def publish_alarms(self, alarms: AlarmList) -> AlarmList:
        """Publish a changed message list on ``alarms`` (``seq`` is the bus's own counter)
        and serve it on ``alarms/list``; returns what went out."""
        with self._lock:
            alarms = msgspec.structs.replace(alarms, seq=self._alarms.seq + 1)
            self._alarms = alarms
        self.outbox.post(self._alarm_pub, alarms)
        return alarms

    def publish_forces(self, forces: ForceList) -> ForceList:
        """Publish a changed force table on ``forces`` (``seq`` is the bus's own counter),
        serve it there, and put the number of jobs into ``status`` at once."""
        with self._lock:
            forces = msgspec.structs.replace(forces, seq=self._forces.seq + 1)
            self._forces = forces
            self._status = msgspec.structs.replace(self._status, forces=len(forces.entries))
            self._status_sent_ns = 0
        self.outbox.post(self._force_pub, forces)
        self._publish_status()
        return forces

    def set_cpu_state(
        self,
        state: str,
        reason: str = "",
        *,
        stop: DiagEvent | None = None,
        cause: DiagEvent | None = None,
    ) -> None:
        """Report a CPU run state change (RUN/STOP/STARTUP) on ``status`` at once, with
        ``reason``: why it is in STOP, and its diagnostic entries: the STOP's and the error
        that caused it."""
        with self._lock:
            self._status = msgspec.structs.replace(
                self._status, state=state, reason=reason, stop=stop, cause=cause
            )
        self._publish_status()

    def scanned(self, cycle: int, t_ms: int) -> None:
        """A scan ended, without deltas (a program of blocks) or given by :meth:`begin_scan`:
        its cycle and time go into ``status``, published at most once a second."""
        with self._lock:
            self._cycle = (cycle, t_ms)
        if time.monotonic_ns() - self._status_sent_ns >= STATUS_PERIOD_NS:
            self._publish_status()

    # ------------------------------------------------------------ more keys

    def key(self, leaf: str) -> str:
        """The key ``s7graph/<cpu>/<leaf>``."""
        return f"{ROOT}/{self._keys.cpu}/{leaf}"

    def declare_publisher(self, leaf: str) -> zenoh.Publisher:
        """A publisher on ``s7graph/<cpu>/<leaf>`` (JSON, blocking: nothing dropped on the
        way), undeclared with the rest by :meth:`close`; put on it through :meth:`post`."""
        pub = self._session.declare_publisher(
            self.key(leaf),
            encoding=zenoh.Encoding.APPLICATION_JSON,
            congestion_control=zenoh.CongestionControl.BLOCK,
        )
        self._declared.append(pub)
        return pub

    def declare_queryable(self, leaf: str, handler: Callable[[zenoh.Query], None]) -> None:
        """A queryable on ``s7graph/<cpu>/<leaf>`` whose ``handler`` sees each query (on a
        zenoh thread: it must not block or raise), undeclared by :meth:`close`."""
        self._declared.append(self._session.declare_queryable(self.key(leaf), handler))

    def post(self, sink: Sink, message: msgspec.Struct) -> None:
        """Queue ``message`` for the outbox's thread, which encodes it and puts it on
        ``sink`` (a publisher, or a query's :class:`QueryReply`): the scan thread never
        waits for the bus."""
        self.outbox.post(sink, message)

    def set_cycle_stats(self, stats: CycleStats) -> None:
        """Carry ``stats`` in the next ``status`` (published at most once a second)."""
        with self._lock:
            self._status = msgspec.structs.replace(self._status, stats=stats)

    def set_chart(self, fb: str, layout: ChartLayout) -> None:
        """The FB runs another chart (an online change): serve ``layout`` on
        ``fb/<fb>/chart`` (a large one with its parts on ``fb/<fb>/chart/part``) and publish
        it there, so views redraw."""
        if fb not in self._charts:
            raise KeyError(f"unknown FB {fb!r}; known: {', '.join(self._charts)}")
        data, parts = _served(layout)
        with self._lock:
            self._charts[fb] = layout
            self._chart_bytes[fb], self._chart_parts[fb] = data, parts
        with contextlib.suppress(zenoh.ZError):
            self._chart_pubs[fb].put(data)

    def route(self, ops: Iterable[str], handler: Callable[[PendingCommand], None]) -> None:
        """Commands with one of ``ops`` go to ``handler`` (on the zenoh thread: it must not
        block) instead of the scan boundary's queue; it checks, applies, audits and
        answers them itself (``web.bus.online``: the engineering ops)."""
        for op in ops:
            self._routes[op] = handler

    def serve(self, leaf: str, read: Callable[[], bytes | None], *, fb: str | None = None) -> None:
        """One more read-only queryable, ``s7graph/<cpu>/<leaf>`` or, with ``fb``,
        ``s7graph/<cpu>/fb/<fb>/<leaf>``; ``read()`` gives the JSON (None: no answer)."""
        key = self._keys.fb(fb, leaf) if fb is not None else f"{ROOT}/{self._keys.cpu}/{leaf}"
        self._serve(key, read)

    def feed(self, leaf: str) -> Callable[[msgspec.Struct], None]:
        """One more published key, ``s7graph/<cpu>/<leaf>``, also a queryable answering the
        latest message; the function returned publishes a message there (from the scan
        thread: the outbox's thread encodes and puts it). A feed of values whose newest
        is whole (``web.bus.operands``): a put the bus cannot take is dropped."""
        key = f"{ROOT}/{self._keys.cpu}/{leaf}"
        pub = self._session.declare_publisher(key, encoding=zenoh.Encoding.APPLICATION_JSON)
        self._declared.append(pub)
        latest: list[msgspec.Struct | None] = [None]

        def read() -> bytes | None:
            message = latest[0]
            return None if message is None else encode(message)

        self._serve(key, read)

        def post(message: msgspec.Struct) -> None:
            latest[0] = message
            self.outbox.post(pub, message)

        return post

    @property
    def queued(self) -> int:
        """Commands received and not yet taken at a scan boundary."""
        return self._commands.qsize()

    def drain_commands(self) -> list[PendingCommand]:
        """Every command received since the last call, oldest first (call at a scan boundary).

        Commands older than ``max_age_s`` are refused here, not returned: their sender has
        stopped waiting, and applying a command nobody sees answered would surprise."""
        drained: list[PendingCommand] = []
        now = time.monotonic_ns()
        while True:
            try:
                p = self._commands.get_nowait()
            except queue.Empty:
                return drained
            if now - p.received_ns > self._max_age_ns:
                self._expire(p)
            else:
                drained.append(p)

    def apply_commands(
        self,
        apply: Apply,
        *,
        cycle: int | None = None,
        durable: Durability | None = None,
        until_ns: int | None = None,
    ) -> int:
        """Take the pending commands and pass each through the gate: who sent it, may
        their role, then ``apply(command) -> (applied, reason[, detail])`` as that user,
        then the audit row. An exception from ``apply`` refuses that command. Returns how
        many were handled.

        ``until_ns`` (``time.perf_counter_ns``): the end of this boundary's share of the
        cycle for communication (``engine.watchdog.COMM_LOAD_PCT``). Once it is past, the
        commands still waiting stay queued for the next boundary, in order, and
        ``comm_limited`` counts the boundary; one command is always handled, so a flood
        slows the answers, never the scan, and never stops them.

        With ``durable`` (the runner) the replies wait, off the scan thread, until what
        was applied so far — these commands' effects and audit rows — is on disk
        (``durable.when_durable(durable.durable_mark(), ...)``); without it they leave at
        once. Commands still unconfirmed ``REPLY_WITHIN_S`` after they came are answered
        here as not confirmed."""
        self._answer_overdue()
        results = []
        taken = 0
        now = time.monotonic_ns()
        while True:
            if taken and until_ns is not None and time.perf_counter_ns() >= until_ns:
                if not self._commands.empty():
                    self.comm_limited += 1
                break
            try:
                p = self._commands.get_nowait()
            except queue.Empty:
                break
            taken += 1
            if now - p.received_ns > self._max_age_ns:
                self._expire(p)
                continue
            applied, reason = self.gate.apply(p.command, apply, cycle=cycle, note=p.note)
            results.append((p, applied, reason))
        if not results:
            return 0
        if durable is None:
            for p, applied, reason in results:
                p.resolve(applied, reason, cycle=cycle)
            return len(results)
        waiting = _Awaiting(results, cycle, self._within_ns)
        self._awaiting.append(waiting)
        durable.when_durable(durable.durable_mark(), waiting.durable)
        return len(results)

    def _expire(self, p: PendingCommand) -> None:
        p.resolve(False, _EXPIRED)
        self.gate.refuse(p.command, str(_EXPIRED), note=p.note)

    def _answer_overdue(self) -> None:
        now = time.monotonic_ns()
        awaiting = self._awaiting
        while awaiting and (awaiting[0].answered or awaiting[0].deadline_ns <= now):
            waiting = awaiting.popleft()
            waiting.overdue(
                f"the state file has not committed it within {self._within_ns / 1e9:g} s"
            )

    def close(self) -> None:
        """Undeclare queryables and publishers; refuse commands still waiting."""
        for p in self.drain_commands():
            p.resolve(False, Refusal("communication", "CPU bus closed"))
        while self._awaiting:
            self._awaiting.popleft().overdue("the CPU bus closed before it was on disk")
        with contextlib.suppress(Exception):  # the refusals counted so far: written, published
            self.gate.flush()
        self.gate.on_audit = None
        self.outbox.close()  # what the last scans published goes out first
        self._logins.close()
        for d in reversed(self._declared):
            with contextlib.suppress(zenoh.ZError):
                d.undeclare()
        self._declared.clear()

    def __enter__(self) -> BusPublisher:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # ------------------------------------------------------------ zenoh callbacks

    def _publish_status(self) -> None:
        with self._lock:
            self._status_sent_ns = time.monotonic_ns()
            status = self._status_now()
        self.outbox.post(self._status_pub, status)

    def _status_now(self) -> CpuStatus:
        cycle, t_ms = self._cycle
        return msgspec.structs.replace(self._status, cycle=cycle, t_ms=t_ms)

    def _publish_audit(self, entry: AuditEntry) -> None:
        """Queued for the outbox's thread like every other publication: a put from the
        scan thread lets go of the interpreter lock, and getting it back behind the
        threads that take the commands can cost the scan milliseconds."""
        self.outbox.post(self._audit_pub, entry)

    def _serve(self, key: str, read: Callable[[], bytes | None]) -> None:
        """A read-only queryable on ``key`` answering ``read()`` under ``key`` itself, so a
        wildcard query (``s7graph/**``) gets each answer under its own name."""

        def on_query(query: zenoh.Query) -> None:
            try:
                data = read()
            except Exception as exc:  # the asker hears why (an error reply), never a silence
                why = sqlite_words(exc) if isinstance(exc, sqlite3.Error) else str(exc)
                with contextlib.suppress(Exception):  # never raise on a zenoh thread
                    query.reply_err(f"cannot read {key}: {' '.join(why.split())[:160]}".encode())
                return
            with contextlib.suppress(Exception):
                if data is not None:
                    query.reply(key, data, encoding=zenoh.Encoding.APPLICATION_JSON)

        self._declared.append(self._session.declare_queryable(key, on_query))

    def _chart_of(self, fb: str) -> bytes | None:
        return self._chart_bytes.get(fb)

    def _on_part(self, fb: str, query: zenoh.Query) -> None:
        """``fb/<fb>/chart/part?k=K`` (a zenoh thread)."""
        with self._lock:
            parts = self._chart_parts.get(fb, [])
        _answer_part(query, self._keys.fb(fb, "chart/part"), parts)

    def _state_of(self, fb: str) -> bytes | None:
        state = self.deltas.state(fb) if self.deltas is not None else None
        return None if state is None else encode(state)

    def _alarm_bytes(self) -> bytes:
        with self._lock:
            return encode(self._alarms)

    def _force_bytes(self) -> bytes:
        with self._lock:
            return encode(self._forces)

    def _status_bytes(self) -> bytes:
        with self._lock:
            status = self._status_now()
        return encode(status)

    def origin(self, query: zenoh.Query) -> tuple[str, str]:
        """Where ``query`` came from by the transport, and why the CPU cannot tell ("": it
        can; ``web.bus.origin.query_origin``)."""
        return query_origin(self._session, query.source_info)

    def _on_cmd(self, query: zenoh.Query) -> None:
        # Runs on a zenoh thread: validate, enqueue, never block and never raise. A wildcard
        # query is no command: ignored. The command's origin becomes the transport's; the
        # one it claims is kept as the audit row's note.
        if str(query.key_expr) != self._keys.cmd:
            return
        source, unproven = self.origin(query)
        try:
            payload = query.payload
            if payload is None:
                raise ProtocolError("empty command")
            command = decode(payload.to_bytes(), Command)
        except Exception as exc:
            self._refuse(query, None, _unreadable(exc), source)
            return
        note = claimed_note(command.origin)
        command = msgspec.structs.replace(command, origin=source)
        if unproven:  # the link it came over cannot be named: refused, saying what to do
            self._refuse(query, command, Refusal("refused", unproven), source, note)
            return
        if command.fb not in self._charts and not _cpu_wide(command, self._charts):
            runs = f"runs {', '.join(self._charts)}" if self._charts else "runs no GRAPH FB"
            reason = Refusal("not_found", f"unknown FB {command.fb!r}; this CPU {runs}")
            self._refuse(query, command, reason, source, note)
            return
        pending = PendingCommand(command, query, note=note)
        routed = self._routes.get(command.op)
        if routed is not None:
            try:
                routed(pending)
            except Exception as exc:  # never raise on a zenoh thread
                self._refuse(query, command, _route_broke(command, exc), source, note)
            return
        try:
            self._commands.put_nowait(pending)
        except queue.Full:
            reason = Refusal("busy", "command queue full; the CPU is not draining commands")
            self._refuse(query, command, reason, source, note)

    def _refuse(
        self,
        query: zenoh.Query,
        command: Command | None,
        reason: str,
        source: str = "",
        note: str = "",
    ) -> None:
        op, fb = (command.op, command.fb) if command is not None else ("", "")
        _answer(query, refusal_reply(reason, op=op, fb=fb))
        with contextlib.suppress(Exception):  # the audit must not raise on a zenoh thread
            self.gate.refuse(command, str(reason)[:4096], origin=source, note=note)


def _served(layout: ChartLayout) -> tuple[bytes, list[bytes]]:
    """``layout`` as served: its JSON (a head, if too large for one message) and its parts'
    (``protocol.split_layout``)."""
    head, parts = split_layout(layout)
    return encode(head), [encode(p) for p in parts]


def _answer_part(query: zenoh.Query, key: str, parts: list[bytes]) -> None:
    """Answer ``?k=K`` with part K of ``parts`` under ``key``; a bad or missing ``k`` with an
    error reply; a wildcard query not at all (a part is asked for by its exact key). Never
    raises (a zenoh thread)."""
    try:
        if str(query.key_expr) != key:
            return
        given = zenoh.Parameters(str(query.parameters)).get("k")
        if not parts:
            query.reply_err(b"the chart is whole, in one message: read chart, it has no parts")
            return
        if given is None or not given.isdigit() or int(given) >= len(parts):
            why = f"?k={str(given)[:16]!r}: give a part, 0 to {len(parts) - 1}"
            query.reply_err(why.encode())
            return
        query.reply(key, parts[int(given)], encoding=zenoh.Encoding.APPLICATION_JSON)
    except Exception:
        return


def _cpu_wide(command: Command, charts: Mapping[str, object]) -> bool:
    """Whether ``command`` acts on the CPU whatever FB it names: the switch's ops and
    forcing, and on a CPU without an FB (no ``charts``) ``ack_msg`` (the message list is
    the CPU's)."""
    return type(command).where in _CPU_WIDE or (not charts and command.op == "ack_msg")
