"""Refusals of unauthenticated senders: counted, one audit row a minute per source and reason.

Every command a CPU refuses is audited, but a refusal of a sender the CPU did not
authenticate costs the sender nothing, and one row each let a flood of them write 0.5 GB an
hour. :class:`RefusalTally` keeps them as *windows*: one per wall-clock minute and *kind* —
the source (``origin``), the reason, and the name given when it is one of the users file's
(any other name is a claim, and an attacker has as many as he likes). The first refusal of
a window writes its row at once (count 1: an operator sees an attack start); the later ones
only count. The count goes to the file with the next scan's state (a job the state writer
runs with the scan's rows, reading the count as it is then), or, without a writer, every
``flush``; the bus's ``audit`` gets the row as written and then its count at most every
``flush`` (a timer of ``FLUSH_S``), never a message a refusal.

A window's row says what its refusals had in common: user, origin, op, FB, arguments,
reason and the name claimed of the first, each ``*`` once a later one differed. Its text
(arguments, reason) is cut to ``TEXT`` characters: an unauthenticated sender's 4 KiB
arguments are no evidence worth 4 KiB a row. More than ``MAX_KINDS`` kinds in one minute
(a sender making up sources or reasons) are counted together in one more window,
``OVERFLOW``; so a minute adds at most ``MAX_KINDS + 1`` rows, whatever is sent.

Which refusals come here is the gate's decision (``web/bus/gate.py``, docs/security.md,
"The audit cannot fill the disk"). The tally runs under the audit store's lock.
"""

from __future__ import annotations

import contextlib
import dataclasses
import functools
import sqlite3
import threading
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from typing import Final, TypeAlias

from s7graph.engine.rollup import Job
from s7graph.web.access.audit import AuditRecord, AuditStore, Facts, row_size, write_count

__all__ = ["FLUSH_S", "MAX_KINDS", "TEXT", "WINDOW_NS", "Kind", "RefusalTally"]

WINDOW_NS: Final = 60 * 1_000_000_000
"""A window: one wall-clock minute."""
MAX_KINDS: Final = 256
"""Windows one minute opens before the rest go to the overflow window."""
TEXT: Final = 512
"""Characters kept of an aggregated row's arguments and reason."""
FLUSH_S: Final = 1.0
"""At most this long before a count that changed is published (and, without a writer,
written)."""
Kind: TypeAlias = tuple[str, str, str]
"""(origin, reason, the users file's name given or "")."""
OVERFLOW: Final[Kind] = ("*", "*", "*")
OVERFLOW_REASON: Final = (
    f"more than {MAX_KINDS} kinds (source, reason) of refusal this minute: the rest counted here"
)


@dataclass(slots=True, eq=False)
class _Window:
    minute: int
    row: AuditRecord  # as its first refusal wrote it
    args: Mapping[str, object]  # the first refusal's, to compare with
    labels: dict[str, str] = field(default_factory=dict)  # what differs from ``row``: "*"
    count: int = 1
    size: int = 0  # ``row_size`` as last written
    written: int = 1  # the count in the file, or in the job queued to write it
    shown: int = 1  # the count last published
    queued: bool = False  # a job will write the count with the next scan's state
    closed: bool = False

    def add(self, facts: Facts) -> None:
        self.count += 1
        row = self.row
        for name, now in (
            ("user", facts.user[:80]),
            ("origin", facts.origin[:160]),
            ("op", facts.op[:32]),
            ("fb", facts.fb[:64]),
            ("claimed", facts.claimed[:80]),
        ):
            if now != getattr(row, name):
                self.labels[name] = "*"
        if facts.args != self.args:
            self.labels["args"] = "*"
        if facts.reason[:TEXT] != row.reason and row.reason != OVERFLOW_REASON:
            self.labels["reason"] = "*"

    def record(self) -> AuditRecord:
        """The row as it stands: its count and what its refusals had in common."""
        row, labels = self.row, self.labels
        return dataclasses.replace(
            row,
            count=self.count,
            user=labels.get("user", row.user),
            origin=labels.get("origin", row.origin),
            op=labels.get("op", row.op),
            fb=labels.get("fb", row.fb),
            args=labels.get("args", row.args),
            reason=labels.get("reason", row.reason),
            claimed=labels.get("claimed", row.claimed),
        )


class RefusalTally:
    """The open windows of one gate. ``audit``: the store the rows go to (None: the gate's
    memory); ``flush_s``: how long a changed count may wait to be published (None: until
    ``flush`` is called, as tests do with their own clock)."""

    def __init__(
        self,
        audit: AuditStore | None,
        *,
        max_kinds: int = MAX_KINDS,
        flush_s: float | None = FLUSH_S,
    ) -> None:
        self.audit = audit
        self.lock = audit.lock if audit is not None else threading.RLock()
        self.max_kinds = max_kinds
        self.flush_s = flush_s
        self.on_flush: Callable[[], None] | None = None
        """What the timer calls (the gate's ``flush``: it publishes the counts)."""
        self._open: dict[Kind, _Window] = {}  # this minute's
        self._minute = -1
        self._closing: list[_Window] = []  # of earlier minutes, count not yet written
        self._timer: threading.Timer | None = None
        self.counted = 0
        """Refusals counted into a window's row instead of a row of their own."""

    def refuse(
        self, t_ns: int, kind: Kind, facts: Facts, write: Callable[[Facts], AuditRecord]
    ) -> tuple[AuditRecord | None, list[AuditRecord]]:
        """Count a refusal of ``kind`` at wall time ``t_ns`` (call with ``lock`` held): the
        row ``write(facts)`` wrote if it opened a window (None: it was counted in one), and
        the rows of windows a new minute closed whose count changed since published."""
        minute = t_ns // WINDOW_NS
        changed = self._sweep(minute) if minute != self._minute else []
        if kind not in self._open and len(self._open) >= self.max_kinds:
            kind = OVERFLOW
            facts = dataclasses.replace(facts, reason=OVERFLOW_REASON)
        window = self._open.get(kind)
        if window is None:
            row = write(facts)
            self._open[kind] = _Window(minute, row, facts.args, size=row_size(row))
            if self.audit is not None:
                self.audit.keep(row.id)
            return row, changed
        window.add(facts)
        self.counted += 1
        if not window.queued and self.audit is not None and self.audit.deferred:
            window.queued = True
            self.audit.queue(self._job(window))
        self._start_timer()
        return None, changed

    def flush(self, t_ns: int) -> list[AuditRecord]:
        """Close the windows of minutes before ``t_ns``'s, write the counts the state
        writer will not (no writer) and return the rows whose count changed since they were
        last published (call with ``lock`` held)."""
        minute = t_ns // WINDOW_NS
        changed = self._sweep(minute) if minute > self._minute else []
        return changed + self._settle(self._open.values())

    def live(self, rows: Iterable[AuditRecord]) -> list[AuditRecord]:
        """``rows`` with the counts of the windows still counting (call with ``lock``)."""
        windows = {w.row.id: w for w in [*self._open.values(), *self._closing]}
        return [windows[r.id].record() if r.id in windows else r for r in rows]

    def cancel(self) -> None:
        """Stop the timer (the gate is done)."""
        with self.lock:
            if self._timer is not None:
                self._timer.cancel()
                self._timer = None

    # ------------------------------------------------------------ inside

    def _sweep(self, minute: int) -> list[AuditRecord]:
        """A new minute: this one's windows close."""
        for window in self._open.values():
            window.closed = True
            self._closing.append(window)
        self._open = {}
        self._minute = minute
        closing, self._closing = self._closing, []
        changed = self._settle(closing)
        self._closing = [w for w in closing if not self._done(w)]
        return changed

    def _settle(self, windows: Iterable[_Window]) -> list[AuditRecord]:
        """Write the counts no job will (no writer), and the rows to publish."""
        changed = []
        for window in windows:
            if window.count != window.written and not window.queued:
                rec = self._written(window)
                if self.audit is not None:
                    self.audit.queue(functools.partial(_write_count, rec))
            if window.count != window.shown:
                window.shown = window.count
                changed.append(window.record())
        return changed

    def _written(self, window: _Window) -> AuditRecord:
        """The window's row as it is about to be written (its count and size taken)."""
        rec = window.record()
        size = row_size(rec)
        if size != window.size and self.audit is not None:
            self.audit.resized(size - window.size)
        window.written, window.size = rec.count, size
        return rec

    def _done(self, window: _Window) -> bool:
        """A closed window whose count is in the file: its row may be rolled up now."""
        done = window.closed and window.written == window.count and not window.queued
        if done and self.audit is not None:
            self.audit.keep(window.row.id, False)
        return done

    def _job(self, window: _Window) -> Job:
        """The state writer's job: the window's count as it is when the job runs."""

        def write(db: sqlite3.Connection) -> None:
            with self.lock:
                rec = self._written(window)
                window.queued = False
            write_count(db, rec)
            with self.lock:
                if window in self._closing and self._done(window):
                    self._closing.remove(window)

        return write

    def _start_timer(self) -> None:
        if self.flush_s is None or self._timer is not None or self.on_flush is None:
            return
        self._timer = threading.Timer(self.flush_s, self._fire)
        self._timer.daemon = True
        self._timer.start()

    def _fire(self) -> None:
        with self.lock:
            self._timer = None
        if self.on_flush is not None:
            with contextlib.suppress(Exception):  # a store closed meanwhile: nothing to do
                self.on_flush()


def _write_count(rec: AuditRecord, db: sqlite3.Connection) -> None:
    write_count(db, rec)
