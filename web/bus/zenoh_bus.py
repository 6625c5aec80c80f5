"""The zenoh bus between a CPU and its views (DESIGN.md "Edges").

Key space, all under ``s7graph/<cpu>/``:

- ``status`` — :class:`CpuStatus`, published on change and at most once a second
  (also a queryable, for late joiners);
- ``fb/<name>/chart`` — queryable: the :class:`ChartLayout`;
- ``fb/<name>/state`` — queryable: the latest :class:`StepStateUpdate` with its ``seq``;
- ``fb/<name>/delta`` — the :class:`StepStateUpdate` of every scan that changed something;
  ``seq`` counts these, so a late joiner does ``get(state)`` and applies newer deltas only,
  and a gap in ``seq`` means a missed delta;
- ``alarms`` — the :class:`AlarmList` (the CPU's message list), published on change;
  ``alarms/list`` — queryable: the current one (``seq`` orders the two);
- ``cmd`` — queryable: a :class:`Command` in, one :class:`CommandReply` out. Valid commands
  go on a thread-safe queue; the scan loop drains it at a scan boundary and resolves each,
  which sends the reply. Invalid ones are refused at once with the reason.

Sessions use a loopback peer config (listen/connect on 127.0.0.1 or a unix socket,
multicast and gossip scouting off) and must always be closed.
"""

from __future__ import annotations

import contextlib
import json
import queue
import threading
import time
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

import msgspec
import zenoh

from s7graph.web.bus.protocol import (
    AlarmList,
    ChartLayout,
    Command,
    CommandReply,
    CpuStatus,
    CycleStats,
    ProtocolError,
    StepStateUpdate,
    decode,
    encode,
    valid_name,
)

__all__ = [
    "BusClient",
    "BusPublisher",
    "PendingCommand",
    "StateFollower",
    "keys",
    "loopback_config",
    "open_session",
]

ROOT = "s7graph"
COMMAND_QUEUE_SIZE = 256
COMMAND_MAX_AGE_S = 4.5  # older commands are refused: their sender (5 s timeout) gave up
STATUS_PERIOD_S = 1.0


def loopback_config(
    listen: Iterable[str] = (), connect: Iterable[str] = (), *, mode: str = "peer"
) -> zenoh.Config:
    """A zenoh config that talks only to the given endpoints, never multicasts or gossips.

    Endpoints look like ``tcp/127.0.0.1:7447`` or ``unixsock-stream/<dir>/z.sock``. With no
    endpoints at all, the session only reaches itself (useful in one process)."""
    config = zenoh.Config()
    config.insert_json5("mode", json.dumps(mode))
    config.insert_json5("listen/endpoints", json.dumps(list(listen)))
    config.insert_json5("connect/endpoints", json.dumps(list(connect)))
    config.insert_json5("scouting/multicast/enabled", "false")
    config.insert_json5("scouting/gossip/enabled", "false")
    return config


def open_session(listen: Iterable[str] = (), connect: Iterable[str] = ()) -> zenoh.Session:
    """Open a loopback peer session; the caller closes it (``with open_session(...) as s:``)."""
    return zenoh.open(loopback_config(listen, connect))


@dataclass(frozen=True, slots=True)
class keys:
    """Key expressions of one CPU."""

    cpu: str

    def __post_init__(self) -> None:
        if not valid_name(self.cpu):
            raise ValueError(f"invalid CPU name {self.cpu!r} for a key expression")

    @property
    def status(self) -> str:
        return f"{ROOT}/{self.cpu}/status"

    @property
    def alarms(self) -> str:
        return f"{ROOT}/{self.cpu}/alarms"

    @property
    def alarm_list(self) -> str:
        return f"{ROOT}/{self.cpu}/alarms/list"

    @property
    def cmd(self) -> str:
        return f"{ROOT}/{self.cpu}/cmd"

    def fb(self, name: str, leaf: str) -> str:
        if not valid_name(name):
            raise ValueError(f"invalid FB name {name!r} for a key expression")
        return f"{ROOT}/{self.cpu}/fb/{name}/{leaf}"


# ---------------------------------------------------------------- CPU side


@dataclass(eq=False)
class PendingCommand:
    """A validated command waiting for the scan boundary; :meth:`resolve` sends the reply."""

    command: Command
    query: zenoh.Query | None = None
    received_ns: int = field(default_factory=time.monotonic_ns)
    reply: CommandReply | None = None

    def resolve(self, applied: bool, reason: str = "", *, cycle: int | None = None) -> None:
        """Answer the sender once: applied, or refused and why."""
        if self.reply is not None:
            return
        self.reply = CommandReply(
            applied=applied,
            reason=reason[:4096],
            op=self.command.op,
            fb=self.command.fb,
            cycle=cycle,
        )
        _answer(self.query, self.reply)
        self.query = None


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

    Call :meth:`publish` once per scan per FB, and :meth:`drain_commands` at the scan
    boundary; :meth:`close` undeclares everything (the session stays the caller's)."""

    def __init__(
        self,
        session: zenoh.Session,
        cpu: str,
        charts: Mapping[str, ChartLayout],
        *,
        queue_size: int = COMMAND_QUEUE_SIZE,
        max_age_s: float = COMMAND_MAX_AGE_S,
    ) -> None:
        self._keys = keys(cpu)
        self._session = session
        self._lock = threading.Lock()
        self._charts = dict(charts)
        self._chart_bytes = {name: encode(layout) for name, layout in self._charts.items()}
        self._state: dict[str, StepStateUpdate] = {}
        self._seq: dict[str, int] = dict.fromkeys(self._charts, 0)
        self._commands: queue.Queue[PendingCommand] = queue.Queue(maxsize=queue_size)
        self._max_age_ns = int(max_age_s * 1e9)
        self._status = CpuStatus(cpu=cpu, fbs=list(self._charts))
        self._status_sent_ns = 0
        self._alarms = AlarmList()
        self._declared: list[Any] = []
        self._delta_pubs: dict[str, zenoh.Publisher] = {}
        try:
            for name in self._charts:
                self._declared.append(
                    session.declare_queryable(self._keys.fb(name, "chart"), self._on_chart)
                )
                self._declared.append(
                    session.declare_queryable(self._keys.fb(name, "state"), self._on_state)
                )
                pub = session.declare_publisher(
                    self._keys.fb(name, "delta"),
                    encoding=zenoh.Encoding.APPLICATION_JSON,
                    congestion_control=zenoh.CongestionControl.BLOCK,
                )
                self._delta_pubs[name] = pub
                self._declared.append(pub)
            self._declared.append(session.declare_queryable(self._keys.cmd, self._on_cmd))
            self._declared.append(session.declare_queryable(self._keys.status, self._on_status))
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
            self._declared.append(
                session.declare_queryable(self._keys.alarm_list, self._on_alarm_list)
            )
        except BaseException:
            self.close()
            raise

    # ------------------------------------------------------------ scan side

    def publish(self, fb: str, update: StepStateUpdate) -> bool:
        """Record one scan of ``fb``; publish a delta if something changed. Returns whether
        a delta went out. ``update.seq`` is replaced by the bus's own change counter."""
        if fb not in self._charts:
            raise KeyError(f"unknown FB {fb!r}; known: {', '.join(self._charts)}")
        with self._lock:
            previous = self._state.get(fb)
            changed = update.changed_from(previous)
            if changed:
                self._seq[fb] += 1
            update = msgspec.structs.replace(update, seq=self._seq[fb])
            self._state[fb] = update
        if changed:
            self._delta_pubs[fb].put(encode(update))
        self._publish_status(update)
        return changed

    def publish_alarms(self, alarms: AlarmList) -> AlarmList:
        """Publish a changed message list on ``alarms`` (``seq`` is the bus's own counter)
        and serve it on ``alarms/list``; returns what went out."""
        with self._lock:
            alarms = msgspec.structs.replace(alarms, seq=self._alarms.seq + 1)
            self._alarms = alarms
        self._alarm_pub.put(encode(alarms))
        return alarms

    def set_cpu_state(self, state: str) -> None:
        """Report a CPU run state change (RUN/STOP/STARTUP) on ``status`` at once."""
        with self._lock:
            self._status = msgspec.structs.replace(self._status, state=state)
            self._status_sent_ns = 0
        self._publish_status(None)

    def set_cycle_stats(self, stats: CycleStats) -> None:
        """Carry ``stats`` in the next ``status`` (published at most once a second)."""
        with self._lock:
            self._status = msgspec.structs.replace(self._status, stats=stats)

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
                p.resolve(False, "expired before the scan boundary")
            else:
                drained.append(p)

    def apply_commands(
        self, apply: Callable[[Command], tuple[bool, str]], *, cycle: int | None = None
    ) -> int:
        """Drain and apply every pending command with ``apply(command) -> (applied, reason)``;
        an exception from ``apply`` refuses that command. Returns how many were handled."""
        pending = self.drain_commands()
        for p in pending:
            try:
                applied, reason = apply(p.command)
            except Exception as exc:  # a bad command must not stop the scan loop
                applied, reason = False, f"{type(exc).__name__}: {exc}"
            p.resolve(applied, reason, cycle=cycle)
        return len(pending)

    def close(self) -> None:
        """Undeclare queryables and publishers; refuse commands still waiting."""
        for p in self.drain_commands():
            p.resolve(False, "CPU bus closed")
        for d in reversed(self._declared):
            with contextlib.suppress(zenoh.ZError):
                d.undeclare()
        self._declared.clear()

    def __enter__(self) -> BusPublisher:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # ------------------------------------------------------------ zenoh callbacks

    def _publish_status(self, update: StepStateUpdate | None) -> None:
        now = time.monotonic_ns()
        with self._lock:
            if update is not None:
                self._status = msgspec.structs.replace(
                    self._status, cycle=update.cycle, t_ms=update.t_ms
                )
            if now - self._status_sent_ns < STATUS_PERIOD_S * 1e9:
                return
            self._status_sent_ns = now
            payload = encode(self._status)
        self._status_pub.put(payload)

    def _fb_of(self, query: zenoh.Query) -> str:
        return str(query.key_expr).split("/")[-2]

    def _on_chart(self, query: zenoh.Query) -> None:
        data = self._chart_bytes.get(self._fb_of(query))
        if data is not None:
            query.reply(query.key_expr, data, encoding=zenoh.Encoding.APPLICATION_JSON)

    def _on_state(self, query: zenoh.Query) -> None:
        with self._lock:
            state = self._state.get(self._fb_of(query))
        if state is not None:
            query.reply(query.key_expr, encode(state), encoding=zenoh.Encoding.APPLICATION_JSON)

    def _on_alarm_list(self, query: zenoh.Query) -> None:
        with self._lock:
            payload = encode(self._alarms)
        query.reply(query.key_expr, payload, encoding=zenoh.Encoding.APPLICATION_JSON)

    def _on_status(self, query: zenoh.Query) -> None:
        with self._lock:
            payload = encode(self._status)
        query.reply(query.key_expr, payload, encoding=zenoh.Encoding.APPLICATION_JSON)

    def _on_cmd(self, query: zenoh.Query) -> None:
        # Runs on a zenoh thread: validate, enqueue, never block and never raise.
        try:
            payload = query.payload
            if payload is None:
                raise ProtocolError("empty command")
            command = decode(payload.to_bytes(), Command)
        except ProtocolError as exc:
            _answer(query, CommandReply(applied=False, reason=str(exc)))
            return
        except Exception as exc:
            _answer(query, CommandReply(applied=False, reason=f"bad command: {exc}"))
            return
        if command.fb not in self._charts:
            reason = f"unknown FB {command.fb!r}; this CPU runs {', '.join(self._charts)}"
            _answer(query, CommandReply(applied=False, reason=reason, op=command.op, fb=command.fb))
            return
        try:
            self._commands.put_nowait(PendingCommand(command, query))
        except queue.Full:
            reason = "command queue full; the CPU is not draining commands"
            _answer(query, CommandReply(applied=False, reason=reason, op=command.op))


# ---------------------------------------------------------------- view side


class BusClient:
    """A view's (or a test's) handle on one CPU over the bus."""

    def __init__(self, session: zenoh.Session, cpu: str, *, timeout: float = 5.0) -> None:
        self._keys = keys(cpu)
        self._session = session
        self._timeout = timeout
        self._subscribers: list[zenoh.Subscriber[Any]] = []

    def _get_one(
        self, key: str, payload: bytes | None = None, timeout: float | None = None
    ) -> bytes | None:
        replies = self._session.get(key, payload=payload, timeout=timeout or self._timeout)
        for reply in replies:
            if reply.ok is not None:
                return reply.ok.payload.to_bytes()
        return None

    def chart(self, fb: str) -> ChartLayout | None:
        """The FB's chart structure, or None if no CPU answers."""
        data = self._get_one(self._keys.fb(fb, "chart"))
        return None if data is None else decode(data, ChartLayout)

    def state(self, fb: str) -> StepStateUpdate | None:
        """The FB's latest state, or None if no CPU answers or no scan ran yet."""
        data = self._get_one(self._keys.fb(fb, "state"))
        return None if data is None else decode(data, StepStateUpdate)

    def status(self) -> CpuStatus | None:
        data = self._get_one(self._keys.status)
        return None if data is None else decode(data, CpuStatus)

    def alarms(self) -> AlarmList | None:
        """The CPU's current message list, or None if no CPU answers."""
        data = self._get_one(self._keys.alarm_list)
        return None if data is None else decode(data, AlarmList)

    def on_alarms(self, callback: Callable[[AlarmList], None]) -> None:
        """Call ``callback`` with the current message list, then with each newer one (by
        ``seq``; on a zenoh thread)."""
        lock = threading.Lock()
        latest = [-1]

        def offer(alarms: AlarmList) -> None:
            with lock:
                if alarms.seq <= latest[0]:
                    return
                latest[0] = alarms.seq
                callback(alarms)

        def on_sample(sample: zenoh.Sample) -> None:
            with contextlib.suppress(ProtocolError):
                offer(decode(sample.payload.to_bytes(), AlarmList))

        self._subscribers.append(self._session.declare_subscriber(self._keys.alarms, on_sample))
        with contextlib.suppress(ProtocolError, zenoh.ZError):
            current = self.alarms()
            if current is not None:
                offer(current)

    def send(self, command: Command, *, timeout: float | None = None) -> CommandReply:
        """Send a command and wait for the CPU's answer; no answer is a refusal too."""
        wait = timeout or self._timeout
        try:
            data = self._get_one(self._keys.cmd, encode(command), wait)
        except zenoh.ZError as exc:
            return CommandReply(applied=False, reason=f"bus error: {type(exc).__name__}")
        if data is None:
            reason = f"no answer from CPU {self._keys.cpu!r} within {wait:g} s"
            return CommandReply(applied=False, reason=reason, op=command.op, fb=command.fb)
        try:
            return decode(data, CommandReply)
        except ProtocolError as exc:
            return CommandReply(applied=False, reason=f"unreadable answer: {exc}")

    def send_raw(self, payload: bytes, *, timeout: float | None = None) -> CommandReply | None:
        """Send raw bytes to ``cmd`` (for tests of hostile input); None if nobody answered."""
        data = self._get_one(self._keys.cmd, payload, timeout)
        return None if data is None else decode(data, CommandReply)

    def follow(self, fb: str, on_update: Callable[[StepStateUpdate], None]) -> StateFollower:
        """Subscribe to deltas, then fetch the state: ``on_update`` sees each newer state once,
        in ``seq`` order (it runs on a zenoh thread; keep it short)."""
        follower = StateFollower(on_update)
        sub = self._session.declare_subscriber(self._keys.fb(fb, "delta"), follower.on_sample)
        self._subscribers.append(sub)
        follower.resync = lambda: self.state(fb)  # type: ignore[method-assign]
        follower.start()
        return follower

    def on_status(self, callback: Callable[[CpuStatus], None]) -> None:
        """Call ``callback`` with every published status."""

        def on_sample(sample: zenoh.Sample) -> None:
            with contextlib.suppress(ProtocolError):
                callback(decode(sample.payload.to_bytes(), CpuStatus))

        self._subscribers.append(self._session.declare_subscriber(self._keys.status, on_sample))

    def close(self) -> None:
        """Undeclare every subscriber (the session stays the caller's)."""
        for sub in self._subscribers:
            with contextlib.suppress(zenoh.ZError):
                sub.undeclare()  # type: ignore[no-untyped-call]  # zenoh's stub: no annotations
        self._subscribers.clear()

    def __enter__(self) -> BusClient:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class StateFollower:
    """Keeps the newest state of one FB from a snapshot plus ``seq``-numbered deltas."""

    def __init__(self, on_update: Callable[[StepStateUpdate], None]) -> None:
        self._on_update = on_update
        self._lock = threading.Lock()
        self.latest: StepStateUpdate | None = None
        self.gaps = 0  # deltas missed (a resync fetched the state again)

    def resync(self) -> StepStateUpdate | None:  # replaced by BusClient.follow
        return None

    def start(self) -> None:
        snapshot = self.resync()
        if snapshot is not None:
            self._offer(snapshot)

    def on_sample(self, sample: zenoh.Sample) -> None:
        try:
            update = decode(sample.payload.to_bytes(), StepStateUpdate)
        except ProtocolError:
            return
        latest = self.latest
        if latest is not None and update.seq > latest.seq + 1:
            self.gaps += 1
        self._offer(update)

    def _offer(self, update: StepStateUpdate) -> None:
        with self._lock:
            latest = self.latest
            if latest is not None and (update.seq, update.cycle) <= (latest.seq, latest.cycle):
                return  # stale, or the same scan seen twice (snapshot and delta)
            self.latest = update
            # Called under the lock so updates reach the view in order.
            self._on_update(update)
