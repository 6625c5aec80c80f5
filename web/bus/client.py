"""A view's (or a command line's, or a test's) side of the zenoh bus: :class:`BusClient`
reads, follows and commands one CPU through its keys (:mod:`web.bus.keys`),
:class:`StateFollower` keeps an FB's newest state from a snapshot and its deltas, and
:func:`find_cpus` lists the CPUs on the bus.

A client follows FBs through one subscription to the CPU's ``deltas`` (one message per
scan, every changed FB's delta): :class:`DeltaFeed` decodes each message's envelope once,
then only the deltas of the FBs followed, and hands each to its followers; a gap in the
messages' ``seq`` (one lost: a congested CPU dropped it) makes every follower get its FB's
``state`` again, on a thread of the feed's own."""

from __future__ import annotations

import contextlib
import threading
import time
from collections.abc import Callable, Sequence
from typing import Any, Literal, TypeVar

import msgspec
import zenoh

from s7graph.web.access.scram import Signer, log_in
from s7graph.web.access.users import name_problem
from s7graph.web.bus.keys import ROOT, keys
from s7graph.web.bus.origin import stamp
from s7graph.web.bus.protocol import (
    AlarmHistory,
    AlarmList,
    AuditEntry,
    AuditList,
    BlockSources,
    ChartLayout,
    ChartPart,
    ChartSource,
    Command,
    CommandReply,
    CpuStatus,
    DiagBuffer,
    ForceList,
    LoginReply,
    LoginRequest,
    OperandCatalog,
    OperandValues,
    ProjectFiles,
    ProtocolError,
    Refusal,
    StepStateUpdate,
    SyncReport,
    WatchRequest,
    WatchValues,
    decode,
    encode,
    join_layout,
    refusal_reply,
    watch_bytes,
)

__all__ = [
    "BusClient",
    "DeltaFeed",
    "ErrorReply",
    "StateFollower",
    "find_cpus",
    "no_answer",
    "unread_note",
    "wait_for_cpus",
]

_Answer = TypeVar("_Answer", WatchValues, SyncReport)
_Read = TypeVar("_Read")

CLIENT_TIMEOUT_S = 5.0
"""How long a :class:`BusClient` waits for an answer."""
MAX_SESSIONS = 4096
"""Logins one client keeps the session keys of (a view: one per page logged in)."""
ZENOH_TIMEOUT = b"Timeout"
"""The error reply zenoh itself gives a query whose wait ran out (from either end, with or
without a replier id: zenoh 1.x), which is no answer, not the CPU's."""
REASON_CHARS = 200
"""Of an error reply's reason, at most this much is shown (a peer may send anything)."""


class ErrorReply(ProtocolError):
    """A query answered with an error (zenoh's ``reply_err``), not the message asked for:
    the text names the key and gives the answerer's reason, on one line."""


def refusal(reply: zenoh.Reply) -> bytes | None:
    """The reason of an error reply; None for an answer, or for zenoh's own ``Timeout``
    (no answer)."""
    if reply.err is None:
        return None
    said = reply.err.payload.to_bytes()
    return None if said == ZENOH_TIMEOUT else said


def one_line(reason: bytes) -> str:
    """An error reply's reason as one printable line of at most ``REASON_CHARS``."""
    text = "".join(c if c.isprintable() else " " for c in reason.decode("utf-8", "replace"))
    text = " ".join(text.split())
    return text if len(text) <= REASON_CHARS else text[: REASON_CHARS - 1] + "…"


def no_answer(cpu: str, wait: float, waited: float) -> str:
    """Why a request of CPU ``cpu`` got no answer: the ``wait`` ran out, or the bus ended it
    sooner — after ``waited`` s, with no CPU of that name reachable to answer (none on the
    bus, the CPU gone, its link lost). Both begin ``no answer from CPU``."""
    if waited < wait - min(0.5, wait / 2):  # ended well before the wait was up
        return (
            f"no answer from CPU {cpu!r}: the bus ended the request after {waited:.1f} s "
            "(no such CPU reachable: not running, or its link lost)"
        )
    return f"no answer from CPU {cpu!r} within {wait:g} s"


class BusClient:
    """A view's (or a test's) handle on one CPU over the bus."""

    def __init__(
        self, session: zenoh.Session, cpu: str, *, timeout: float = CLIENT_TIMEOUT_S
    ) -> None:
        self._keys = keys(cpu)
        self._session = session
        self._timeout = timeout
        self._subscribers: list[zenoh.Subscriber[Any]] = []
        self._lock = threading.Lock()
        self._signers: dict[str, Signer] = {}  # token -> its session's key and seq
        self._feed: DeltaFeed | None = None  # the followers of ``deltas`` (``follow``)

    def _get_one(
        self, key: str, payload: bytes | None = None, timeout: float | None = None
    ) -> bytes | None:
        replies = self._session.get(
            key,
            payload=payload,
            timeout=timeout or self._timeout,
            source_info=stamp(self._session),  # the CPU audits the link it came over
        )
        refused = None
        for reply in replies:
            if reply.ok is not None:
                return reply.ok.payload.to_bytes()
            if refused is None:
                refused = refusal(reply)
        if refused is not None:
            where = key.partition("?")[0]
            raise ErrorReply(f"{where}: the CPU answered with an error: {one_line(refused)}")
        return None

    def _read(
        self,
        key: str,
        kind: type[_Read],
        payload: bytes | None = None,
        timeout: float | None = None,
    ) -> _Read | None:
        """The answer to a query of ``key`` as ``kind``, or None if nobody answers; an
        error reply, or an answer that does not decode, raises :class:`ProtocolError`
        naming the key."""
        data = self._get_one(key, payload, timeout)
        if data is None:
            return None
        try:
            return decode(data, kind)
        except ProtocolError as exc:
            raise ProtocolError(f"{key.partition('?')[0]}: unreadable answer: {exc}") from None

    def _ask(
        self, key: str, kind: type[_Read], payload: bytes | None, wait: float | None
    ) -> _Read | str | None:
        """:meth:`_read` for a request that must come back as a reply: the answer, None
        when nobody answered, or why it is none — the bus failed, an error reply, an
        answer that does not decode (naming the key)."""
        try:
            return self._read(key, kind, payload, wait)
        except zenoh.ZError as exc:
            said = " ".join(str(exc).split()) or "it gave no reason"
            return f"{key.partition('?')[0]}: bus error: {said[:256]}"
        except ProtocolError as exc:  # an error reply (ErrorReply) or no message
            return str(exc)

    def chart(self, fb: str) -> ChartLayout | None:
        """The FB's chart structure, whole (a large one fetched in parts), or None if no
        CPU answers."""
        head = self._read(self._keys.fb(fb, "chart"), ChartLayout)
        return None if head is None else self._whole(head)

    def _whole(self, head: ChartLayout, tries: int = 3) -> ChartLayout | None:
        """``head`` with its parts (``fb/<fb>/chart/part?k=K``); fetched again from the
        head when the CPU ran another chart version meanwhile; None if a part does not
        come. Not on a zenoh thread."""
        for _ in range(tries):
            if not head.parts:
                return head
            key = self._keys.fb(head.fb, "chart/part")
            parts = []
            try:
                for k in range(head.parts):
                    data = self._get_one(f"{key}?k={k}")
                    if data is None:
                        return None
                    parts.append(decode(data, ChartPart))
            except ErrorReply:  # no such part now: the CPU runs a version in fewer parts
                parts.clear()
            if parts and all(p.version == head.version for p in parts):
                return join_layout(head, parts)
            again = self._read(self._keys.fb(head.fb, "chart"), ChartLayout)
            if again is None:
                return None
            head = again
        raise ProtocolError(f"chart of {head.fb}: its version changed while it was read")

    def source(self, fb: str) -> ChartSource | None:
        """The ``.s7g`` source of the chart the FB runs, or None if no CPU answers."""
        return self._read(self._keys.fb(fb, "source"), ChartSource)

    def project(self) -> ProjectFiles | None:
        """The charts and importable files of the CPU's project directory (None: no CPU
        answers, or it has none)."""
        return self._read(f"{ROOT}/{self._keys.cpu}/project", ProjectFiles)

    def on_chart(self, fb: str, callback: Callable[[ChartLayout], None]) -> None:
        """Call ``callback`` with the FB's chart (whole) each time the CPU runs another
        version."""

        newest = [0]  # the version last given to ``callback``
        lock = threading.Lock()

        def deliver(head: ChartLayout) -> None:
            with contextlib.suppress(ProtocolError):
                layout = self._whole(head)
                with lock:
                    if layout is None or layout.version < newest[0]:
                        return
                    newest[0] = layout.version
                callback(layout)

        def on_sample(sample: zenoh.Sample) -> None:
            with contextlib.suppress(ProtocolError):
                head = decode(sample.payload.to_bytes(), ChartLayout)
                if not head.parts:
                    deliver(head)
                    return  # the parts are fetched off the zenoh thread
                threading.Thread(target=deliver, args=(head,), daemon=True).start()

        key = self._keys.fb(fb, "chart")
        self._subscribers.append(self._session.declare_subscriber(key, on_sample))

    def state(self, fb: str) -> StepStateUpdate | None:
        """The FB's latest state, or None if no CPU answers or no scan ran yet."""
        return self._read(self._keys.fb(fb, "state"), StepStateUpdate)

    def status(self) -> CpuStatus | None:
        return self._read(self._keys.status, CpuStatus)

    def alarms(self) -> AlarmList | None:
        """The CPU's current message list, or None if no CPU answers."""
        return self._read(self._keys.alarm_list, AlarmList)

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
        return self._read(self._keys.forces, ForceList)

    def on_forces(self, callback: Callable[[ForceList], None]) -> None:
        """Call ``callback`` with the current force jobs, then with each newer list (by
        ``seq``; on a zenoh thread)."""
        self._follow_seq(self._keys.forces, ForceList, self.forces, callback)

    def diag(self, n: int | None = None) -> DiagBuffer | None:
        """The CPU's diagnostic buffer, newest first (its newest ``n`` entries; the CPU's
        default 100), or None if no CPU answers."""
        key = self._keys.diag if n is None else f"{self._keys.diag}?n={n}"
        return self._read(key, DiagBuffer)

    def on_diag(self, callback: Callable[[DiagBuffer], None]) -> None:
        """Call ``callback`` with the entries the CPU writes from now on, newest first, as
        it publishes them (``diag/new``, on a zenoh thread)."""

        def on_sample(sample: zenoh.Sample) -> None:
            with contextlib.suppress(ProtocolError):
                callback(decode(sample.payload.to_bytes(), DiagBuffer))

        key = self._keys.diag_new
        self._subscribers.append(self._session.declare_subscriber(key, on_sample))

    def watch(
        self, addresses: Sequence[str], *, timeout: float | None = None, token: str = ""
    ) -> WatchValues:
        """The values of ``addresses`` at the CPU's next scan boundary; no answer, or a
        request the CPU refuses, is a ``WatchValues`` with its ``error``. With the
        ``token`` of a login of this client the request is numbered and signed with its
        session key (the CPU queues it in its user's own share)."""
        request = WatchRequest(addresses=list(addresses))
        signer = self._signer(token)
        if signer is not None:
            request = msgspec.structs.replace(request, user=signer.user, token=token)

            def message(seq: int) -> bytes:
                return watch_bytes(msgspec.structs.replace(request, seq=seq))

            seq, mac = signer.numbered(message)
            request = msgspec.structs.replace(request, seq=seq, mac=mac or msgspec.UNSET)
        return self._answer(self._keys.watch, encode(request), WatchValues, timeout)

    def synchronization(self, fb: str, *, timeout: float | None = None) -> SyncReport:
        """Every step of ``fb`` judged against the process values at the CPU's next scan
        boundary (``fb/<fb>/sync``); no answer, or a refusal, is a report with its
        ``error``."""
        return self._answer(self._keys.fb(fb, "sync"), None, SyncReport, timeout)

    def _answer(
        self, key: str, payload: bytes | None, kind: type[_Answer], timeout: float | None
    ) -> _Answer:
        """The CPU's answer to a query of ``key`` as ``kind``; a ``kind`` with its
        ``error`` when the bus fails, no CPU answers in time or the answer is unreadable."""
        wait, asked = timeout or self._timeout, time.monotonic()
        got = self._ask(key, kind, payload, wait)
        if got is None:
            got = no_answer(self._keys.cpu, wait, time.monotonic() - asked)
        return kind(error=got) if isinstance(got, str) else got

    def blocks(self) -> BlockSources | None:
        """The S7-SCL blocks the CPU runs, as source, or None if no CPU answers."""
        return self._read(self._keys.blocks, BlockSources)

    def operands(self) -> OperandValues | None:
        """The CPU's latest operand values, or None if no CPU answers (or it has none)."""
        return self._read(self._keys.operands, OperandValues)

    def operand_catalog(self) -> OperandCatalog | None:
        """What the CPU's operand values carry (names, types, addresses), or None."""
        return self._read(self._keys.operand_list, OperandCatalog)

    def on_operands(self, callback: Callable[[OperandValues], None]) -> None:
        """Call ``callback`` with the current operand values, then with each newer one (by
        ``seq``; on a zenoh thread)."""
        self._follow_seq(self._keys.operands, OperandValues, self.operands, callback)

    def send(self, command: Command, *, timeout: float | None = None) -> CommandReply:
        """Send a command and wait for the CPU's answer; no answer — or one that cannot be
        read — is a refusal too, of kind ``communication``. A
        command with the token of a login of this client is numbered and signed with
        its session key first (unless it carries a ``mac`` already)."""
        wait = timeout or self._timeout
        signer = self._signer(command.token)
        if signer is not None and not command.mac:
            command = signer.sign(command)
        asked = time.monotonic()
        got = self._ask(self._keys.cmd, CommandReply, encode(command), wait)
        if got is None:
            got = no_answer(self._keys.cpu, wait, time.monotonic() - asked)
        if isinstance(got, str):
            return refusal_reply(Refusal("communication", got), op=command.op, fb=command.fb)
        return got

    def login(self, user: str, password: str = "", *, origin: str = "") -> LoginReply:
        """Log in at the CPU (no password needed without a users file) by SCRAM-SHA-256:
        the password never leaves this process, and the CPU must prove it holds the user's
        verifier. The reply holds the token to put in each :class:`Command`; this client
        keeps the session key and signs those commands in :meth:`send`. No answer is a
        refusal too."""
        problem = name_problem(user)
        if problem:
            return LoginReply(ok=False, reason=problem)

        def ask(scram: str, login_id: str) -> LoginReply:
            op: Literal["login", "proof"] = "proof" if login_id else "login"
            return self._ask_login(
                LoginRequest(op=op, user=user, scram=scram, login_id=login_id, origin=origin)
            )

        answer, signer = log_in(user, password, ask)
        if isinstance(answer, str):
            return LoginReply(ok=False, reason=answer)
        if signer is not None:
            with self._lock:
                while len(self._signers) >= MAX_SESSIONS:  # the oldest go first
                    del self._signers[next(iter(self._signers))]
                self._signers[signer.token] = signer
        return answer

    def logout(self, token: str, *, user: str = "", origin: str = "") -> LoginReply:
        """Revoke ``token`` at the CPU (signed with its session key) and forget its key."""
        with self._lock:
            signer = self._signers.pop(token, None)
        mac = signer.logout_mac() if signer is not None else ""
        request = LoginRequest(op="logout", user=user, token=token, mac=mac, origin=origin)
        return self._ask_login(request)

    def _signer(self, token: str) -> Signer | None:
        with self._lock:
            return self._signers.get(token) if token else None

    def _ask_login(self, request: LoginRequest) -> LoginReply:
        got = self._ask(self._keys.login, LoginReply, encode(request), None)
        if got is None:
            got = f"no answer from CPU {self._keys.cpu!r}"
        return LoginReply(ok=False, reason=got) if isinstance(got, str) else got

    def audit(self) -> AuditList | None:
        """The CPU's last 50 audit rows, or None if no CPU answers."""
        return self._read(self._keys.audit_list, AuditList)

    def acked(self) -> AuditList | None:
        """Of each message, the CPU's newest applied acknowledgement that gave it a comment
        or emptied it, however old (``audit/acked``), or None if no CPU answers."""
        return self._read(self._keys.audit_acked, AuditList)

    def history(self) -> AlarmHistory | None:
        """The CPU's last 200 message events, or None if no CPU answers."""
        return self._read(self._keys.alarm_history, AlarmHistory)

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
        return self._read(self._keys.cmd, CommandReply, payload, timeout)

    def follow(self, fb: str, on_update: Callable[[StepStateUpdate], None]) -> StateFollower:
        """Subscribe to deltas, then fetch the state: ``on_update`` sees each newer state once,
        in ``seq`` order (it runs on a zenoh thread; keep it short). The deltas come from
        the CPU's ``deltas``, through one subscription for all the FBs this client follows
        (:class:`DeltaFeed`)."""
        follower = StateFollower(on_update)
        follower.resync = lambda: self.state(fb)  # type: ignore[method-assign]
        with self._lock:
            feed = self._feed
            if feed is None:
                feed = self._feed = DeltaFeed()
                sub = self._session.declare_subscriber(self._keys.deltas, feed.on_sample)
                self._subscribers.append(sub)
            feed.add(fb, follower)
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
        with self._lock:
            self._feed = None

    def __enter__(self) -> BusClient:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def find_cpus(
    session: zenoh.Session, *, timeout: float = 2.0, unreadable: list[str] | None = None
) -> list[CpuStatus]:
    """The status of every CPU answering on the bus (a wildcard query), sorted by name; an
    answer that is no status is left out, and said in ``unreadable`` (key and why)."""
    found: dict[str, CpuStatus] = {}
    replies = session.get(
        f"{ROOT}/*/status",
        timeout=timeout,
        target=zenoh.QueryTarget.ALL,
        consolidation=zenoh.ConsolidationMode.NONE,
    )
    for reply in replies:
        if reply.ok is None:
            said = refusal(reply)
            if unreadable is not None and said is not None:
                unreadable.append(f"an error reply: {one_line(said)}")
            continue
        try:
            status = decode(reply.ok.payload.to_bytes(), CpuStatus)
        except ProtocolError as exc:
            if unreadable is not None:
                unreadable.append(f"{reply.ok.key_expr}: unreadable answer: {exc}")
            continue
        found[status.cpu] = status
    return [found[name] for name in sorted(found)]


def wait_for_cpus(
    session: zenoh.Session, wait_s: float, enough: Callable[[list[CpuStatus]], bool] = bool
) -> tuple[list[CpuStatus], list[str]]:
    """:func:`find_cpus` again every 0.2 s until what it finds is ``enough`` (default: any
    CPU) or ``wait_s`` have passed: the CPUs of the last look, and what it could not read."""
    deadline = time.monotonic() + wait_s
    while True:
        unreadable: list[str] = []
        cpus = find_cpus(session, unreadable=unreadable)
        if enough(cpus) or time.monotonic() >= deadline:
            return cpus, unreadable
        time.sleep(0.2)


def unread_note(unreadable: Sequence[str]) -> str:
    """What :func:`find_cpus` could not read, as the end of a "no CPU answers" line ("":
    nothing)."""
    if not unreadable:
        return ""
    more = f" (and {len(unreadable) - 1} more)" if len(unreadable) > 1 else ""
    return f"; an answer could not be read: {unreadable[0]}{more}"


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
        """A delta of the FB's own key (``fb/<fb>/delta``)."""
        try:
            update = decode(sample.payload.to_bytes(), StepStateUpdate)
        except ProtocolError:
            return
        self.on_delta(update)

    def on_delta(self, update: StepStateUpdate) -> None:
        """A delta of the FB (a gap in ``seq`` is counted; the delta is whole)."""
        latest = self.latest
        if latest is not None and update.seq > latest.seq + 1:
            self.gaps += 1
        self._offer(update)

    def forget(self) -> None:
        """The CPU started anew (its counts start again): take whatever comes next."""
        with self._lock:
            self.latest = None

    def refetch(self) -> None:
        """Get the state again (a message of ``deltas`` was lost): it is taken if newer."""
        snapshot = self.resync()
        if snapshot is None:
            return
        latest = self.latest
        if snapshot.seq > (latest.seq if latest is not None else 0):
            self.gaps += 1  # a delta was missed
        self._offer(snapshot)

    def _offer(self, update: StepStateUpdate) -> None:
        with self._lock:
            latest = self.latest
            if latest is not None and (update.seq, update.cycle) <= (latest.seq, latest.cycle):
                return  # stale, or the same scan seen twice (snapshot and delta)
            self.latest = update
            # Called under the lock so updates reach the view in order.
            self._on_update(update)


class _Envelope(msgspec.Struct, frozen=True):
    """A ``deltas`` message with each FB's delta left undecoded (``ScanDeltas``)."""

    seq: int = 0
    fbs: dict[str, msgspec.Raw] = {}


class DeltaFeed:
    """The followers of one CPU's ``deltas`` (``BusClient.follow``): ``on_sample`` decodes
    a message's envelope, then each delta of an FB followed, and offers it to that FB's
    followers; on a gap in the messages' ``seq`` every follower refetches its FB's state
    (:meth:`StateFollower.refetch`) on a thread of the feed's own, never a zenoh thread.
    A ``seq`` lower than the last is a CPU that started anew, counting from 1 again: every
    follower forgets what it had first (:meth:`StateFollower.forget`), or it would take
    the new CPU's states for stale ones until they outnumbered the old. ``lost`` counts
    the gaps."""

    def __init__(self) -> None:
        self._followers: dict[str, tuple[StateFollower, ...]] = {}
        self._lock = threading.Lock()
        self._last: int | None = None  # the seq of the last message
        self._refetching = False
        self._again = False
        self.lost = 0

    def add(self, fb: str, follower: StateFollower) -> None:
        with self._lock:
            self._followers[fb] = (*self._followers.get(fb, ()), follower)

    def on_sample(self, sample: zenoh.Sample) -> None:
        try:
            envelope = decode(sample.payload.to_bytes(), _Envelope)
        except ProtocolError:
            return
        followers = self._followers
        last, self._last = self._last, envelope.seq
        if last is not None and envelope.seq < last:  # a CPU started anew: its counts too
            for group in list(followers.values()):
                for follower in group:
                    follower.forget()
        for fb, raw in envelope.fbs.items():
            wanted = followers.get(fb)
            if wanted:
                try:
                    update = decode(raw, StepStateUpdate)
                except ProtocolError:
                    continue
                for follower in wanted:
                    follower.on_delta(update)
        if last is not None and not last <= envelope.seq <= last + 1:  # lost, or a new CPU
            self.lost += 1
            self._refetch()

    def _refetch(self) -> None:
        with self._lock:
            if self._refetching:
                self._again = True
                return
            self._refetching = True
        threading.Thread(target=self._refetch_all, name="s7graph-refetch", daemon=True).start()

    def _refetch_all(self) -> None:
        while True:
            with self._lock:
                followers = [f for group in self._followers.values() for f in group]
                self._again = False
            for follower in followers:
                with contextlib.suppress(ProtocolError, zenoh.ZError):
                    follower.refetch()
            with self._lock:
                if not self._again:
                    self._refetching = False
                    return
