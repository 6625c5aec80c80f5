"""The CPU's diagnostic buffer on the bus (docs/bus.md, "The diagnostic buffer: diag").

:class:`DiagFeed` serves the ``diag`` queryable — the newest entries first, 100 unless the
query asks ``?n=N`` (1..1000) — and publishes on ``diag/new`` the entries written since the
last publication. An entry's ``number`` is its place among all the entries the CPU has
written to its state file, so it stays across restarts (``DiagnosticBuffer.continue_from``);
with a state file an entry is served and published only once it is on disk, so a crash never
gives its number to another entry. The scan thread only looks, at each scan boundary,
whether the buffer's count moved (:meth:`DiagFeed.at_boundary`); when it did it keeps a copy
of the buffer for the queryable and queues the new entries for the publisher's outbox, so a
query never reads the CPU's buffer while a scan writes it. Each entry goes out as STEP 7
lists it (``engine.diag_events``): event ID, text, requested OB and priority class, the time
on the CPU clock and on the wall clock.
"""

from __future__ import annotations

import functools
import threading
from collections.abc import Callable, Sequence

import zenoh

from s7graph.engine.cpu import Cpu
from s7graph.engine.diag_events import event_text, priority_class, requested_ob, stop_cause
from s7graph.engine.interrupts import priority
from s7graph.engine.record import DiagEntry
from s7graph.web.bus.protocol import MAX_DIAG_ENTRIES, DiagBuffer, DiagEvent, encode
from s7graph.web.bus.publisher import BusPublisher, Durability

__all__ = ["DEFAULT_ENTRIES", "DiagFeed", "diag_event", "entries_asked"]

DEFAULT_ENTRIES = 100
"""How many entries ``diag`` answers when the query does not say (``?n=``)."""


def diag_event(
    entry: DiagEntry, number: int, priority_of: Callable[[int], int] = priority
) -> DiagEvent:
    """``entry`` (the ``number``-th the CPU process held) as a bus message; ``priority_of``
    the CPU's priority classes (``Cpu.priority_of``)."""
    ob = requested_ob(entry)
    return DiagEvent(
        number=number,
        event_id=entry.event_id & 0xFFFF,
        text=event_text(entry.event_id)[:4096],
        info=entry.message[:4096],
        block=entry.block[:256],
        address=entry.address[:256],
        ob=ob if ob <= 255 else 0,
        priority=min(priority_class(entry, priority_of), 255),
        t_ms=max(entry.t_ns // 1_000_000, 0),
        wall_ms=max(entry.wall_ns // 1_000_000, 0),
    )


def entries_asked(parameters: str) -> int | str:
    """The ``n`` of a ``diag`` query's parameters (``n=20``), ``DEFAULT_ENTRIES`` without
    one, or why it is no number of entries (one line)."""
    try:
        given = zenoh.Parameters(parameters).get("n")
    except Exception:
        return f"unreadable parameters {parameters[:64]!r}"
    if given is None:
        return DEFAULT_ENTRIES
    if not given.isdigit() or not 1 <= int(given) <= MAX_DIAG_ENTRIES:
        return f"?n={given[:16]!r}: give a number of entries, 1 to {MAX_DIAG_ENTRIES}"
    return int(given)


class DiagFeed:
    """The diagnostic buffer of ``cpu`` on ``publisher``'s bus (``diag``, ``diag/new``);
    call :meth:`at_boundary` in the scan thread after each scan."""

    def __init__(self, cpu: Cpu, publisher: BusPublisher) -> None:
        self.cpu = cpu
        self._publisher = publisher
        self._lock = threading.Lock()
        buffer = cpu.diagnostics
        self._seen = buffer.total  # the newest entry served and published
        self._staged = buffer.total  # the newest entry handed on at a scan boundary
        self._snapshot: tuple[DiagEntry, ...] = tuple(buffer)
        self._encoded: tuple[tuple[int, int], bytes] = ((-1, 0), b"")
        self._pub = publisher.declare_publisher("diag/new")
        publisher.declare_queryable("diag", self._on_query)

    def at_boundary(self, durable: Durability | None = None) -> None:
        """Publish the entries written since the last call (scan thread); with ``durable``
        (the runner of a CPU with a state file) once they are on disk, so that a number
        read on the bus is never given to another entry after a crash."""
        buffer = self.cpu.diagnostics
        total = buffer.total
        if total == self._staged:
            return
        new = buffer.since(self._staged)
        self._staged = total
        snapshot = tuple(buffer)
        first = total - len(new) + 1
        events = [diag_event(e, first + k, self.cpu.priority_of) for k, e in enumerate(new)]
        events.reverse()  # newest first
        message = DiagBuffer(total=total, capacity=buffer.capacity, entries=events)
        show = functools.partial(self._show, total, snapshot, message)
        if durable is None:
            show(None)
        else:
            durable.when_durable(durable.durable_mark(), show)

    def _show(
        self, total: int, snapshot: tuple[DiagEntry, ...], message: DiagBuffer, _: str | None
    ) -> None:
        """The entries up to number ``total`` are on disk (or never will be: shown all the
        same): serve and publish them (the scan or the writer thread)."""
        with self._lock:
            if total <= self._seen:
                return
            self._seen, self._snapshot = total, snapshot
        self._publisher.post(self._pub, message)

    def encoded(self, n: int = DEFAULT_ENTRIES) -> bytes:
        """``current(n)`` as JSON, made once per state of the buffer and ``n`` (a view
        that asks again and again costs the CPU's process one encoding)."""
        with self._lock:
            key = (self._seen, n)
            if self._encoded[0] == key:
                return self._encoded[1]
        data = encode(self.current(n))
        with self._lock:
            self._encoded = (key, data)
        return data

    def current(self, n: int = DEFAULT_ENTRIES) -> DiagBuffer:
        """The newest ``n`` entries, newest first (any thread)."""
        with self._lock:
            total, snapshot = self._seen, self._snapshot
        newest = snapshot[-n:] if n < len(snapshot) else snapshot
        first = total - len(newest) + 1
        events = [diag_event(e, first + k, self.cpu.priority_of) for k, e in enumerate(newest)]
        events.reverse()
        return DiagBuffer(total=total, capacity=self.cpu.diagnostics.capacity, entries=events)

    def stop_events(self) -> tuple[DiagEvent | None, DiagEvent | None]:
        """(the STOP entry, the error entry that caused it) of the CPU's last STOP, as bus
        messages; None where there is none (scan thread: it reads the buffer)."""
        stop = self.cpu.stop_entry
        if stop is None:
            return None, None
        entries = list(self.cpu.diagnostics)
        cause = stop_cause(entries, stop)
        return self._event(entries, stop), self._event(entries, cause)

    def _event(self, entries: Sequence[DiagEntry], entry: DiagEntry | None) -> DiagEvent | None:
        if entry is None:
            return None
        total = self.cpu.diagnostics.total
        for k, e in enumerate(entries):
            if e is entry:
                return diag_event(e, total - len(entries) + 1 + k, self.cpu.priority_of)
        return diag_event(entry, 0, self.cpu.priority_of)  # no longer in the buffer

    def _on_query(self, query: zenoh.Query) -> None:
        # a zenoh thread: never raise, never block
        try:
            n = entries_asked(str(query.parameters))
            if isinstance(n, str):
                query.reply_err(n.encode())
                return
            data = self.encoded(n)
            key = self._publisher.key("diag")
            query.reply(key, data, encoding=zenoh.Encoding.APPLICATION_JSON)
        except Exception:
            return
