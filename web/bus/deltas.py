"""The CPU's FB states on the bus: per scan, one message on ``deltas`` carrying the
:class:`StepStateUpdate` of every FB that changed; each on ``fb/<fb>/delta`` as well while
something subscribes there; per FB the latest state for ``fb/<fb>/state``.

:class:`DeltaOut` is the part of :class:`~web.bus.publisher.BusPublisher` that does this.
In the scan thread it only compares (``StepStateUpdate.changed_from``, for the updates an
FB gives it: ``LiveGraph.changed`` gives none for a scan that changed nothing), numbers —
``seq`` per FB, counting its changes, and ``seq`` per message on ``deltas`` — and queues
one job on the publisher's :class:`~web.bus.outbox.Outbox` — or, for a scan whose deltas
come one by one (:meth:`DeltaOut.begin`, a :class:`ScanOut`), one job every ``part``
deltas, so that the first of a large scan leave while the scan thread still builds the
others: each such message carries the scan's ``seq``. The outbox's thread sets each
delta's ``seq``, encodes the scan's message in one go and puts it; then, for each FB whose
own key has a subscriber (a zenoh matching listener tells), encodes and puts its delta
there. When the outbox drops the job, the scan's ``seq`` stays used: a follower of
``deltas`` sees the gap and gets ``state`` again.
"""

from __future__ import annotations

import contextlib
import operator
import threading
from collections.abc import Callable, Iterable, Sequence
from typing import Any

import msgspec
import zenoh

from s7graph.web.bus.keys import keys
from s7graph.web.bus.outbox import Outbox
from s7graph.web.bus.protocol import (
    MAX_MESSAGE_BYTES,
    ScanDeltas,
    StepStateUpdate,
    encode,
)

__all__ = ["PART", "DeltaOut", "ScanJob", "ScanOut", "encode_parts"]

PART = 32
"""Deltas a :class:`ScanOut` gathers before they leave in one message (the scan's others
are still being built): small enough that the first leave soon, large enough that a
message carries more than its envelope (``bench/bus.py --part``)."""

_first = operator.itemgetter(0)
Changed = list[tuple[str, StepStateUpdate, int]]
"""The deltas of one scan: (FB, its update, its ``seq``)."""


class DeltaOut:
    """The deltas and states of a CPU's FBs ``fbs`` (see the module docstring); the
    publishers it declares on ``session`` go with :meth:`undeclare`."""

    def __init__(
        self, session: zenoh.Session, cpu_keys: keys, fbs: Iterable[str], outbox: Outbox
    ) -> None:
        self.outbox = outbox
        self._lock = threading.Lock()
        self._state: dict[str, StepStateUpdate] = {}  # the latest update given (its seq: _seq)
        self._seq: dict[str, int] = dict.fromkeys(fbs, 0)
        self._names = frozenset(self._seq)
        self.scans = 0
        """The ``seq`` of the last message queued for ``deltas``."""
        self.put = 0
        """Messages put on ``deltas`` (by the outbox's thread)."""
        self.put_own = 0
        """Deltas put on their FB's own key (by the outbox's thread)."""
        self._wanted: dict[str, bool] = dict.fromkeys(self._seq, False)
        self._fb_pubs: dict[str, zenoh.Publisher] = {}
        self._declared: list[Any] = []
        try:
            for name in self._seq:
                pub = session.declare_publisher(
                    cpu_keys.fb(name, "delta"),
                    encoding=zenoh.Encoding.APPLICATION_JSON,
                    congestion_control=zenoh.CongestionControl.BLOCK,
                )
                self._declared.append(pub)
                self._fb_pubs[name] = pub
                self._declared.append(pub.declare_matching_listener(self._matching(name)))
                now: Any = pub.matching_status  # a MatchingStatus (its stub says bool)
                self._wanted[name] = bool(getattr(now, "matching", now))
            self._pub = session.declare_publisher(
                cpu_keys.deltas,
                encoding=zenoh.Encoding.APPLICATION_JSON,
                congestion_control=zenoh.CongestionControl.BLOCK,
            )
            self._declared.append(self._pub)
        except BaseException:
            self.undeclare()
            raise

    def _matching(self, fb: str) -> Callable[[zenoh.MatchingStatus], None]:
        def on_status(status: zenoh.MatchingStatus) -> None:  # on a zenoh thread
            self._wanted[fb] = status.matching

        return on_status

    def publish(
        self, cycle: int, t_ms: int, updates: Sequence[tuple[str, StepStateUpdate]]
    ) -> list[str]:
        """Record one scan: each ``(fb, update)`` becomes the FB's state; those that changed
        go out together on ``deltas`` (cycle ``cycle``, time ``t_ms``). Returns the FBs that
        changed, in order. An unknown FB raises KeyError, nothing of the scan recorded."""
        if not self._names.issuperset(map(_first, updates)):
            unknown = sorted({fb for fb, _ in updates} - self._names)
            raise KeyError(f"unknown FB {unknown[0]!r}; known: {', '.join(self._seq)}")
        out = self.begin(cycle, t_ms, part=0)
        for fb, update in updates:
            out.add(fb, update)
        return [fb for fb, _ in out.end()]

    def begin(self, cycle: int, t_ms: int, *, part: int = PART) -> ScanOut:
        """A scan (cycle ``cycle`` at time ``t_ms``) whose updates come one at a time
        (:meth:`ScanOut.add`); every ``part`` changed ones leave together (0: all at
        :meth:`ScanOut.end`)."""
        return ScanOut(self, cycle, t_ms, part)

    def _record(self, fb: str, update: StepStateUpdate) -> int:
        """``update`` becomes the FB's state; its new ``seq`` if it changed, else 0."""
        with self._lock:
            state, seqs = self._state, self._seq
            if fb not in seqs:
                raise KeyError(f"unknown FB {fb!r}; known: {', '.join(seqs)}")
            before = state.get(fb)
            state[fb] = update
            if not update.changed_from(before):
                return 0
            seq = seqs[fb] = seqs[fb] + 1
            return seq

    def _scan_seq(self) -> int:
        """The ``seq`` of a new message on ``deltas``."""
        with self._lock:
            self.scans += 1
            return self.scans

    def own_key_read(self, fb: str) -> bool:
        """Whether something subscribes to ``fb/<fb>/delta`` (its deltas are put there)."""
        return self._wanted[fb]

    def read(self) -> bool:
        """Whether something subscribes to ``deltas`` now (zenoh's matching status)."""
        now: Any = self._pub.matching_status
        return bool(getattr(now, "matching", now))

    def state(self, fb: str) -> StepStateUpdate | None:
        """The FB's latest state with its ``seq`` (None: no scan yet)."""
        with self._lock:
            state, seq = self._state.get(fb), self._seq[fb]
        return None if state is None else msgspec.structs.replace(state, seq=seq)

    def undeclare(self) -> None:
        """Undeclare the publishers and matching listeners."""
        for d in reversed(self._declared):
            with contextlib.suppress(zenoh.ZError):
                d.undeclare()
        self._declared.clear()


class ScanOut:
    """One scan's updates as the scan thread builds them (:meth:`DeltaOut.begin`): each
    :meth:`add` compares and numbers; every ``part`` changed deltas leave in one message
    with the scan's ``seq``, the rest at :meth:`end`."""

    __slots__ = ("_pending", "changed", "cycle", "out", "part", "scan", "t_ms")

    def __init__(self, out: DeltaOut, cycle: int, t_ms: int, part: int) -> None:
        self.out, self.cycle, self.t_ms, self.part = out, cycle, t_ms, part
        self.scan = 0  # the scan's seq on ``deltas`` (0: none yet, nothing changed)
        self.changed: list[tuple[str, StepStateUpdate]] = []
        """The FBs that changed so far, with their updates, in order."""
        self._pending: Changed = []

    def add(self, fb: str, update: StepStateUpdate) -> bool:
        """Record ``update`` as FB ``fb``'s state; whether it changed (its delta goes out).
        An unknown FB raises KeyError."""
        seq = self.out._record(fb, update)
        if not seq:
            return False
        self.changed.append((fb, update))
        pending = self._pending
        pending.append((fb, update, seq))
        if len(pending) == self.part:
            self._send()
        return True

    def end(self) -> list[tuple[str, StepStateUpdate]]:
        """Send what is left; the FBs that changed, with their updates, in order."""
        if self._pending:
            self._send()
        return self.changed

    def _send(self) -> None:
        out, pending = self.out, self._pending
        if not self.scan:
            self.scan = out._scan_seq()
        self._pending = []
        out.outbox.run(ScanJob(out, self.scan, self.cycle, self.t_ms, pending), len(pending))


class ScanJob:
    """One scan's deltas (``seq`` ``scan``) of ``out``, sent by the outbox's thread
    (``Outbox.run``): the message on ``deltas``, then each delta on its FB's own key while
    something subscribes there."""

    __slots__ = ("changed", "cycle", "out", "scan", "t_ms")

    def __init__(self, out: DeltaOut, scan: int, cycle: int, t_ms: int, changed: Changed) -> None:
        self.out, self.scan, self.cycle, self.t_ms, self.changed = out, scan, cycle, t_ms, changed

    def __call__(self) -> int:
        out = self.out
        replace = msgspec.structs.replace
        fbs = {fb: replace(update, seq=seq) for fb, update, seq in self.changed}
        message = ScanDeltas(seq=self.scan, cycle=self.cycle, t_ms=self.t_ms, fbs=fbs)
        sent = 0
        for data in encode_parts(message):
            out._pub.put(data)
            sent += 1
        out.put += sent
        wanted = out._wanted
        for fb, update in fbs.items():
            if wanted[fb]:
                out._fb_pubs[fb].put(encode(update))
                out.put_own += 1
                sent += 1
        return sent


def encode_parts(message: ScanDeltas, limit: int = MAX_MESSAGE_BYTES) -> list[bytes]:
    """``message`` encoded; in several messages with its ``seq``, its FBs shared out, if it
    is over ``limit`` bytes (an FB's delta alone over it goes out alone, as it is)."""
    data = encode(message)
    if len(data) <= limit or len(message.fbs) < 2:
        return [data]
    items = list(message.fbs.items())
    half = len(items) // 2
    return [
        *encode_parts(msgspec.structs.replace(message, fbs=dict(items[:half])), limit),
        *encode_parts(msgspec.structs.replace(message, fbs=dict(items[half:])), limit),
    ]
