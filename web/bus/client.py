"""A view's (or a command line's, or a test's) side of the zenoh bus: :class:`BusClient`
reads, follows and commands one CPU through its keys (:mod:`web.bus.keys`),
:class:`StateFollower` keeps an FB's newest state from a snapshot and its deltas, and
:func:`find_cpus` lists the CPUs on the bus."""

from __future__ import annotations

import contextlib
import threading
from collections.abc import Callable
from typing import Any

import zenoh

from s7graph.web.bus.keys import ROOT, keys
from s7graph.web.bus.protocol import (
    AlarmHistory,
    AlarmList,
    AuditEntry,
    AuditList,
    ChartLayout,
    ChartSource,
    Command,
    CommandReply,
    CpuStatus,
    ForceList,
    LoginReply,
    LoginRequest,
    OperandCatalog,
    OperandValues,
    ProjectFiles,
    ProtocolError,
    StepStateUpdate,
    decode,
    encode,
)

__all__ = ["BusClient", "StateFollower", "find_cpus"]

CLIENT_TIMEOUT_S = 5.0
"""How long a :class:`BusClient` waits for an answer."""


class BusClient:
    """A view's (or a test's) handle on one CPU over the bus."""

    def __init__(
        self, session: zenoh.Session, cpu: str, *, timeout: float = CLIENT_TIMEOUT_S
    ) -> None:
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

    def source(self, fb: str) -> ChartSource | None:
        """The ``.s7g`` source of the chart the FB runs, or None if no CPU answers."""
        data = self._get_one(self._keys.fb(fb, "source"))
        return None if data is None else decode(data, ChartSource)

    def project(self) -> ProjectFiles | None:
        """The charts and importable files of the CPU's project directory (None: no CPU
        answers, or it has none)."""
        data = self._get_one(f"{ROOT}/{self._keys.cpu}/project")
        return None if data is None else decode(data, ProjectFiles)

    def on_chart(self, fb: str, callback: Callable[[ChartLayout], None]) -> None:
        """Call ``callback`` with the FB's chart each time the CPU runs another version."""

        def on_sample(sample: zenoh.Sample) -> None:
            with contextlib.suppress(ProtocolError):
                callback(decode(sample.payload.to_bytes(), ChartLayout))

        key = self._keys.fb(fb, "chart")
        self._subscribers.append(self._session.declare_subscriber(key, on_sample))

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
        self._follow_seq(self._keys.alarms, AlarmList, self.alarms, callback)

    def _follow_seq(
        self,
        key: str,
        kind: type[Any],
        current: Callable[[], Any],
        callback: Callable[[Any], None],
    ) -> None:
        """Subscribe to ``key``'s publications of ``kind`` and fetch the current one:
        ``callback`` sees each newer one (by ``seq``) once."""
        lock = threading.Lock()
        latest = [-1]

        def offer(message: Any) -> None:
            with lock:
                if message.seq <= latest[0]:
                    return
                latest[0] = message.seq
                callback(message)

        def on_sample(sample: zenoh.Sample) -> None:
            with contextlib.suppress(ProtocolError):
                offer(decode(sample.payload.to_bytes(), kind))

        self._subscribers.append(self._session.declare_subscriber(key, on_sample))
        with contextlib.suppress(ProtocolError, zenoh.ZError):
            message = current()
            if message is not None:
                offer(message)

    def forces(self) -> ForceList | None:
        """The CPU's force jobs, or None if no CPU answers."""
        data = self._get_one(self._keys.forces)
        return None if data is None else decode(data, ForceList)

    def on_forces(self, callback: Callable[[ForceList], None]) -> None:
        """Call ``callback`` with the current force jobs, then with each newer list (by
        ``seq``; on a zenoh thread)."""
        self._follow_seq(self._keys.forces, ForceList, self.forces, callback)

    def operands(self) -> OperandValues | None:
        """The CPU's latest operand values, or None if no CPU answers (or it has none)."""
        data = self._get_one(self._keys.operands)
        return None if data is None else decode(data, OperandValues)

    def operand_catalog(self) -> OperandCatalog | None:
        """What the CPU's operand values carry (names, types, addresses), or None."""
        data = self._get_one(self._keys.operand_list)
        return None if data is None else decode(data, OperandCatalog)

    def on_operands(self, callback: Callable[[OperandValues], None]) -> None:
        """Call ``callback`` with the current operand values, then with each newer one (by
        ``seq``; on a zenoh thread)."""
        self._follow_seq(self._keys.operands, OperandValues, self.operands, callback)

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

    def login(self, user: str, password: str = "", *, origin: str = "") -> LoginReply:
        """Log in at the CPU (no password needed without a users file); the reply holds the
        token to put in each :class:`Command`. No answer is a refusal too."""
        try:
            request = LoginRequest(op="login", user=user, password=password, origin=origin)
        except (TypeError, ValueError) as exc:
            return LoginReply(ok=False, reason=str(exc))
        return self._ask_login(request)

    def logout(self, token: str, *, user: str = "", origin: str = "") -> LoginReply:
        """Revoke ``token`` at the CPU."""
        return self._ask_login(LoginRequest(op="logout", user=user, token=token, origin=origin))

    def _ask_login(self, request: LoginRequest) -> LoginReply:
        try:
            data = self._get_one(self._keys.login, encode(request))
        except (ProtocolError, zenoh.ZError) as exc:
            return LoginReply(ok=False, reason=f"bus error: {type(exc).__name__}")
        if data is None:
            return LoginReply(ok=False, reason=f"no answer from CPU {self._keys.cpu!r}")
        try:
            return decode(data, LoginReply)
        except ProtocolError as exc:
            return LoginReply(ok=False, reason=f"unreadable answer: {exc}")

    def audit(self) -> AuditList | None:
        """The CPU's last 50 audit rows, or None if no CPU answers."""
        data = self._get_one(self._keys.audit_list)
        return None if data is None else decode(data, AuditList)

    def history(self) -> AlarmHistory | None:
        """The CPU's last 200 message events, or None if no CPU answers."""
        data = self._get_one(self._keys.alarm_history)
        return None if data is None else decode(data, AlarmHistory)

    def on_audit(self, callback: Callable[[AuditEntry], None]) -> None:
        """Call ``callback`` with each audit row as the CPU writes it (on a zenoh thread)."""

        def on_sample(sample: zenoh.Sample) -> None:
            with contextlib.suppress(ProtocolError):
                callback(decode(sample.payload.to_bytes(), AuditEntry))

        self._subscribers.append(self._session.declare_subscriber(self._keys.audit, on_sample))

    def on_alive(self, callback: Callable[[bool], None]) -> None:
        """Call ``callback(True)`` when the CPU's bus appears (also if it is up already) and
        ``callback(False)`` when it goes (closed, crashed, or the link lost)."""

        def on_sample(sample: zenoh.Sample) -> None:
            callback(sample.kind == zenoh.SampleKind.PUT)

        sub = self._session.liveliness().declare_subscriber(
            self._keys.alive, on_sample, history=True
        )
        self._subscribers.append(sub)

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


def find_cpus(session: zenoh.Session, *, timeout: float = 2.0) -> list[CpuStatus]:
    """The status of every CPU answering on the bus (a wildcard query), sorted by name."""
    found: dict[str, CpuStatus] = {}
    replies = session.get(
        f"{ROOT}/*/status",
        timeout=timeout,
        target=zenoh.QueryTarget.ALL,
        consolidation=zenoh.ConsolidationMode.NONE,
    )
    for reply in replies:
        if reply.ok is None:
            continue
        with contextlib.suppress(ProtocolError):
            status = decode(reply.ok.payload.to_bytes(), CpuStatus)
            found[status.cpu] = status
    return [found[name] for name in sorted(found)]


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
