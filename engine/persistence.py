"""State on disk: one SQLite file per CPU (docs/state-file.md; docs/runtime.md, "Restarts: warm,
hot, cold").

Saved: retentive M/T/C and retain DBs (``Memory.snapshot()``), every instance DB
(``InstanceDB.snapshot()``, OBJECT values through ``to_state()``), the diagnostic buffer,
the restart type, what would block a hot restart, the force jobs (``engine/force.py``: they
outlive a restart and a power cycle, as on S7), and extra named parts registered with
``add_part`` (the CPU's message list: the engine does not know its type). Alarms (every
message event, with the acknowledging user) and the audit log (who did what, when) are
append-only tables, bounded: their oldest rows are summed into a summary table per day
(``engine/rollup.py``; docs/state-file.md, "Bounded logs").

**Written only when changed.** ``stage(cpu)`` (in the scan thread, between scans) compares
the state with what was last staged and returns a :class:`Batch` of the rows that changed —
None when nothing did; ``write(batch)`` commits one batch as one transaction (in any thread:
the runner's writer, ``engine/writer.py``). ``stage(cpu, defer=True)`` leaves the instance
DBs in the batch (``Batch.unencoded``) for ``encode_next(batch)``: the runner's writer
encodes them while the scan thread sleeps (what it has not by the next scan is carried
under that scan's staging, or encoded by the scan thread before it: ``engine/writer.py``)
— for 25 FBs of 8 sequencers about 1.3 ms a cycle off the path from a scan to its
deadline. An instance DB is one row, its snapshot as
compressed MessagePack (a 7-step chart: about 600 bytes, one page of the file's 1 KiB pages),
so a step switch rewrites a page or two. ``stage`` encodes each instance as it stands
(``InstanceDB.snapshot(live=True)``: a GRAPH FB's lists are read where they are, not copied)
and compares the bytes with those last staged; the writer only compresses. MessagePack
(msgspec) rather than JSON because encoding shares the interpreter lock with the scan: 25
instances of 8 sequencers took 4 ms with ``json.dumps`` and take 0.5 ms with msgspec, whose
floats keep NaN and infinity; zlib and SQLite let go of the lock while they work. A row of
format 4 is a MessagePack pair: the snapshot without the ``VOLATILE`` keys, then those keys
(object name → key → value). Rows of format 3 (one MessagePack map) and of format 2
(compressed JSON, also what a value MessagePack cannot hold is written as) are still read.

Keys an OBJECT value names in its ``VOLATILE`` (a GRAPH FB's call counter and the clock
time of its last call, which dates its running step times) are saved with every write of
the row, but on their own cause one only every ``time_mark_ms`` (500 ms): what a hot restart
can lose of a running step time is bounded, so a supervision time cannot be outrun by
restarts.

**Synced.** The file is in WAL mode with ``synchronous=FULL`` (``SYNCHRONOUS``): a commit
is on the disk when ``write`` returns, so what a command's reply waited for survives a
power cut, not only a killed process (docs/durability.md). A row is also written again
when its FB changed (an online change) though its data did not: it carries the new
fingerprint.

**Trusted only when recognised.** The file carries a format mark, and each instance DB the
label, name and fingerprint of its FB (``FB.state_format``, else its interface). ``load``
refuses — :class:`StateFileError` naming the problem — an empty, truncated, garbled or
foreign file, one without a table (copied without its write-ahead log), one locked by
another process, a dropped instances table, an instance of another FB, a DB the program no
longer has, a malformed row (a diagnostics row too) or memory image
(``engine/state_checks.py``), text that is not UTF-8 (a ``meta`` value by its key), a
file of another program than the store's (``engine/state_identity.py``: recorded when
the file is written, refused by ``load``; a renamed source the file's instance DBs
recognise is carried over, noted); a
changed fingerprint lets the FB's ``state_format.adapt`` carry the data over (a GRAPH
FB: by step number, ``sequencer/change/carry.py``) and reports what it could not keep. A
file missing beside its ``-wal`` (or its ``.renew``) is refused, never started fresh; a
full disk or a read-only folder is the disk's problem, not the file's: refused without
``--fresh`` as the way out. A file is recognised and loaded on a read-only connection
(immutable without a ``-wal`` beside it) and opened for writing only once it is taken
(``open_writing``; the first ``write`` at the latest): a refused file is left byte for byte
as it was, no ``-wal`` of it checkpointed, no ``-wal`` or ``-shm`` made beside it.

**Rebuilt when lost.** A file deleted, replaced or damaged under the running CPU (or its
``-wal`` deleted) is noticed at the next ``write`` (``StateWriteError.renew``) and built anew
from a whole staging (``renew``, ``engine/renew.py``) — the CPU is not taken down.
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import json
import os
import sqlite3
import zlib
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Final, Protocol, runtime_checkable

import msgspec

from s7graph.engine.blocks import FB, BlockKind, Decl, InstanceDB
from s7graph.engine.cpu import Cpu
from s7graph.engine.diag_events import last_error_stop
from s7graph.engine.diagnostics import EventId
from s7graph.engine.errors import S7Error
from s7graph.engine.file_lock import try_lock
from s7graph.engine.modes import CpuMode
from s7graph.engine.record import DiagEntry
from s7graph.engine.renew import gone, known, rebuild
from s7graph.engine.restart import stop_blocker
from s7graph.engine.rollup import ALARM_ROWS, ALARM_SUMMARY, Job, low_water, roll_alarms
from s7graph.engine.state_checks import check_hot_image, check_memory_image, diag_entry
from s7graph.engine.state_identity import (
    CHART,
    KIND_KEY,
    SOURCE_KEY,
    Evidence,
    Held,
    Program,
    beside,
    foreign,
    malformed,
    recorded,
    renamed,
    way_out,
)

__all__ = [
    "FORMAT",
    "READABLE",
    "SYNCHRONOUS",
    "AlarmEvent",
    "Batch",
    "LoadReport",
    "RenewHooks",
    "StateFileError",
    "StateStore",
    "StateWriteError",
    "diag_row",
    "fingerprint_of",
    "foreign_state",
    "not_a_state_file",
    "not_in_use",
    "sqlite_words",
    "state_beside",
    "unpack_instance",
    "unrecognised",
]

FORMAT = "s7graph-state 5"
"""The format mark in ``meta``: what this code writes (instance rows as MessagePack pairs,
the ``VOLATILE`` keys apart; a GRAPH FB's lists that hold only their fill kept as the fill,
``sequencer.state``)."""
READABLE = ("s7graph-state 2", "s7graph-state 3", "s7graph-state 4", FORMAT)
"""Format marks this code trusts; a file of an older one is marked ``FORMAT`` when opened
(its JSON rows stay readable, new rows are MessagePack)."""

_SCHEMA = (
    """
CREATE TABLE IF NOT EXISTS meta (key TEXT PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS instances (
    number INTEGER PRIMARY KEY, fb TEXT NOT NULL, name TEXT NOT NULL,
    fingerprint TEXT NOT NULL, shape TEXT NOT NULL, data BLOB NOT NULL);
CREATE TABLE IF NOT EXISTS diagnostics (
    seq INTEGER PRIMARY KEY, t_ns INTEGER, event_id INTEGER, block TEXT, message TEXT,
    address TEXT, ob INTEGER NOT NULL DEFAULT 0, priority INTEGER NOT NULL DEFAULT 0,
    wall_ns INTEGER NOT NULL DEFAULT 0);
CREATE TABLE IF NOT EXISTS alarms (
    id INTEGER PRIMARY KEY AUTOINCREMENT, t_ns INTEGER, key TEXT, state TEXT, text TEXT,
    user TEXT NOT NULL DEFAULT '', cpu_ns INTEGER, reason TEXT NOT NULL DEFAULT '');
CREATE TABLE IF NOT EXISTS parts (name TEXT PRIMARY KEY, state TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS audit (
    id INTEGER PRIMARY KEY AUTOINCREMENT, t_ns INTEGER, user TEXT, action TEXT, detail TEXT);
"""
    + ALARM_SUMMARY
)
SYNCHRONOUS = "FULL"
"""SQLite's ``synchronous`` for the state file: FULL syncs the write-ahead log at every
commit, so a commit that returned survives a power cut (NORMAL, in WAL mode, may lose the
last ones); ``bench/state_writes.py`` measures the cost."""
TIME_MARK_MS = 500.0
"""Default of ``StateStore.time_mark_ms``."""
_NOT_KEPT = {"program download", "no hot restart image saved"}
"""Hot-restart blockers that belong to one run, not to the state on disk."""
_BUSY = (5, 6)  # SQLITE_BUSY, SQLITE_LOCKED: another connection holds the lock
_DAMAGED = (11, 26)  # SQLITE_CORRUPT, SQLITE_NOTADB: the file was overwritten or cut
_DISK = {
    3: "no permission to open it or its write-ahead log",
    8: "its disk or folder is read-only, or the file is",
    10: "the disk failed to read or write it",
    13: "the disk is full",
    14: "it or its write-ahead log cannot be opened (a read-only folder?)",
}
"""SQLite's primary error codes that are the disk's or the folder's, not the file's: the file
is not read, and the way out is never ``--fresh``."""
_DISK_WAY_OUT = "{0}, then run again (the file itself was not found wrong)"
_DISK_FIX = {
    10: "free space on its disk or check the disk (the kernel's log: dmesg)",
    13: "free space on its disk",
}
_OURS = {"meta", "instances", "diagnostics", "alarms", "parts", "audit"}
_APPENDABLE = {"alarms", "audit"}
_APPENDED: set[tuple[str, tuple[str, ...]]] = set()
"""(table, columns) pairs ``append`` has checked."""
_NO_TABLES = (
    "an SQLite file without a single table: its content may be in a write-ahead log that is "
    "missing (copied without its -wal file?)"
)
_WAL_WAY_OUT = (
    "copy it again together with {0}-wal (or copy it once the run that writes it has "
    "stopped), or start anew with --fresh (keeps this file as {0}.old-N)"
)
_HELD: dict[tuple[int, int], list[int]] = {}
"""The state files this process holds, by device and inode: [descriptor, stores open]."""
_IN_USE_WAY_OUT = "stop the process that holds it (or wait until it ends), then run again"
_ALARM_COLUMNS = ("t_ns", "key", "state", "text", "user", "cpu_ns", "reason")
_ADDED_ALARM_COLUMNS = (
    ("user", "TEXT NOT NULL DEFAULT ''"),
    ("cpu_ns", "INTEGER"),
    ("reason", "TEXT NOT NULL DEFAULT ''"),
)
_DIAG_COLUMNS = (
    "seq",
    "t_ns",
    "event_id",
    "block",
    "message",
    "address",
    "ob",
    "priority",
    "wall_ns",
)
_ADDED_DIAG_COLUMNS = (
    ("ob", "INTEGER NOT NULL DEFAULT 0"),
    ("priority", "INTEGER NOT NULL DEFAULT 0"),
    ("wall_ns", "INTEGER NOT NULL DEFAULT 0"),
)
DiagRow = tuple[int, int, int, str, str, str, int, int, int]
"""A row of the diagnostics table, in ``_DIAG_COLUMNS`` order."""


def diag_row(seq: int, e: DiagEntry) -> DiagRow:
    """The diagnostics row ``seq`` of entry ``e`` (``_DIAG_COLUMNS`` order)."""
    return (seq, e.t_ns, e.event_id, e.block, e.message, e.address, e.ob, e.priority, e.wall_ns)


class StateFileError(S7Error):
    """A state file that cannot be trusted for this program: ``path`` and ``problem``;
    ``way_out`` what to do when it is not starting anew (``--fresh``)."""

    def __init__(self, path: Path, problem: str, *, way_out: str = "") -> None:
        self.path = path
        self.problem = problem
        self.way_out = way_out
        super().__init__(f"{path}: {problem}")


class StateWriteError(S7Error):
    """Writing the state file failed (disk full, I/O error, locked): the first error;
    ``busy`` when another connection holds the lock (worth a retry); ``renew`` when the file
    was deleted, replaced or damaged under the CPU (``StateStore.renew`` builds it anew)."""

    def __init__(
        self,
        path: Path,
        problem: str,
        *,
        busy: bool = False,
        renew: bool = False,
        committed: bool = False,
    ) -> None:
        self.path = path
        self.problem = problem
        self.busy = busy
        self.renew = renew
        self.committed = committed
        """The batch was committed to the file that is gone (the open connection still reads
        it: a renewal copies its rows)."""
        super().__init__(f"{path}: cannot write the state: {problem}")


@dataclass(frozen=True, slots=True)
class RenewHooks:
    """What another user of the file does when the store builds it anew
    (``StateStore.renew``): ``schema(db)`` adds its tables and columns to the new file,
    ``release()`` closes its own connections to the old one (before it goes aside),
    ``reopen()`` opens them on the new one."""

    schema: Callable[[sqlite3.Connection], None]
    release: Callable[[], None]
    reopen: Callable[[], None]


@runtime_checkable
class AlarmEvent(Protocol):
    """What ``log_alarms`` takes from ``ScanRecord.alarms`` (``sfb.alarms.MessageEvent``)."""

    kind: str
    msg_id: int | str
    t_ns: int
    user: str
    text: str


def _dumps(data: object) -> str:
    return json.dumps(data, sort_keys=True, separators=(",", ":"), default=str)


def fingerprint_of(fb: FB) -> str:
    """What an instance DB's data is recognised by: the FB's ``state_format.fingerprint``
    (a GRAPH FB: its compiled chart), else a hash of its interface."""
    fmt = fb.state_format
    if fmt is not None:
        return fmt.fingerprint
    text = _dumps([[v.name, v.type, str(v.decl)] for v in fb.interface])
    return "interface:" + hashlib.sha256(text.encode()).hexdigest()[:16]


@dataclass(slots=True)
class Batch:
    """The rows one or more scans changed: written as one transaction. ``upto`` is the mark
    (the runner's scan number) of the last scan whose state it holds."""

    upto: int = 0
    meta: dict[str, str] = field(default_factory=dict)
    instances: dict[int, tuple[str, str, str, str, bytes]] = field(default_factory=dict)
    """DB number → (FB label, FB name, fingerprint, shape JSON, encoded snapshot): ``write``
    compresses it, in the writer's thread."""
    parts: dict[str, str] = field(default_factory=dict)
    diagnostics: list[DiagRow] = field(default_factory=list)
    alarms: list[tuple[int, str, str, str, str, int | None, str]] = field(default_factory=list)
    audit: list[tuple[int, str, str, str]] = field(default_factory=list)
    appended: list[tuple[str, tuple[str, ...], tuple[Any, ...]]] = field(default_factory=list)
    """Rows of the append-only tables written by the edges (``StateStore.append``):
    (table, columns, values)."""
    jobs: list[Job] = field(default_factory=list)
    """Work of the edges on their own tables (``StateStore.queue``), run in order after the
    rows above, in the same transaction: an audit row's count, the roll-up of old rows."""
    unencoded: list[tuple[int, InstanceDB]] = field(default_factory=list)
    """Instance DBs staged with ``defer`` whose rows are still to be found
    (``StateStore.encode_next``), in order: before the next scan changes them."""
    time_mark: bool = False
    """Whether a time mark was due when the batch was staged (``unencoded`` rows are
    written for their ``VOLATILE`` keys alone)."""
    staged_ns: int = 0
    """The CPU's clock when the batch was staged."""
    full: bool = False
    """It holds a whole staging (``stage(full=True)``): enough to build the file anew."""

    def __bool__(self) -> bool:
        return bool(
            self.meta
            or self.instances
            or self.parts
            or self.diagnostics
            or self.alarms
            or self.audit
            or self.appended
            or self.jobs
            or self.unencoded
        )

    def merge(self, later: Batch) -> None:
        """Fold a later batch into this one (the later rows win, appended rows add up, the
        later's ``unencoded`` instance DBs are this one's now); this one may hold none
        still to encode."""
        if self.unencoded:
            raise ValueError("a batch with instance DBs still to encode cannot take another")
        self.unencoded = later.unencoded
        self.time_mark, self.staged_ns = later.time_mark, later.staged_ns
        self.full = self.full or later.full
        self.upto = max(self.upto, later.upto)
        self.meta.update(later.meta)
        self.instances.update(later.instances)
        self.parts.update(later.parts)
        self.diagnostics.extend(later.diagnostics)
        self.alarms.extend(later.alarms)
        self.audit.extend(later.audit)
        self.appended.extend(later.appended)
        self.jobs.extend(later.jobs)

    @property
    def rows(self) -> int:
        return (
            len(self.meta)
            + len(self.instances)
            + len(self.parts)
            + len(self.diagnostics)
            + len(self.alarms)
            + len(self.audit)
            + len(self.appended)
            + len(self.jobs)
        )


@dataclass(slots=True)
class LoadReport:
    """What ``load`` found: the saved mode, whether the last run ended cleanly, and notes
    (a chart changed since: what was carried over and what was not)."""

    mode: str = ""
    clean: bool = False
    last_restart: str = ""
    changed: list[int] = field(default_factory=list)
    """Instance DBs whose FB changed since the file was written (carried over)."""
    notes: list[str] = field(default_factory=list)
    stopped: str = ""
    """Why the last run went to STOP by an error, read back from its diagnostic buffer
    (``engine.diag_events.last_error_stop``); empty when it did not."""


_MODES: Final = frozenset(str(m) for m in CpuMode)


def _saved_report(store: StateStore) -> LoadReport:
    """What the file says of the last run — its mode, whether it ended cleanly, its last
    restart — each a value this code writes; StateFileError naming the key otherwise (a
    file someone edited is not trusted for what it says)."""
    mode, clean = store.meta("mode") or "", store.meta("clean")
    if mode and mode not in _MODES:
        raise StateFileError(store.path, f"malformed meta 'mode': {mode[:40]!r}")
    if clean not in (None, "0", "1"):
        raise StateFileError(store.path, f"malformed meta 'clean': {clean[:40]!r}")
    return LoadReport(mode=mode, clean=clean == "1", last_restart=store.meta("last_restart") or "")


def _volatile(value: object) -> tuple[str, ...]:
    names = getattr(type(value), "VOLATILE", ())
    return tuple(names) if isinstance(names, tuple) else ()


def _take_volatile(idb: InstanceDB, snapshot: dict[str, object]) -> dict[str, object]:
    """Take the ``VOLATILE`` keys of each OBJECT value out of ``snapshot`` (in place):
    object name → {key: value}."""
    taken: dict[str, object] = {}
    for name in idb.fb.objects:
        value = idb.values[name]
        keys = _volatile(value)
        state = snapshot.get(name)
        if not keys or not isinstance(state, dict):
            continue
        if state is value:  # an object without to_state: never change it
            state = snapshot[name] = dict(state)
        part = {key: state.pop(key) for key in keys if key in state}
        if part:
            taken[name] = part
    return taken


def _json_row(snapshot: dict[str, object], volatile: dict[str, object]) -> tuple[bytes, bytes]:
    """(what is compared, what is stored) of a snapshot MessagePack cannot hold (an integer
    beyond 64 bits): its JSON without the volatile keys, and with them put back."""
    key = _dumps(snapshot).encode()
    for name, part in volatile.items():
        state = snapshot[name]
        if isinstance(state, dict) and isinstance(part, dict):
            state.update(part)
    return key, _dumps(snapshot).encode()


class StateStore:
    """One SQLite file holding a CPU's state, its alarm log and its audit log.

    Opening checks the file (``StateFileError``); ``load`` restores a CPU from it, both on a
    read-only connection to a file that was there; ``open_writing`` (or the first
    ``write``) opens it for writing; ``stage`` and ``write`` keep it up to date; ``save``
    does both at once."""

    def __init__(
        self,
        path: Path | str,
        *,
        interval_ms: float | None = None,
        hot: bool = False,
        time_mark_ms: float | None = TIME_MARK_MS,
        synchronous: str = SYNCHRONOUS,
        program: Program | None = None,
    ) -> None:
        self.path = Path(path)
        self.hot = hot
        self.program = program
        """The program the file belongs to: ``load`` refuses another's, writing records it
        (None: neither; ``engine/state_identity.py``)."""
        if synchronous not in ("EXTRA", "FULL", "NORMAL", "OFF"):
            raise ValueError(f"synchronous must be EXTRA, FULL, NORMAL or OFF, not {synchronous!r}")
        self.synchronous = synchronous
        self.time_mark_ns = None if time_mark_ms is None else int(time_mark_ms * 1_000_000)
        """While only ``VOLATILE`` keys change (step times running), their row is written
        at most this often: what a restart can lose of a running step time."""
        """Also keep what only a hot restart needs (non-retentive M/T/C, the output image):
        written when it changes, which a warm restart would clear anyway."""
        self.interval_ns = None if interval_ms is None else int(interval_ms * 1_000_000)
        existed = self.path.exists()
        _check_path(self.path, existed)
        self.renew_hooks: list[RenewHooks] = []
        """Other users of the file, told when it is built anew (``renew``)."""
        self.made_private = False
        """Others could read the file as it was found: it was made its owner's alone (when
        it was opened for writing)."""
        self._db, self._held, self._made_shm = _opened(self.path, existed, synchronous)
        self._writing = not existed  # an existing file: read-only until ``open_writing``
        self._drop_hot = False  # the hot restart image to delete once writing
        if self._writing:
            self._idents()
            _stamp(self._db, program)
        self._lock: Any = _NoLock()  # a writer's lock once one is attached (use_lock)
        self._parts: dict[str, tuple[Callable[[], object], Callable[[Any], None]]] = {}
        self._part_seen: dict[str, object] = {}
        self._seen: dict[int, tuple[bytes, dict[str, object], FB]] = {}
        """Each instance DB as last staged: its encoded snapshot without the volatile keys,
        those, and its FB (an online change makes a new one: the row is written again,
        with the new fingerprint, even when its data did not change)."""
        self._shapes: dict[int, tuple[FB, str]] = {}
        self._meta_seen: dict[str, str] = {}
        self._images_seen: dict[str, dict[str, Any]] = {}  # the memory images last staged
        self._marked_ns: int | None = None
        self._last_ns: int | None = None
        self._diag_saved = 0
        self._diag_seq = self._next_diag_seq()
        self._logs = Batch()
        self.alarm_limit = ALARM_ROWS
        """Message events kept in ``alarms``; older ones are summed into ``alarm_summary``
        (``engine/rollup.py``) in the transaction that adds the one over the limit."""
        self._alarm_rows = _count(self._db, "alarms")
        self.deferred = False
        """Set by a writer: ``log_*`` rows wait for the next ``stage`` instead of being
        written at once, so they commit with the scan's state (and off the scan thread)."""
        self.saves = 0

    def _next_diag_seq(self) -> int:
        if "diagnostics" not in _tables(self._db):  # a file from before: read as it is
            return 0
        row = self._db.execute("SELECT MAX(seq) FROM diagnostics").fetchone()
        return 0 if row is None or row[0] is None else int(row[0]) + 1

    def diagnostics_saved(self) -> int:
        """The number of the next diagnostics row: every entry below it is in the file."""
        return self._next_diag_seq()

    def close(self) -> None:
        self._db.close()
        if self._made_shm and not self._writing:  # read only: nothing of it left beside the file
            _drop_shm(self.path, self._held)
        _let_go(self._held)  # after the connection: closing a descriptor drops its locks
        self._held = None

    def open_writing(self) -> None:
        """Open the file, read-only since it was recognised (and loaded), for writing: the
        tables and columns this code writes added, the format mark, the hot restart image
        a warm run does not keep deleted, the file made its owner's alone. Done by the
        first ``write`` at the latest; ``StateFileError`` (a full disk, a read-only folder).
        Until then a file that is refused is left as it was found, byte for byte."""
        if not self._writing:
            _for_writing(self)

    def use_lock(self, lock: Any) -> None:
        """The writer's lock guards the queued log rows (``log_*`` from other threads)."""
        self._lock = lock

    def has_state(self) -> bool:
        return self.meta("memory") is not None

    def add_part(
        self, name: str, snapshot: Callable[[], object], restore: Callable[[Any], None]
    ) -> None:
        """Persist ``snapshot()`` (JSON-able plain data) under ``name`` with the state;
        ``load`` hands it back to ``restore``. Register before ``load``. A ``snapshot``
        returning the very same object as last time is taken as unchanged."""
        self._parts[name] = (snapshot, restore)

    # ---- staging: what changed since the last stage -------------------------------------

    def stage(
        self, cpu: Cpu, *, upto: int = 0, full: bool = False, defer: bool = False
    ) -> Batch | None:
        """The rows that changed since the last ``stage`` (all of them with ``full``), as a
        batch marked ``upto``; None when nothing changed. Call in the scan thread, between
        scans: it reads the CPU's state without locking it.

        ``defer`` (not with ``full``): the instance DBs — most of the work for large charts
        — are left in ``Batch.unencoded``, to be encoded (``encode_next``) by another
        thread while the scan thread idles, never while a scan runs; the batch is returned
        as long as any is left."""
        batch = Batch(upto=upto)
        with self._lock:
            logs, self._logs = self._logs, Batch()
        batch.merge(logs)
        batch.upto = upto
        meta = {
            "mode": str(cpu.mode),
            "last_restart": str(cpu.last_restart or ""),
            "hot_blockers": _dumps(sorted(cpu.hot_blockers - _NOT_KEPT)),
            "forces": _dumps(cpu.forces.snapshot()) if cpu.forces else "[]",
        }
        for key, value in meta.items():
            if full or self._meta_seen.get(key) != value:
                batch.meta[key] = value
        self._meta_seen.update(batch.meta)
        images = {"memory": cpu.mem.snapshot}
        if self.hot:
            images["hot_memory"] = cpu.mem.hot_snapshot
        for key, take in images.items():
            image = take()  # strings, integers and booleans: compared as they are, dumped
            if full or self._images_seen.get(key) != image:  # only when they changed
                batch.meta[key] = _dumps(image)
                self._images_seen[key] = image
        now = cpu.process_ns()
        mark = full or (
            self.time_mark_ns is not None
            and (self._marked_ns is None or now - self._marked_ns >= self.time_mark_ns)
        )
        if defer and not full:
            batch.unencoded = list(cpu.instance_dbs.items())
            batch.time_mark, batch.staged_ns = mark, now
        else:
            for number, idb in cpu.instance_dbs.items():
                self._stage_instance(number, idb, batch, full, mark)
            if batch.instances or self._marked_ns is None:
                self._marked_ns = now
        for name, (snap, _) in self._parts.items():
            data = snap()
            seen = self._part_seen.get(name, _UNSEEN)
            if full or (data is not seen and data != seen):
                batch.parts[name] = _dumps(data)
                self._part_seen[name] = data
        new = cpu.diagnostics.since(self._diag_saved)
        # the row of entry number N is N - 1; entries that left the ring before they were
        # staged leave their numbers unused
        self._diag_seq = max(self._diag_seq, cpu.diagnostics.total - len(new))
        for e in new:
            batch.diagnostics.append(self.diagnostic_row(e))
        self._diag_saved = cpu.diagnostics.total
        if not batch:
            return None
        if full:
            batch.meta["cycle"] = str(cpu.cycle)
            batch.full = True
        return batch

    def encode_next(self, batch: Batch) -> bool:
        """Encode the first of ``batch.unencoded`` into ``batch.instances`` if it changed
        (as ``stage`` does without ``defer``); whether any is left. Never while a scan runs:
        the rows must hold the state of the scan they were staged after."""
        if batch.unencoded:
            number, idb = batch.unencoded.pop(0)
            self._stage_instance(number, idb, batch, False, batch.time_mark)
            if not batch.unencoded and (batch.instances or self._marked_ns is None):
                self._marked_ns = batch.staged_ns
        return bool(batch.unencoded)

    def _stage_instance(
        self, number: int, idb: InstanceDB, batch: Batch, full: bool, mark: bool
    ) -> None:
        fb = idb.fb
        snapshot = idb.snapshot(live=True)  # read where it is: encoded before anything runs
        volatile = _take_volatile(idb, snapshot)
        row: bytes | None = None
        try:
            key = _PACK.encode(snapshot)
        except (OverflowError, TypeError):
            key, row = _json_row(snapshot, volatile)
        seen = self._seen.get(number)
        if (
            not full
            and seen is not None
            and key == seen[0]
            and seen[2] is fb
            and not (mark and volatile != seen[1])
        ):
            return  # unchanged, or only its volatile keys and no time mark due
        if row is None:
            row = _PAIR + key + _PACK.encode(volatile)
        self._seen[number] = (key, volatile, fb)
        shape = self._shapes.get(number)
        if shape is None or shape[0] is not fb:
            fmt = fb.state_format
            shape = self._shapes[number] = (fb, _dumps(fmt.shape() if fmt is not None else None))
        batch.instances[number] = (fb.label, fb.name, fingerprint_of(fb), shape[1], row)

    def diagnostic_row(self, entry: DiagEntry) -> DiagRow:
        """The diagnostics row of ``entry``, numbered next (``stage``; the runner's last
        word when the scan hangs, written outside it)."""
        seq = self._diag_seq
        self._diag_seq += 1
        return diag_row(seq, entry)

    def maybe_save(self, cpu: Cpu) -> bool:
        """Stage and write at once if something changed (and the interval has passed)."""
        now = cpu.process_ns()
        if (
            self.interval_ns is not None
            and self._last_ns is not None
            and now - self._last_ns < self.interval_ns
        ):
            return False
        batch = self.stage(cpu)
        if batch is None:
            return False
        self.write(batch)
        self._last_ns = now
        return True

    def save(self, cpu: Cpu, *, clean: bool | None = None, before: Batch | None = None) -> None:
        """Write everything now (at startup and on stop); ``clean`` marks whether the run
        ended cleanly (True at a shutdown, False while running). A clean end writes the
        hot-restart image too: S7-400 may restart hot after a STOP by hand."""
        batch = self.stage(cpu, full=True) or Batch()
        if before is not None:  # rows a writer could not write (``StoreWriter.left``)
            before.merge(batch)
            batch = before
        if clean is not None:
            batch.meta["clean"] = "1" if clean else "0"
        if clean and not self.hot:  # a clean STOP allows a manual hot restart (as on S7-400)
            batch.meta["hot_memory"] = _dumps(cpu.mem.hot_snapshot())
        batch.full = True
        try:
            self.write(batch)
        except StateWriteError as exc:
            if not exc.renew:
                raise
            note = self.renew(batch, exc.problem)
            cpu.diagnostics.record(cpu.clock.now_ns(), EventId.STATE_RENEWED, "", note)

    # ---- writing ---------------------------------------------------------------------------

    def write(self, batch: Batch) -> None:
        """Commit ``batch`` as one transaction; ``StateWriteError`` names the first error
        (``renew`` set when the file was deleted, replaced or damaged: ``renew``)."""
        if not batch:
            return
        if not self._writing:
            try:
                _for_writing(self)
            except StateFileError as exc:
                raise StateWriteError(self.path, exc.problem) from None
        lost = gone(self.path, self._files)
        if lost is not None:
            raise StateWriteError(self.path, lost[0], renew=lost[1])
        self._alarm_rows = self._commit(self._db, batch)
        self.saves += 1
        lost = gone(self.path, self._files)  # gone while it was committed
        if lost is not None:
            raise StateWriteError(self.path, lost[0], renew=lost[1], committed=True)

    def _commit(self, db: sqlite3.Connection, batch: Batch) -> int:
        """``batch`` as one transaction on ``db``; the rows the alarm log holds then."""
        try:
            db.execute("BEGIN IMMEDIATE")
            if batch.meta:
                db.executemany("INSERT OR REPLACE INTO meta VALUES (?, ?)", batch.meta.items())
            if batch.instances:
                db.executemany(
                    "INSERT OR REPLACE INTO instances VALUES (?, ?, ?, ?, ?, ?)",
                    [(n, *row[:4], _compress(row[4])) for n, row in batch.instances.items()],
                )
            if batch.parts:
                db.executemany("INSERT OR REPLACE INTO parts VALUES (?, ?)", batch.parts.items())
            if batch.diagnostics:
                db.executemany(
                    f"INSERT OR REPLACE INTO diagnostics ({', '.join(_DIAG_COLUMNS)}) "
                    "VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?)",
                    batch.diagnostics,
                )
            if batch.alarms:
                db.executemany(
                    f"INSERT INTO alarms ({', '.join(_ALARM_COLUMNS)}) "
                    "VALUES (?, ?, ?, ?, ?, ?, ?)",
                    batch.alarms,
                )
            if batch.audit:
                db.executemany(
                    "INSERT INTO audit (t_ns, user, action, detail) VALUES (?, ?, ?, ?)",
                    batch.audit,
                )
            for (table, columns), rows in _grouped(batch.appended).items():
                marks = ", ".join("?" * len(columns))
                db.executemany(f"INSERT INTO {table} ({', '.join(columns)}) VALUES ({marks})", rows)
            for job in batch.jobs:
                _run_job(db, job)
            alarms = self._bound_alarms(db, batch)
            db.execute("COMMIT")
        except sqlite3.Error as exc:
            if db.in_transaction:
                with contextlib.suppress(sqlite3.Error):  # the first error is the one to name
                    db.execute("ROLLBACK")
            code = int(getattr(exc, "sqlite_errorcode", 0) or 0) & 0xFF
            name = getattr(exc, "sqlite_errorname", "")
            problem = f"{exc} ({name})" if name else str(exc)
            if code in _DAMAGED:
                problem = f"the file was damaged while the CPU ran: {problem}"
            raise StateWriteError(
                self.path, problem, busy=code in _BUSY, renew=code in _DAMAGED
            ) from None
        return alarms

    def renew(self, batch: Batch, why: str) -> str:
        """Build the file anew after ``why`` (``engine/renew.py``) with ``batch``, which must
        hold a whole staging (``stage(full=True)``) and every row still waiting; what
        happened, in words. ``StateWriteError`` when it cannot be built."""
        return _renewed(self, batch, why)

    def _idents(self) -> None:
        """Remember which files the connection writes (``engine/renew.py``, ``gone``)."""
        self._files = known(self.path)

    def _bound_alarms(self, db: sqlite3.Connection, batch: Batch) -> int:
        """Roll the oldest message events into ``alarm_summary`` if ``batch`` takes the log
        over ``alarm_limit`` (in its transaction); the rows the log holds then."""
        added = len(batch.alarms) + sum(1 for row in batch.appended if row[0] == "alarms")
        rows = self._alarm_rows + added
        if added and rows > self.alarm_limit:
            rows -= roll_alarms(db, low_water(self.alarm_limit))
        return rows

    def meta(self, key: str) -> str | None:
        """The ``meta`` value of ``key`` (None: none); StateFileError if not UTF-8 text."""
        return _meta(self._db, self.path, key)

    # ---- loading ---------------------------------------------------------------------------

    def load(self, cpu: Cpu) -> LoadReport | None:
        """Restore memory, instance DBs, diagnostics and the registered parts into a
        STOPped CPU; None when the file holds no state yet. ``StateFileError`` when it
        holds a state this CPU cannot trust (see the module docstring), SQLite's own
        errors reading it included."""
        try:
            return _load(self, cpu)
        except sqlite3.DatabaseError as exc:
            raise _unreadable(self.path, exc) from None

    # ---- alarms and audit (hooks for sfb/alarms.py and the web commands) ---------------------

    def _log(self, table: str, row: tuple[Any, ...]) -> None:
        if self.deferred:
            with self._lock:
                getattr(self._logs, table).append(row)
            return
        batch = Batch()
        getattr(batch, table).append(row)
        self.write(batch)

    def log_alarm(
        self,
        t_ns: int,
        key: str,
        state: str,
        text: str = "",
        user: str = "",
        cpu_ns: int | None = None,
        reason: str = "",
    ) -> None:
        self._log("alarms", (t_ns, key, state, text, user, cpu_ns, reason))

    def log_alarms(self, events: Iterable[object], wall_ns: int) -> int:
        """Append every message event among ``events`` (a ``ScanRecord.alarms``) at wall time
        ``wall_ns``: kind as state, the acknowledging user, the CPU clock's time, and the
        reason when a restart made it go. Returns how many were logged."""
        n = 0
        for e in events:
            if isinstance(e, AlarmEvent):
                reason = str(getattr(e, "reason", "") or "")
                self.log_alarm(wall_ns, str(e.msg_id), e.kind, e.text, e.user, e.t_ns, reason)
                n += 1
        return n

    def log_audit(self, t_ns: int, user: str, action: str, detail: str = "") -> None:
        self._log("audit", (t_ns, user, action, detail))

    def append(self, table: str, columns: tuple[str, ...], values: tuple[Any, ...]) -> bool:
        """Queue one row of an append-only table (``audit``, ``alarms``) to commit with the
        next scan's state — in the same transaction, so a durable mark covers it. False
        (nothing queued) when no writer defers the rows: the caller writes it itself."""
        if (table, columns) not in _APPENDED:  # checked once: a flood appends a row a command
            if table not in _APPENDABLE or not all(c.isidentifier() for c in columns):
                raise ValueError(f"cannot append to {table}({', '.join(columns)})")
            _APPENDED.add((table, columns))
        if len(columns) != len(values):
            raise ValueError(f"{len(columns)} columns, {len(values)} values")
        with self._lock:
            if not self.deferred:
                return False
            self._logs.appended.append((table, columns, values))
        return True

    def queue(self, job: Job) -> bool:
        """Queue ``job(connection)`` to run in the transaction of the next scan's state,
        after its rows (``StateStore.append``); an exception other than SQLite's undoes
        what the job did, nothing else. False (nothing queued) when no writer defers the
        rows: the caller runs it itself."""
        with self._lock:
            if not self.deferred:
                return False
            self._logs.jobs.append(job)
        return True

    def alarms(self) -> list[dict[str, Any]]:
        cur = self._db.execute(f"SELECT {', '.join(_ALARM_COLUMNS)} FROM alarms ORDER BY id")
        return [dict(zip(_ALARM_COLUMNS, r, strict=True)) for r in cur]

    def audit(self) -> list[dict[str, Any]]:
        cur = self._db.execute("SELECT t_ns, user, action, detail FROM audit ORDER BY id")
        return [dict(zip(("t_ns", "user", "action", "detail"), r, strict=True)) for r in cur]

    def instance_state(self, number: int) -> dict[str, Any] | None:
        """The stored snapshot of instance DB ``number`` as plain data (None if none), for
        tests and tools reading the file."""
        row = self._db.execute("SELECT data FROM instances WHERE number=?", (number,)).fetchone()
        return None if row is None else unpack_instance(row[0])


def _opened(
    path: Path, existed: bool, synchronous: str
) -> tuple[sqlite3.Connection, tuple[int, int] | None, bool]:
    """(the connection, the lock held, whether this connection made the ``-shm``) of a state
    file: a new one created and set up for writing; an existing one locked (``_hold``), then
    recognised (``_check_existing``) on a read-only connection — nothing written to it, no
    checkpoint of its write-ahead log, no ``-wal`` or ``-shm`` left beside it when it is
    refused. ``StateFileError`` when it is."""
    held: tuple[int, int] | None = None
    shm = Path(f"{path}-shm")
    had_shm = shm.exists()
    try:
        if existed:
            held = _hold(path)
            db = _reader(path)
        else:
            db = _connect(path)
    except sqlite3.Error as exc:
        _let_go(held)
        raise _unreadable(path, exc) from None
    try:
        if existed:
            _check_existing(db, path)
        else:
            held = _hold(path)
            _setup(db, synchronous, new=True)
            _make_private(path)
    except BaseException as exc:
        db.close()
        if existed and not had_shm:
            _drop_shm(path, held)
        _let_go(held)
        if isinstance(exc, (sqlite3.DatabaseError, UnicodeDecodeError)):
            raise _unreadable(path, exc) from None
        raise
    return db, held, existed and not had_shm and shm.exists()


def _reader(path: Path) -> sqlite3.Connection:
    """A read-only connection to ``path``; immutable when no ``-wal`` is beside it (nothing
    to read from one, and a read-only connection to a WAL file makes a ``-wal`` and a
    ``-shm`` it cannot remove), else reading the ``-wal`` too (it may make a ``-shm``:
    ``_drop_shm``)."""
    quiet = "" if Path(f"{path}-wal").exists() else "&immutable=1"
    uri = f"{path.absolute().as_uri()}?mode=ro{quiet}"  # a '?' or '#' in the path quoted
    return sqlite3.connect(
        uri, uri=True, check_same_thread=False, isolation_level=None, timeout=5.0
    )


def _drop_shm(path: Path, held: tuple[int, int] | None) -> None:
    """Remove the ``-shm`` a read-only connection made beside ``path`` (none was there),
    unless another store of this process still has the file open."""
    entry = _HELD.get(held) if held is not None else None
    if entry is None or entry[1] <= 1:
        with contextlib.suppress(OSError):
            os.unlink(f"{path}-shm")


def _for_writing(store: StateStore) -> None:
    """``StateStore.open_writing``: the read-only connection replaced by one that writes."""
    db = _connect(store.path)
    store._db.close()
    store._db = db
    try:
        _setup(db, store.synchronous, new=False)
        _stamp(db, store.program)
        if store._drop_hot:
            _drop_hot_image(db)
    except sqlite3.DatabaseError as exc:
        raise _unreadable(store.path, exc) from None
    store._writing = True
    store.made_private = _make_private(store.path)
    store._idents()  # the alarm rows were counted at open: nothing was written since


def _drop_hot_image(db: sqlite3.Connection) -> None:
    """A warm run does not keep the hot restart image up to date: it goes (a read-only
    file fails later, at the first write)."""
    with contextlib.suppress(sqlite3.Error):
        db.execute("DELETE FROM meta WHERE key='hot_memory'")


def _setup(db: sqlite3.Connection, synchronous: str, *, new: bool) -> None:
    """Set a file up for writing: WAL, ``synchronous``, the schema."""
    if new:
        db.execute("PRAGMA page_size=1024")  # a short row change writes one short page
    db.execute("PRAGMA journal_mode=WAL")
    db.execute(f"PRAGMA synchronous={synchronous}")  # FULL: fsync at every commit
    _schema(db)


def _tables(db: sqlite3.Connection) -> set[str]:
    return {r[0] for r in db.execute("SELECT name FROM sqlite_master WHERE type='table'")}


def _count(db: sqlite3.Connection, table: str) -> int:
    """The rows of ``table`` (0 when a file from before lacks it)."""
    if table not in _tables(db):
        return 0
    return int(db.execute(f"SELECT COUNT(*) FROM {table}").fetchone()[0])


def _schema(db: sqlite3.Connection) -> None:
    """The tables and columns this code writes (those missing added) and the format mark."""
    db.executescript(_SCHEMA)
    for table, added in (
        ("alarms", _ADDED_ALARM_COLUMNS),
        ("diagnostics", _ADDED_DIAG_COLUMNS),
    ):
        columns = {row[1] for row in db.execute(f"PRAGMA table_info({table})")}
        for column, decl in added:
            if column not in columns:  # a state file from before the column existed
                db.execute(f"ALTER TABLE {table} ADD COLUMN {column} {decl}")
    db.execute("INSERT OR REPLACE INTO meta VALUES ('format', ?)", (FORMAT,))


def _check_existing(db: sqlite3.Connection, path: Path) -> None:
    """``StateFileError`` for an existing file that is not a state file this code trusts."""
    tables = _tables(db)
    check = db.execute("PRAGMA quick_check").fetchone()
    if check is None or check[0] != "ok":
        raise StateFileError(path, f"damaged file ({check[0] if check else '?'})")
    if not tables:
        raise StateFileError(path, _NO_TABLES, way_out=_WAL_WAY_OUT.format(path))
    if unrecognised(tables):
        raise StateFileError(path, unrecognised(tables))
    if "instances" not in tables and _holds_state(db, tables):
        raise StateFileError(
            path,
            "the instances table is gone (the instance DBs, a sequencer's "
            "position among them): an incomplete state",
        )
    if "instances" in tables:
        columns = {r[1] for r in db.execute("PRAGMA table_info(instances)")}
        if "state" in columns:
            raise StateFileError(path, "written by an older s7graph (no fingerprints)")
    if "diagnostics" in tables:
        have = {r[1] for r in db.execute("PRAGMA table_info(diagnostics)")}
        added = dict(_ADDED_DIAG_COLUMNS)  # a file from before lacks these: read as defaults
        lacking = [c for c in _DIAG_COLUMNS if c not in have and c not in added]
        if lacking:
            raise StateFileError(path, f"the diagnostics table has no {', '.join(lacking)} column")
    if "meta" in tables:
        mark = _meta(db, path, "format")
        if mark is not None and mark not in READABLE:
            raise StateFileError(path, f"unknown format {mark!r}")


def unrecognised(tables: set[str]) -> str:
    """Why an SQLite file of ``tables`` is no s7graph state file, as ``s7graph run`` says it
    (no table at all; none a state file has ever had), or "" when it may be one."""
    if not tables:
        return _NO_TABLES
    return "" if tables & _OURS else "an SQLite file, but not an s7graph state file"


def _load(store: StateStore, cpu: Cpu) -> LoadReport | None:
    """``StateStore.load``, on the connection the file was recognised on (read-only until
    the store writes: a file refused here is left as it was found)."""
    problem = _foreign(store._db, store.path, store.program, cpu)
    if problem is not None and store.program is not None:
        raise StateFileError(store.path, problem, way_out=way_out(store.path, store.program))
    moved = renamed(store.program, recorded(store.meta)) if store.program is not None else None
    memory = store.meta("memory")
    tables = _tables(store._db)  # a file from before may lack some (added once writing)
    instances = (
        store._db.execute(
            "SELECT number, fb, name, fingerprint, shape, data FROM instances ORDER BY number"
        ).fetchall()
        if "instances" in tables
        else []
    )
    if memory is None and not instances:
        return None
    report = _saved_report(store)
    if memory is None:
        raise StateFileError(store.path, "no memory image (an incomplete state)")
    if moved is not None:  # a renamed source: its note first; no hot restart, as a download
        report.notes.append(moved)
    hot = store.meta("hot_memory")
    image = _checked(store.path, "memory image", memory, check_memory_image, cpu)
    if hot is not None:
        hot_image = _checked(store.path, "hot restart image", hot, check_hot_image, cpu)
        _restore_part(store.path, "hot restart image", lambda: cpu.mem.restore_hot(hot_image))
    else:
        cpu.hot_blockers.add("no hot restart image saved")
    _restore_part(store.path, "memory image", lambda: cpu.mem.restore(image))
    for number, label, name, fingerprint, shape, data in instances:
        _load_instance(store.path, cpu, int(number), label, name, fingerprint, shape, data, report)
    unsaved = _unsaved(cpu, {int(row[0]) for row in instances}, report)
    blockers = store.meta("hot_blockers")
    if blockers:
        _restore_part(
            store.path,
            "hot restart blockers",
            lambda: cpu.hot_blockers.update(str(b) for b in json.loads(blockers)),
        )
    forces = store.meta("forces")
    if forces is not None:
        _restore_part(
            store.path, "force table", lambda: cpu.forces.restore(json.loads(forces), cpu.mem)
        )
    saved = _saved_diagnostics(store._db, store.path, cpu.diagnostics.capacity)
    for entry in saved:
        cpu.diagnostics.add(entry)
    cpu.diagnostics.continue_from(store._diag_seq)  # numbered on from the last run's
    report.stopped = last_error_stop(saved) or ""
    stopped = stop_blocker(saved)
    if stopped is not None:
        cpu.hot_blockers.add(stopped)
    store._diag_saved = cpu.diagnostics.total
    parts = store._db.execute("SELECT name, state FROM parts") if "parts" in tables else []
    for part_name, state in parts:
        part = store._parts.get(str(part_name))
        if part is not None:
            _restore_part(
                store.path,
                f"part {part_name!r}",
                functools.partial(_restore_json, part[1], str(state)),
            )
    if not report.changed and not unsaved and moved is None:
        cpu.hot_blockers.discard("program download")  # the very program that was running
    if not store.hot:  # not kept up to date from now on: deleted once the store writes
        store._drop_hot = True
        if store._writing:
            _drop_hot_image(store._db)
    return report


def _stamp(db: sqlite3.Connection, program: Program | None) -> None:
    """Record ``program`` in the file (none: what it records stays)."""
    if program is not None:
        db.executemany(
            "INSERT OR REPLACE INTO meta VALUES (?, ?)",
            ((KIND_KEY, program.kind), (SOURCE_KEY, program.source)),
        )


def _foreign(db: sqlite3.Connection, path: Path, program: Program | None, cpu: Cpu) -> str | None:
    """Why the file is another program's than ``program`` (``state_identity.foreign``; None:
    it is not known to be, or no program was given); ``StateFileError`` when what it
    records is not what this code writes."""
    return _judged(db, path, program, cpu, foreign)


def _judged(
    db: sqlite3.Connection,
    path: Path,
    program: Program | None,
    cpu: Cpu,
    judge: Callable[[Program, Evidence], str | None],
) -> str | None:
    """``judge`` (``state_identity.foreign`` or ``beside``) of the file on ``db`` for
    ``program`` run on ``cpu``, on the ``Evidence`` of both: what the file records, the
    instance DBs it holds and the CPU's (None when no program was given);
    ``StateFileError`` when what it records is not what this code writes."""
    tables = _tables(db)
    kind, source = _meta(db, path, KIND_KEY), _meta(db, path, SOURCE_KEY)
    problem = malformed(kind, source)
    if problem is not None:
        raise StateFileError(path, problem)
    if program is None:
        return None
    rows = (
        db.execute("SELECT number, fb, name, fingerprint FROM instances ORDER BY number")
        if "instances" in tables
        else []
    )
    held = tuple(
        Held(int(n), str(fb), str(name), str(fp).startswith(CHART)) for n, fb, name, fp in rows
    )
    mine = (fingerprint_of(idb.fb) for idb in cpu.instance_dbs.values())
    seen = Evidence(
        saved=recorded({KIND_KEY: kind, SOURCE_KEY: source}.get),
        holds_state=_holds_state(db, tables) or bool(held),
        held=held,
        own=frozenset((n, idb.fb.label, idb.fb.name) for n, idb in cpu.instance_dbs.items()),
        has_chart=any(f.startswith(CHART) for f in mine),
    )
    return judge(program, seen)


def foreign_state(path: Path, program: Program, cpu: Cpu) -> str | None:
    """Why the state file at ``path`` is another program's than ``program``, read without
    changing it and without taking its lock (readers are not kept out); None when it is
    not known to be: no file, one of this program's, an older one that may be, or one that
    cannot be read (opening it to run says why)."""
    return _peek(path, lambda db: _foreign(db, path, program, cpu))


def state_beside(path: Path, program: Program, cpu: Cpu) -> str | None:
    """Whose state the file at ``path`` holds when ``program`` would carry it over and its
    instance DBs are ``program``'s (``state_identity.beside``: a file of a renamed source),
    read as ``foreign_state`` reads; None when it does not, or cannot be read."""
    return _peek(path, lambda db: _judged(db, path, program, cpu, beside))


def _peek(path: Path, read: Callable[[sqlite3.Connection], str | None]) -> str | None:
    """``read`` of the file at ``path`` on a read-only connection (``_reader``), nothing of
    it changed and its lock not taken; None when there is no file or it cannot be read."""
    if not path.is_file():
        return None
    had_shm = Path(f"{path}-shm").exists()
    try:
        db = _reader(path)
    except sqlite3.Error:
        return None
    try:
        return read(db)
    except (sqlite3.Error, StateFileError):
        return None
    finally:
        db.close()
        if not had_shm:  # one a reader of the -wal made: nothing of it left
            _drop_shm(path, None)


def _renewed(store: StateStore, batch: Batch, why: str) -> str:
    """``StateStore.renew``: the file rebuilt, the store's connection and lock moved to it,
    the other users told (``RenewHooks``)."""

    def release() -> None:
        for hooks in store.renew_hooks:
            hooks.release()
        store._db.close()
        _let_go(store._held)
        store._held = None

    def schema(db: sqlite3.Connection) -> None:
        _schema(db)
        _stamp(db, store.program)
        for hooks in store.renew_hooks:
            hooks.schema(db)

    try:
        aside, lost = rebuild(
            store._db,
            store.path,
            schema=schema,
            fill=lambda db: store._commit(db, batch),
            release=release,
        )
        store._db = _connect(store.path)
        store._db.execute("PRAGMA journal_mode=WAL")
        _make_private(store.path)
        store._db.execute(f"PRAGMA synchronous={store.synchronous}")
        store._held = _hold(store.path)
        store._idents()
        store._alarm_rows = _count(store._db, "alarms")  # what the new file could copy
    except (OSError, sqlite3.Error, StateFileError, StateWriteError) as exc:
        words = exc.problem if isinstance(exc, StateFileError | StateWriteError) else exc
        if isinstance(exc, OSError) and exc.strerror:
            words = exc.strerror
        raise StateWriteError(
            store.path, f"{why}, and a new state file could not be built: {words}"
        ) from None
    for hooks in store.renew_hooks:
        hooks.reopen()
    store.saves += 1
    kept = f"; what was at its path is kept as {', '.join(aside)}" if aside else ""
    unread = f"; not copied (unreadable): {', '.join(lost)}" if lost else ""
    return f"{why}: the state file was written anew from the running CPU{kept}{unread}"


def _connect(path: Path) -> sqlite3.Connection:
    return sqlite3.connect(path, check_same_thread=False, isolation_level=None, timeout=5.0)


def _make_private(path: Path) -> bool:
    """Keep the state file and its ``-wal`` and ``-shm`` to their owner (it holds the audit:
    who did what, from where): each that others may read is made mode 0600. Whether one
    was; ``StateFileError`` when one cannot be (another user's file)."""
    made = False
    for part in (path, Path(f"{path}-wal"), Path(f"{path}-shm")):
        try:
            mode = part.stat().st_mode
        except FileNotFoundError:
            continue
        if mode & 0o077:
            try:
                os.chmod(part, mode & 0o700)
            except OSError as exc:
                raise StateFileError(
                    path,
                    f"others may read {part.name}, and it cannot be made private: "
                    f"{exc.strerror or exc}",
                    way_out=f"run as its owner, or chmod 600 {part} as its owner",
                ) from None
            made = True
    return made


def not_a_state_file(path: Path) -> StateFileError | None:
    """Why what is at ``path`` cannot be a state file, told before SQLite opens it: a
    directory, an empty file (SQLite would take it for a new database); None for anything
    else, nothing there included. Its ``way_out`` when there is one besides starting anew
    (``--fresh``, a run's; none for an empty file). ``s7graph run`` and ``s7graph audit``
    refuse a path in these words."""
    if path.is_dir():
        return StateFileError(
            path,
            "a directory, not a state file",
            way_out="give --state the path of a file (or move the directory away)",
        )
    if path.is_file() and path.stat().st_size == 0:
        return StateFileError(path, "empty file (0 bytes), not a state file")
    return None


def _check_path(path: Path, existed: bool) -> None:
    """``StateFileError`` for what is at ``path`` before SQLite opens it: what is not a
    state file (``not_a_state_file``), or a write-ahead log without its file (deleted while
    a run wrote it: SQLite would start a new file beside it and the state in the log would
    be lost)."""
    refused = not_a_state_file(path) if existed else None
    if refused is not None:
        raise refused
    renewed = Path(f"{path}.renew")
    if not existed and renewed.is_file():
        raise StateFileError(
            path,
            f"missing, but {renewed.name} is there: the run that wrote it ended while it "
            "built the state file anew (engine/renew.py)",
            way_out=f"rename {renewed} to {path.name} (the state it was built with), or start "
            f"anew with --fresh",
        )
    wal = Path(f"{path}-wal")
    if not existed and wal.is_file() and wal.stat().st_size > 0:
        raise StateFileError(
            path,
            f"missing, but its write-ahead log {wal.name} is there: the state file was "
            "deleted (or moved) while a run wrote it, and the log alone cannot be read",
            way_out=f"put the file back beside {wal.name}, or start anew with --fresh "
            f"(keeps {wal.name} as {path}.old-N-wal)",
        )


class _NoLock:
    """The lock of a store nobody writes from another thread."""

    def __enter__(self) -> None:
        return None

    def __exit__(self, *exc: object) -> None:
        return None


class _Unseen:
    def __repr__(self) -> str:
        return "<unseen>"


_UNSEEN = _Unseen()


def _run_job(db: sqlite3.Connection, job: Job) -> None:
    """``job`` in a savepoint: its own failure (not the file's) undoes only its work."""
    db.execute("SAVEPOINT job")
    try:
        job(db)
    except sqlite3.Error:
        raise
    except Exception:
        db.execute("ROLLBACK TO job")
    db.execute("RELEASE job")


def _grouped(
    rows: list[tuple[str, tuple[str, ...], tuple[Any, ...]]],
) -> dict[tuple[str, tuple[str, ...]], list[tuple[Any, ...]]]:
    """Appended rows by table and columns, each group in the order queued."""
    out: dict[tuple[str, tuple[str, ...]], list[tuple[Any, ...]]] = {}
    for table, columns, values in rows:
        out.setdefault((table, columns), []).append(values)
    return out


def _restore_json(restore: Callable[[Any], None], text: str) -> None:
    restore(json.loads(text))


_PACK = msgspec.msgpack.Encoder(enc_hook=str)  # str for what it cannot encode, as _dumps
_UNPACK = msgspec.msgpack.Decoder()


_PAIR = b"\x92"
"""MessagePack's header of a two-element array: a format-4 row (a map never starts so)."""


def _compress(raw: bytes) -> bytes:
    return zlib.compress(raw, 1)  # level 1: half the time of 6, 3 % larger (bench/README.md)


def unpack_instance(blob: object) -> dict[str, Any]:
    """An instance snapshot from its stored row: compressed MessagePack (a format-4 pair,
    its volatile keys put back, or a format-3 map), or compressed JSON (format 2, and what
    MessagePack cannot hold), told apart by the first byte (a JSON object starts with
    ``{``, MessagePack never does)."""
    if not isinstance(blob, bytes):
        raise ValueError(f"the data is {type(blob).__name__}, not a compressed snapshot")
    raw = zlib.decompress(blob)
    data = json.loads(raw) if raw[:1] == b"{" else _UNPACK.decode(raw)
    if isinstance(data, list):
        data = _joined(data)
    if not isinstance(data, dict):
        raise ValueError("the data is not an object")
    return data


def _joined(pair: list[Any]) -> dict[str, Any]:
    """A format-4 row's snapshot with its volatile keys put back."""
    if len(pair) != 2 or not isinstance(pair[0], dict) or not isinstance(pair[1], dict):
        raise ValueError("the data is neither an object nor a pair of them")
    data: dict[str, Any] = pair[0]
    volatile: dict[str, Any] = pair[1]
    for name, part in volatile.items():
        state = data.get(name)
        if not isinstance(state, dict) or not isinstance(part, dict):
            raise ValueError(f"volatile keys of {name!r}, which holds no object state")
        state.update(part)
    return data


def _by_name(fb: FB, data: dict[str, object]) -> list[str]:
    """An FB whose interface changed: what restoring by name keeps and drops."""
    names = {v.name for v in fb.interface if v.decl is not Decl.TEMP}
    dropped = sorted(set(data) - names)
    added = sorted(names - set(data))
    for name in dropped:
        del data[name]
    notes = [f"interface changed; variables kept by name ({len(data)})"]
    if dropped:
        notes.append(f"dropped (no longer declared): {', '.join(dropped)}")
    if added:
        notes.append(f"new, at their initial values: {', '.join(added)}")
    return notes


def _restore_part(path: Path, what: str, restore: Callable[[], object]) -> None:
    """``restore()``; anything but a ``StateFileError`` it raises is a malformed ``what``."""
    try:
        restore()
    except StateFileError:
        raise
    except Exception as exc:
        raise StateFileError(path, f"malformed {what}: {_why(exc)}") from None


def _load_instance(
    path: Path,
    cpu: Cpu,
    number: int,
    label: str,
    name: str,
    fingerprint: str,
    shape: str,
    blob: bytes,
    report: LoadReport,
) -> None:
    """Restore instance DB ``number`` from its row (a changed FB's data carried over, noted
    in ``report``); ``StateFileError`` when the row cannot be trusted."""
    idb = cpu.instance_dbs.get(number)
    held = f"DB{number} holds an instance of {label} {name!r}"
    # a system block's instance the program no longer calls: kept, as S7 keeps DBs
    system = cpu.blocks.get(label)
    sfb = system if isinstance(system, FB) and system.kind is BlockKind.SFB else None
    if idb is None and sfb is not None and number not in cpu.mem.dbs:
        idb = cpu.create_instance_db(number, sfb)
    if idb is None:
        raise StateFileError(path, f"{held}, which this program does not have")
    fb = idb.fb
    if fb.label != label or fb.name != name:
        raise StateFileError(path, f"{held}, not of {fb.label} {fb.name!r}")
    try:
        data = unpack_instance(blob)
        described = json.loads(shape)
    except (ValueError, TypeError, zlib.error) as exc:
        raise StateFileError(path, f"malformed data of DB{number}: {_why(exc)}") from None
    if fingerprint == fingerprint_of(fb):
        _whole(path, number, fb, data)
    else:
        fmt = fb.state_format
        try:
            if fmt is not None:
                data, notes = fmt.adapt(described, data)
            else:
                notes = _by_name(fb, data)
        except (ValueError, KeyError, TypeError, IndexError) as exc:
            raise StateFileError(
                path,
                f"DB{number}: {fb.label} changed and its state cannot be carried over: {_why(exc)}",
            ) from None
        report.changed.append(number)
        report.notes.extend(f"DB{number} {fb.label} {fb.name!r}: {n}" for n in notes)
    _restore_part(path, f"state of DB{number}", lambda: idb.restore(data, strict=True))


def _whole(path: Path, number: int, fb: FB, data: dict[str, Any]) -> None:
    """A row written by this very FB holds every stored variable, its sequencer state too."""
    lacking = [v.name for v in fb.stored if v.name not in data]
    if lacking:
        what = " (its sequencer state)" if set(lacking) & set(fb.objects) else ""
        raise StateFileError(path, f"malformed state of DB{number}: no {', '.join(lacking)}{what}")


def _checked(
    path: Path, what: str, text: str, check: Callable[[object, Any], None], cpu: Cpu
) -> Any:
    """The JSON ``text`` of a memory image, checked (``engine/state_checks.py``)."""
    try:
        data = json.loads(text)
        check(data, cpu.mem)
    except ValueError as exc:
        raise StateFileError(path, f"malformed {what}: {_why(exc)}") from None
    return data


def _saved_diagnostics(db: sqlite3.Connection, path: Path, capacity: int) -> list[DiagEntry]:
    """The last ``capacity`` diagnostics rows as entries, oldest first; ``StateFileError``
    naming a row that is malformed (``engine/state_checks.py``)."""
    have = {r[1] for r in db.execute("PRAGMA table_info(diagnostics)")}
    if not have:
        return []
    added = dict(_ADDED_DIAG_COLUMNS)  # a file from before: their defaults (added once writing)
    columns = [c if c in have else added[c].rsplit(None, 1)[-1] for c in _DIAG_COLUMNS[1:]]
    rows = db.execute(
        f"SELECT seq, {', '.join(columns)} FROM diagnostics ORDER BY seq DESC LIMIT ?",
        (capacity,),
    ).fetchall()
    entries = []
    for row in reversed(rows):
        try:
            entries.append(diag_entry(tuple(row[1:])))
        except ValueError as exc:
            raise StateFileError(path, f"malformed diagnostics row {row[0]}: {exc}") from None
    return entries


def _meta(db: sqlite3.Connection, path: Path, key: str) -> str | None:
    """The ``meta`` value of ``key``, read as bytes so that one not UTF-8 is refused by its
    key (SQLite's own error names only the column)."""
    try:
        row = db.execute("SELECT CAST(value AS BLOB) FROM meta WHERE key=?", (key,)).fetchone()
    except sqlite3.OperationalError as exc:
        if str(exc) != "no such table: meta":  # a file from before without it: none
            raise
        return None
    if row is None:
        return None
    try:
        return bytes(row[0] or b"").decode()
    except UnicodeDecodeError:
        raise StateFileError(
            path, f"not a readable state file (meta {key!r} is not UTF-8 text)"
        ) from None


def _unsaved(cpu: Cpu, saved: set[int], report: LoadReport) -> list[int]:
    """The CPU's instance DBs the file holds no row of (new in the program): noted, at their
    initial values, and no hot restart (a download)."""
    unsaved = sorted(set(cpu.instance_dbs) - saved)
    for number in unsaved:
        fb = cpu.instance_dbs[number].fb
        report.notes.append(
            f"DB{number} {fb.label} {fb.name!r}: no state saved, at its initial values"
        )
        cpu.hot_blockers.add(f"no state saved for DB{number}")
    return unsaved


def _hold(path: Path) -> tuple[int, int] | None:
    """Take the file's lock for this process (an exclusive ``flock``, which SQLite's own
    locks neither use nor notice); StateFileError when another process holds it: two runs
    writing one state file. None where the file system has no such locks."""
    st = path.stat()
    key = (st.st_dev, st.st_ino)
    held = _HELD.get(key)
    if held is not None:  # another store of this process: the lock is ours already
        held[1] += 1
        return key
    fd = os.open(path, os.O_RDONLY | os.O_CLOEXEC)
    locked = try_lock(fd)
    if locked is not True:
        os.close(fd)  # before this store's connection has locked anything
        if locked is False:
            raise StateFileError(
                path, "in use by another process (another run holds it)", way_out=_IN_USE_WAY_OUT
            )
        return None
    _HELD[key] = [fd, 1]
    return key


def not_in_use(path: Path) -> None:
    """StateFileError when another process holds ``path``'s lock (a run on it): before
    ``--fresh`` moves the file aside, which would hand a running CPU's retentive memory to
    a second one. Nothing held after; no file, or no locks on the file system: fine."""
    try:
        fd = os.open(path, os.O_RDONLY | os.O_CLOEXEC)
    except OSError:
        return
    try:
        st = os.fstat(fd)
        if (st.st_dev, st.st_ino) in _HELD:
            return  # this process's own store
        if try_lock(fd) is False:
            raise StateFileError(
                path, "in use by another process (another run holds it)", way_out=_IN_USE_WAY_OUT
            )
    finally:
        os.close(fd)  # the lock, if taken, goes with it


def _let_go(key: tuple[int, int] | None) -> None:
    """One store of this process less on the file; the last one lets the lock go."""
    held = _HELD.get(key) if key is not None else None
    if key is not None and held is not None:
        held[1] -= 1
        if held[1] == 0:
            del _HELD[key]
            os.close(held[0])


def _unreadable(path: Path, exc: sqlite3.Error | UnicodeDecodeError) -> StateFileError:
    """The refusal of a file SQLite could not open: in use by another process (locked), or
    not readable."""
    code = int(getattr(exc, "sqlite_errorcode", 0) or 0) & 0xFF
    if code in _BUSY:
        return StateFileError(
            path, f"in use by another process ({exc}): it was not read", way_out=_IN_USE_WAY_OUT
        )
    if code in _DISK or (code == 0 and "unable to open" in str(exc)):
        if not path.parent.is_dir():
            return StateFileError(
                path,
                f"its folder {path.parent} does not exist",
                way_out="create the folder, or give --state a path in one that exists",
            )
        problem = _DISK.get(code, _DISK[14])
        return StateFileError(
            path,
            f"{problem} ({exc}): it was not read",
            way_out=_DISK_WAY_OUT.format(_DISK_FIX.get(code, "make it and its folder writable")),
        )
    return StateFileError(path, f"not a readable state file ({sqlite_words(exc)})")


def sqlite_words(exc: sqlite3.Error | UnicodeDecodeError) -> str:
    """SQLite's error in words, without the text it could not decode (it may be long and is
    not text): for every reader of a state file. SQLite's own message that is not UTF-8 (a
    damaged schema quoted in it) is said with the bytes it could not decode replaced."""
    if isinstance(exc, UnicodeDecodeError):
        return bytes(exc.object).decode("utf-8", "replace")
    text = str(exc)
    if text.startswith("Could not decode to UTF-8 column "):
        column = text.removeprefix("Could not decode to UTF-8 column ").split(" with text ")[0]
        return f"column {column} holds text that is not UTF-8"
    return text


def _holds_state(db: sqlite3.Connection, tables: set[str]) -> bool:
    """Whether the file's ``meta`` holds a saved state (a memory image)."""
    if "meta" not in tables:
        return False
    return db.execute("SELECT 1 FROM meta WHERE key='memory'").fetchone() is not None


def _why(exc: BaseException) -> str:
    """What went wrong, in words: the message without the exception's class, what kind of
    data it was not said where the message alone does not say it."""
    text = str(exc)
    if isinstance(exc, json.JSONDecodeError):
        text = f"not valid JSON ({exc})"
    elif isinstance(exc, msgspec.DecodeError):
        text = f"not valid MessagePack ({exc})"
    elif isinstance(exc, zlib.error):
        text = f"not compressed data ({exc})"
    elif isinstance(exc, KeyError) and exc.args:
        text = f"no {exc.args[0]!r}"
    return (text or "cannot be read")[:300]
