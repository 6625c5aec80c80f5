"""The audit trail and the alarm history in the CPU's SQLite state file.

Every command a CPU receives, applied or refused, is one row of the ``audit`` table: wall
time, user (as established: ``alice``, ``bob (unverified)``; ``(unauthenticated)`` for a
refusal of a sender the CPU did not authenticate), role, origin (page, shell, bus peer),
op, FB, arguments (JSON), outcome (``applied``/``refused``) and reason; ``claimed``, the
name an unauthenticated sender gave — a claim, never in the user column, so nobody can
make rows appear under another's name. The table is the one ``engine.persistence`` has
always had (``t_ns, user, action, detail``); the new columns are added to a file from
before, whose rows then read as applied. The alarm history is the last rows of the
``alarms`` table, which the runner appends every message event to (came, went,
acknowledged, with the user). Tokens and passwords are never arguments: the gate passes
only a command's ``args``.

**Committed with the state.** Given the run's ``StateStore``, the store numbers each row
itself and, while the store's writer runs, queues it there (``StateStore.append``): the row
commits in the same transaction as the next scan's state — the effect of the command it
records — off the scan thread, so a durable mark covers both and a slow disk never holds a
scan up. Without a writer (before the run starts, after it ends) a row is written at once.

The store has its own connection to the file (WAL), so the zenoh threads that answer
queries never touch the scan thread's.

**A count, and a bound.** A row's ``count`` says how many commands it stands for: 1, or
for refusals of senders the CPU did not authenticate, every one of a minute from one
source for one reason (``web/access/tally.py``; the count is set by a job, ``queue``, that
the state writer runs with a later scan's state). The table keeps at most ``max_rows`` rows
and ``max_bytes`` of text (``AUDIT_ROWS``, ``AUDIT_BYTES``); the row that takes it over
queues a roll-up of the oldest rows into ``audit_summary`` — per UTC day, user, op and
outcome: the count and the first and last time, refusals of unauthenticated senders under
``UNAUTHENTICATED`` — in the same transaction (``engine/rollup.py``): the trail loses
detail, never a count. Rows of refusal windows still counting are not rolled.
"""

from __future__ import annotations

import contextlib
import dataclasses
import json
import operator
import sqlite3
import threading
import time
import urllib.parse
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Final, TypeVar

from s7graph.engine.persistence import RenewHooks, sqlite_words, unrecognised
from s7graph.engine.rollup import Job, day_of, low_water, roll
from s7graph.engine.state_checks import stored_integer

if TYPE_CHECKING:
    from s7graph.engine.persistence import StateStore

__all__ = [
    "AUDIT_BYTES",
    "AUDIT_ROWS",
    "UNAUTHENTICATED",
    "AlarmRecord",
    "AuditRecord",
    "AuditStore",
    "Facts",
    "NotAStateFile",
    "SummaryRecord",
    "UnreadableAudit",
    "read_audit",
    "read_summary",
    "write_count",
]

AUDIT_ROWS: Final = 100_000
"""The most rows the ``audit`` table keeps; older ones are summed into ``audit_summary``."""
AUDIT_BYTES: Final = 64 * 1024 * 1024
"""The most text (``row_size``: its characters + 64 a row) the table keeps: 100,000 rows of
4 KiB arguments would be 400 MB."""
UNAUTHENTICATED: Final = "(unauthenticated)"
"""The user of the summary's rows for refusals of senders the CPU did not authenticate: the
names they gave are claims (the rows they came from had them)."""

_NEW_COLUMNS: Final = (
    ("role", "TEXT NOT NULL DEFAULT ''"),
    ("origin", "TEXT NOT NULL DEFAULT ''"),
    ("fb", "TEXT NOT NULL DEFAULT ''"),
    ("args", "TEXT NOT NULL DEFAULT ''"),
    ("outcome", "TEXT NOT NULL DEFAULT 'applied'"),
    ("reason", "TEXT NOT NULL DEFAULT ''"),
    ("count", "INTEGER NOT NULL DEFAULT 1"),
    ("claimed", "TEXT NOT NULL DEFAULT ''"),
)
_CREATE: Final = """
CREATE TABLE IF NOT EXISTS audit (
    id INTEGER PRIMARY KEY AUTOINCREMENT, t_ns INTEGER, user TEXT, action TEXT, detail TEXT);
CREATE TABLE IF NOT EXISTS alarms (
    id INTEGER PRIMARY KEY AUTOINCREMENT, t_ns INTEGER, key TEXT, state TEXT, text TEXT,
    user TEXT NOT NULL DEFAULT '', cpu_ns INTEGER);
CREATE TABLE IF NOT EXISTS audit_summary (
    day TEXT NOT NULL, user TEXT NOT NULL, op TEXT NOT NULL, outcome TEXT NOT NULL,
    count INTEGER NOT NULL, first_ns INTEGER NOT NULL, last_ns INTEGER NOT NULL,
    PRIMARY KEY (day, user, op, outcome));
"""
_AUDIT_COLUMNS: Final = (
    "id",
    "t_ns",
    "user",
    "role",
    "origin",
    "action",
    "fb",
    "args",
    "outcome",
    "reason",
    "detail",
    "count",
    "claimed",
)
_ACKED: Final = (
    "action = 'ack_msg' AND outcome = 'applied' AND "
    "CASE WHEN json_valid(args) THEN json_type(args, '$.comment') END = 'text'"
)
"""SQL of the rows that gave a message its comment or emptied it: applied ``ack_msg`` rows
with a ``comment`` text (arguments cut short, no JSON, never match)."""
_ACKED_MSG: Final = "CASE WHEN json_valid(args) THEN json_extract(args, '$.msg_id') END"
_ACKED_INDEX: Final = (
    f"CREATE INDEX IF NOT EXISTS audit_acked ON audit({_ACKED_MSG}, id) WHERE {_ACKED}"
)
"""Those rows by message, so :meth:`AuditStore.acked` reads the index, not the table."""
_DEFAULTS: Final = {"outcome": "'applied'", "count": "1"}
"""What a column missing from an older file reads as (others: '')."""
_ALWAYS: Final = ("id", "t_ns", "user", "action", "detail")
"""The audit table's columns since the first state file: a table without one is not ours."""
_TEXT: Final = ("user", "role", "origin", "action", "fb", "args", "reason", "detail", "claimed")
_SIZE: Final = "64 + " + " + ".join(f"length(ifnull({c}, ''))" for c in _TEXT)
"""SQL of ``row_size``."""
_SUMMARY_NUMBERS: Final = ("count", "first_ns", "last_ns")
_T = TypeVar("_T")
_SUMMARY_KEYS: Final = {
    "day": day_of("t_ns"),
    "user": f"CASE WHEN outcome = 'refused' AND role = '' THEN '{UNAUTHENTICATED}' "
    "ELSE ifnull(user, '') END",
    "op": "ifnull(action, '')",
    "outcome": "outcome",
}


@dataclass(frozen=True, slots=True)
class AuditRecord:
    """One audit row."""

    id: int
    t_ns: int
    user: str
    role: str
    origin: str
    op: str
    fb: str
    args: str
    outcome: str
    reason: str
    detail: str = ""
    count: int = 1
    """How many commands the row stands for: 1, or the refusals an aggregated row counts."""
    claimed: str = ""
    """The name an unauthenticated sender gave (its ``user`` is ``UNAUTHENTICATED``): a
    claim nobody proved; "" for every row of a proven author."""


def row_size(r: AuditRecord) -> int:
    """What a row weighs against ``max_bytes``: the characters of its text, plus 64."""
    text = (r.user, r.role, r.origin, r.op, r.fb, r.args, r.reason, r.detail, r.claimed)
    return 64 + sum(map(len, text))


@dataclass(frozen=True, slots=True)
class Facts:
    """What one audit row says about one command (the store adds the id and the time)."""

    user: str
    role: str
    origin: str
    op: str
    fb: str
    args: Mapping[str, object]
    applied: bool
    reason: str = ""
    detail: str = ""
    claimed: str = ""
    """The name an unauthenticated sender gave (``web.bus.gate.unproven_author``)."""

    def at(self, row_id: int, t_ns: int, *, text: int = 4096) -> AuditRecord:
        """The row, its fields cut to their column sizes (arguments, reason and detail to
        ``text`` characters) and the arguments as JSON."""
        args = json.dumps(dict(self.args), sort_keys=True, default=str)[:text]
        outcome = "applied" if self.applied else "refused"
        return AuditRecord(
            row_id,
            t_ns,
            self.user[:80],
            self.role[:16],
            self.origin[:160],
            self.op[:32],
            self.fb[:64],
            args,
            outcome,
            self.reason[:text],
            self.detail[:text],
            claimed=self.claimed[:80],
        )


@dataclass(frozen=True, slots=True)
class AlarmRecord:
    """One message event of the alarm history."""

    id: int
    t_ns: int
    msg_id: str
    state: str
    text: str
    user: str


@dataclass(frozen=True, slots=True)
class SummaryRecord:
    """Audit rows rolled into the summary: one UTC day, user, op and outcome."""

    day: str
    user: str
    op: str
    outcome: str
    count: int
    first_ns: int
    last_ns: int


def _migrate(db: sqlite3.Connection) -> None:
    db.executescript(_CREATE)
    have = {row[1] for row in db.execute("PRAGMA table_info(audit)")}
    for column, decl in _NEW_COLUMNS:
        if column not in have:  # a state file from before the column existed
            db.execute(f"ALTER TABLE audit ADD COLUMN {column} {decl}")
    with contextlib.suppress(sqlite3.OperationalError):  # an SQLite without JSON: none
        db.execute(_ACKED_INDEX)


def _connect(target: Path | str, *, uri: bool = False) -> sqlite3.Connection:
    """A connection of the store (WAL, synced as the state store's: durable commits)."""
    db = sqlite3.connect(
        target, check_same_thread=False, isolation_level=None, timeout=5.0, uri=uri
    )
    db.execute("PRAGMA journal_mode=WAL")
    db.execute("PRAGMA synchronous=FULL")
    return db


def _last_id(db: sqlite3.Connection) -> int:
    """The highest audit row id ever given (AUTOINCREMENT never reuses one)."""
    row = db.execute("SELECT MAX(id) FROM audit").fetchone()
    last = int(row[0] or 0) if row is not None else 0
    seq = db.execute("SELECT seq FROM sqlite_sequence WHERE name='audit'").fetchone()
    return max(last, int(seq[0] or 0) if seq is not None else 0)


class UnreadableAudit(Exception):
    """A state file whose audit cannot be read (``read_audit``, ``read_summary``): ``path``
    and ``problem``, in words."""

    def __init__(self, path: Path, problem: str) -> None:
        self.path = path
        self.problem = problem
        super().__init__(f"{path}: not a state file s7graph can read the audit of ({problem})")


class NotAStateFile(UnreadableAudit):
    """An SQLite file ``s7graph run`` would not recognise as a state file, said as it says
    it (``engine.persistence.unrecognised``)."""

    def __str__(self) -> str:
        return f"{self.path}: {self.problem}"


def _tables(db: sqlite3.Connection, path: Path | str) -> set[str]:
    """The tables of a state file; ``NotAStateFile`` when it is not one."""
    tables = {r[0] for r in db.execute("SELECT name FROM sqlite_master WHERE type='table'")}
    problem = unrecognised(tables)
    if problem:
        raise NotAStateFile(Path(path), problem)
    return tables


def _audit_rows(
    db: sqlite3.Connection, where: str, params: tuple[object, ...]
) -> list[AuditRecord]:
    """The audit rows ``where`` selects; ValueError when the table is not the one s7graph
    writes (a column it always had missing, a row that is not typed as written)."""
    have = {row[1] for row in db.execute("PRAGMA table_info(audit)")}
    lacking = [c for c in _ALWAYS if c not in have]
    if lacking:
        raise ValueError(f"its audit table has no column {', '.join(lacking)}")
    cols = ", ".join(c if c in have else _DEFAULTS.get(c, "''") for c in _AUDIT_COLUMNS)
    rows = db.execute(f"SELECT {cols} FROM audit {where}", params).fetchall()
    return [_record(r) for r in rows]


def _record(r: tuple[object, ...]) -> AuditRecord:
    """An ``AuditRecord`` of a row of ``_AUDIT_COLUMNS`` (an older file's NULLs as '');
    ValueError naming the row and column when a number is not an integer or a text is a
    blob."""
    row_id = stored_integer(r[0], "id", "audit row")
    where = f"audit row {row_id}"
    texts = (*r[2:-2], r[-1])  # every column but id, t_ns and count
    for name, v in zip((*_AUDIT_COLUMNS[2:-2], _AUDIT_COLUMNS[-1]), texts, strict=True):
        if isinstance(v, bytes):
            raise ValueError(f"{where}: {name} is a blob, not text")
    text = [str(v or "") for v in texts]
    user, role, origin, op, fb, args, outcome, reason, detail, claimed = text
    return AuditRecord(
        row_id,
        stored_integer(r[1] if r[1] is not None else 0, "t_ns", where),
        user,
        role,
        origin,
        op,
        fb,
        args,
        outcome,
        reason,
        detail,
        stored_integer(r[-2] if r[-2] is not None else 1, "count", where),
        claimed,
    )


def _summary_rows(db: sqlite3.Connection, path: Path | str = "") -> list[SummaryRecord]:
    """The summary's rows; with ``path``, ``NotAStateFile`` when the file is not a state
    file."""
    tables = (
        _tables(db, path)
        if path
        else {r[0] for r in db.execute("SELECT name FROM sqlite_master WHERE type='table'")}
    )
    if "audit_summary" not in tables:
        return []
    rows = db.execute(
        "SELECT day, user, op, outcome, count, first_ns, last_ns FROM audit_summary "
        "ORDER BY day, first_ns, user, op, outcome"
    ).fetchall()
    out = []
    for r in rows:
        where = f"audit_summary row of {r[0]!r}"
        numbers = [
            stored_integer(v, n, where) for v, n in zip(r[4:], _SUMMARY_NUMBERS, strict=True)
        ]
        out.append(SummaryRecord(str(r[0]), str(r[1]), str(r[2]), str(r[3]), *numbers))
    return out


def write_count(db: sqlite3.Connection, r: AuditRecord) -> None:
    """Set the count of row ``r.id`` — and the fields an aggregated row may have changed
    (``*`` once its refusals differed in them) — to ``r``'s."""
    db.execute(
        "UPDATE audit SET count = ?, user = ?, origin = ?, action = ?, fb = ?, args = ?, "
        "reason = ?, claimed = ? WHERE id = ?",
        (r.count, r.user, r.origin, r.op, r.fb, r.args, r.reason, r.claimed, r.id),
    )


_ROW: Final = operator.attrgetter(*(f.name for f in dataclasses.fields(AuditRecord)))
"""An ``AuditRecord`` as the row of ``_AUDIT_COLUMNS``: ``dataclasses.astuple`` deep-copies
every field, half of what a command cost at the scan boundary (65 → 34 µs)."""


class AuditStore:
    """Append audit rows and read the audit trail and the alarm history of one state file;
    ``state``: the run's store, whose writer commits the rows with the scan's state;
    ``max_rows``/``max_bytes``: the bound of the table (module docstring)."""

    def __init__(
        self,
        path: Path | str,
        *,
        state: StateStore | None = None,
        max_rows: int = AUDIT_ROWS,
        max_bytes: int = AUDIT_BYTES,
    ) -> None:
        self.path = Path(path)
        self.state = state
        self.max_rows = max_rows
        self.max_bytes = max_bytes
        self.lock = threading.RLock()
        """Guards the store; ``web/access/tally.py`` counts under it too (one lock: no
        order to get wrong between the two). Never held while the file is read: the scan
        thread takes it for each command's row (``record``), and a read waiting for a slow
        disk would hold the scan up."""
        self._conn_lock = threading.Lock()
        """Guards the connection (taken after ``lock`` when both are)."""
        self._db = _connect(self.path)
        self._released = False
        if state is not None:  # the run's store may build the file anew: follow it
            state.renew_hooks.append(RenewHooks(_migrate, self._release, self._reopen))
        self._kept: set[int] = set()  # rows not to roll up (refusal windows still counting)
        self._rolling = False  # a roll-up is queued
        self.rolled = 0
        """Rows rolled into the summary since the store opened."""
        with self.lock:
            _migrate(self._db)
            self._last_id = _last_id(self._db)
            rows, size = self._db.execute(f"SELECT COUNT(*), SUM({_SIZE}) FROM audit").fetchone()
            self._rows, self._bytes = int(rows or 0), int(size or 0)

    def close(self) -> None:
        with self.lock, self._conn_lock:
            self._db.close()

    def _release(self) -> None:
        """The state file is built anew: let the old one go (closed last, a connection would
        delete the new file's ``-wal`` by name)."""
        with self._conn_lock:
            self._db.close()
            self._released = True

    def _reopen(self) -> None:
        with self._conn_lock:
            self._reader()

    def _reader(self) -> sqlite3.Connection:
        """The connection (``_conn_lock`` held): on the new state file if a renewal let the
        old one go (never creating a file where there is none)."""
        if self._released:
            where = urllib.parse.quote(str(self.path.resolve()))
            self._db = _connect(f"file:{where}?mode=rw", uri=True)
            self._released = False
        return self._db

    @property
    def deferred(self) -> bool:
        """Rows go to the run's writer (committed with a scan's state), not straight in."""
        return self.state is not None and self.state.deferred

    def record(self, t_ns: int, facts: Facts, *, text: int = 4096) -> AuditRecord:
        """Append one row and return it: queued to commit with the next scan's state while
        the run's writer runs, else written now. ``text``: see ``Facts.at``."""
        with self.lock:
            self._last_id += 1
            rec = facts.at(self._last_id, t_ns, text=text)
            values = _ROW(rec)
            if self.state is None or not self.state.append("audit", _AUDIT_COLUMNS, values):
                marks = ", ".join("?" * len(values))
                with self._conn_lock:
                    self._reader().execute(
                        f"INSERT INTO audit ({', '.join(_AUDIT_COLUMNS)}) VALUES ({marks})", values
                    )
            self._rows += 1
            self._bytes += row_size(rec)
            if not self._rolling and (self._rows > self.max_rows or self._bytes > self.max_bytes):
                self._rolling = True
                self.queue(self._roll)
        return rec

    def queue(self, job: Job) -> None:
        """Run ``job(connection)`` in the transaction of the next scan's state (the run's
        writer), or now in a transaction of its own."""
        with self.lock:
            if self.state is not None and self.state.queue(job):
                return
            with self._conn_lock:
                db = self._reader()
                db.execute("BEGIN IMMEDIATE")
                try:
                    job(db)
                except BaseException:
                    db.execute("ROLLBACK")
                    raise
                db.execute("COMMIT")

    def resized(self, delta: int) -> None:
        """A row's text changed by ``delta`` characters (an aggregated row's ``*``)."""
        with self.lock:
            self._bytes += delta

    def keep(self, row_id: int, kept: bool = True) -> None:
        """Whether row ``row_id`` is kept out of roll-ups (its count is still changing)."""
        with self.lock:
            if kept:
                self._kept.add(row_id)
            else:
                self._kept.discard(row_id)

    def _roll(self, db: sqlite3.Connection) -> None:
        """Sum the oldest rows into ``audit_summary`` until the table is a tenth below its
        bounds (a job: in the writer's transaction, after the rows it commits)."""
        with self.lock:
            rows, size, kept = self._rows, self._bytes, set(self._kept)
            self._rolling = False
        keep_rows, keep_bytes = low_water(self.max_rows), low_water(self.max_bytes)
        last, gone_rows, gone_bytes = None, 0, 0
        cursor = db.execute(f"SELECT id, {_SIZE} FROM audit ORDER BY id")
        for row_id, weight in cursor:
            if rows - gone_rows <= keep_rows and size - gone_bytes <= keep_bytes:
                break
            if row_id in kept:
                continue
            last, gone_rows, gone_bytes = row_id, gone_rows + 1, gone_bytes + int(weight)
        cursor.close()
        if last is None:
            return
        skip = sorted(k for k in kept if k < last)
        where = "id <= ?" + (f" AND id NOT IN ({', '.join('?' * len(skip))})" if skip else "")
        keys = _SUMMARY_KEYS
        rolled = roll(
            db, "audit", "audit_summary", keys, count="count", where=where, params=(last, *skip)
        )
        with self.lock:
            self._rows -= rolled
            self._bytes -= gone_bytes
            self.rolled += rolled

    def last(self, n: int = 50) -> list[AuditRecord]:
        """The last ``n`` audit rows, oldest first."""
        with self._conn_lock:
            rows = _audit_rows(self._reader(), "ORDER BY id DESC LIMIT ?", (max(n, 0),))
        return rows[::-1]

    def acked(self, n: int = 1000) -> list[AuditRecord]:
        """Of each message (of the ``n`` acknowledged last), the newest applied ``ack_msg``
        row that gave it a comment or emptied it, however old, oldest first: a read of the
        ``audit_acked`` index, not of the table. ``sqlite3.OperationalError`` from an
        SQLite without JSON functions."""
        newest = f"SELECT max(id) AS m FROM audit WHERE {_ACKED} GROUP BY {_ACKED_MSG}"
        where = f"WHERE id IN (SELECT m FROM ({newest}) ORDER BY m DESC LIMIT ?) ORDER BY id"
        with self._conn_lock:
            return _audit_rows(self._reader(), where, (max(n, 0),))

    def summary(self) -> list[SummaryRecord]:
        """The rows rolled into the summary, oldest day first."""
        with self._conn_lock:
            return _summary_rows(self._reader())

    def alarm_history(self, n: int = 200) -> list[AlarmRecord]:
        """The last ``n`` message events (came, went, acknowledged), oldest first."""
        with self._conn_lock:
            rows = (
                self._reader()
                .execute(
                    "SELECT id, t_ns, key, state, text, user FROM alarms ORDER BY id DESC LIMIT ?",
                    (max(n, 0),),
                )
                .fetchall()
            )
        return [
            AlarmRecord(
                int(r[0]), int(r[1] or 0), str(r[2]), str(r[3]), str(r[4] or ""), str(r[5] or "")
            )
            for r in reversed(rows)
        ]


_SQLITE_WORDS: Final = {
    11: "it is damaged: SQLite finds its pages malformed (truncated or overwritten?)",
    26: "it is not an SQLite database",
}
"""SQLite's primary error codes (``sqlite_errorcode & 0xFF``) a reader meets, in words."""


def _in_words(exc: sqlite3.Error) -> str:
    """What SQLite could not read, in words (never the bytes it could not decode)."""
    text = sqlite_words(exc)
    words = _SQLITE_WORDS.get(int(getattr(exc, "sqlite_errorcode", 0) or 0) & 0xFF)
    if words is not None:
        return words
    if text.startswith(("no such column", "no such table")):
        return f"its tables are not those s7graph writes ({text})"
    return text


_OPEN_TRIES: Final = 3
"""Tries to open a file a running CPU may be replacing (``engine/renew.py``: moved aside,
built anew) before its ``unable to open`` is the answer, 50 ms apart."""


def _reading(path: Path | str, read: Callable[[sqlite3.Connection], _T]) -> _T:
    """``read(connection)`` on the file opened read-only, so nothing in it changes; a file
    without a write-ahead log beside it (no run has it open) as immutable too, so none is
    left beside it either (a read-only connection to a WAL file makes an empty ``-wal`` and
    a ``-shm``, and cannot remove them). ``UnreadableAudit`` naming the file and, in words,
    what could not be read; a file that cannot be opened is tried again, in case a running
    CPU was replacing it."""
    for _ in range(_OPEN_TRIES - 1):
        try:
            return _read_once(path, read)
        except UnreadableAudit as exc:
            if "unable to open" not in exc.problem:
                raise
            time.sleep(0.05)
    return _read_once(path, read)


def _read_once(path: Path | str, read: Callable[[sqlite3.Connection], _T]) -> _T:
    quiet = "" if Path(f"{path}-wal").exists() else "&immutable=1"
    try:
        uri = f"{Path(path).absolute().as_uri()}?mode=ro{quiet}"  # a '?' or '#' in it quoted
        db = sqlite3.connect(uri, uri=True, timeout=5.0)
    except sqlite3.Error as exc:
        raise UnreadableAudit(Path(path), _in_words(exc)) from None
    try:
        return read(db)
    except sqlite3.Error as exc:
        raise UnreadableAudit(Path(path), _in_words(exc)) from None
    except UnicodeDecodeError:
        raise UnreadableAudit(Path(path), "it holds text that is not UTF-8") from None
    except ValueError as exc:
        raise UnreadableAudit(Path(path), str(exc)) from None
    finally:
        db.close()


def read_audit(path: Path | str, *, since_ns: int | None = None) -> list[AuditRecord]:
    """The audit rows of a state file (read-only; a file from before reads too);
    ``UnreadableAudit`` when it is not a state file whose audit can be read."""

    def read(db: sqlite3.Connection) -> list[AuditRecord]:
        if "audit" not in _tables(db, path):
            return []
        if since_ns is None:
            return _audit_rows(db, "ORDER BY id", ())
        return _audit_rows(db, "WHERE t_ns >= ? ORDER BY id", (since_ns,))

    return _reading(path, read)


def read_summary(path: Path | str) -> list[SummaryRecord]:
    """The audit rows a state file rolled into its summary (read-only; none in a file from
    before); ``UnreadableAudit`` when it is not a state file whose audit can be read."""
    return _reading(path, lambda db: _summary_rows(db, path))


def lines(records: Iterable[AuditRecord]) -> list[str]:
    """Audit rows as text lines (``s7graph audit``); a row that counts several refusals
    says how many (``refused ×1,234: …``); one of an unauthenticated sender the name it
    gave as a claim (``(unauthenticated) claiming "olga" (unproven) from …``)."""
    import time

    out = []
    for r in records:
        when = time.strftime("%Y-%m-%d %H:%M:%S", time.localtime(r.t_ns / 1e9))
        times = f" ×{r.count:,}" if r.count != 1 else ""
        verdict = f"{r.outcome}{times}" if r.outcome == "applied" else f"refused{times}: {r.reason}"
        args = "" if r.args in ("", "{}") else f" {r.args}"
        fb = f" {r.fb}" if r.fb else ""
        who = f"{r.user} ({r.role})" if r.role else r.user
        if r.claimed:
            who += f' claiming "{r.claimed}" (unproven)'
        origin = f" from {r.origin}" if r.origin else ""
        detail = f" - {r.detail}" if r.detail and r.outcome == "applied" else ""
        out.append(f"{when}  {who}{origin}: {r.op}{fb}{args}: {verdict}{detail}")
    return out


def summary_lines(records: Iterable[SummaryRecord]) -> list[str]:
    """Summary rows as text lines (``s7graph audit --summary``), times in UTC."""
    import time

    def hms(t_ns: int) -> str:
        return time.strftime("%H:%M:%S", time.gmtime(t_ns / 1e9))

    return [
        f"{r.day}  {r.user}: {r.op} {r.outcome} ×{r.count:,} "
        f"({hms(r.first_ns)}–{hms(r.last_ns)} UTC)"
        for r in records
    ]
