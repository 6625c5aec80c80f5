"""The audit trail and the alarm history in the CPU's SQLite state file.

Every command a CPU receives, applied or refused, is one row of the ``audit`` table: wall
time, user (as established: ``alice``, ``bob (unverified)``, ``?`` for a message nobody
could read), role, origin (page, shell, bus peer), op, FB, arguments (JSON), outcome
(``applied``/``refused``) and reason. The table is the one ``engine.persistence`` has
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
"""

from __future__ import annotations

import dataclasses
import json
import operator
import sqlite3
import threading
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Final

if TYPE_CHECKING:
    from s7graph.engine.persistence import StateStore

__all__ = ["AlarmRecord", "AuditRecord", "AuditStore", "Facts", "read_audit"]

_NEW_COLUMNS: Final = (
    ("role", "TEXT NOT NULL DEFAULT ''"),
    ("origin", "TEXT NOT NULL DEFAULT ''"),
    ("fb", "TEXT NOT NULL DEFAULT ''"),
    ("args", "TEXT NOT NULL DEFAULT ''"),
    ("outcome", "TEXT NOT NULL DEFAULT 'applied'"),
    ("reason", "TEXT NOT NULL DEFAULT ''"),
)
_CREATE: Final = """
CREATE TABLE IF NOT EXISTS audit (
    id INTEGER PRIMARY KEY AUTOINCREMENT, t_ns INTEGER, user TEXT, action TEXT, detail TEXT);
CREATE TABLE IF NOT EXISTS alarms (
    id INTEGER PRIMARY KEY AUTOINCREMENT, t_ns INTEGER, key TEXT, state TEXT, text TEXT,
    user TEXT NOT NULL DEFAULT '', cpu_ns INTEGER);
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
)


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

    def at(self, row_id: int, t_ns: int) -> AuditRecord:
        """The row, its fields cut to their column sizes and the arguments as JSON."""
        args = json.dumps(dict(self.args), sort_keys=True, default=str)[:4096]
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
            self.reason[:4096],
            self.detail[:4096],
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


def _migrate(db: sqlite3.Connection) -> None:
    db.executescript(_CREATE)
    have = {row[1] for row in db.execute("PRAGMA table_info(audit)")}
    for column, decl in _NEW_COLUMNS:
        if column not in have:  # a state file from before the column existed
            db.execute(f"ALTER TABLE audit ADD COLUMN {column} {decl}")


def _last_id(db: sqlite3.Connection) -> int:
    """The highest audit row id ever given (AUTOINCREMENT never reuses one)."""
    row = db.execute("SELECT MAX(id) FROM audit").fetchone()
    last = int(row[0] or 0) if row is not None else 0
    seq = db.execute("SELECT seq FROM sqlite_sequence WHERE name='audit'").fetchone()
    return max(last, int(seq[0] or 0) if seq is not None else 0)


def _audit_rows(
    db: sqlite3.Connection, where: str, params: tuple[object, ...]
) -> list[AuditRecord]:
    have = {row[1] for row in db.execute("PRAGMA table_info(audit)")}
    cols = ", ".join(
        c if c in have else "''" if c != "outcome" else "'applied'" for c in _AUDIT_COLUMNS
    )
    rows = db.execute(f"SELECT {cols} FROM audit {where}", params).fetchall()
    return [AuditRecord(int(r[0]), int(r[1] or 0), *(str(v or "") for v in r[2:])) for r in rows]


_ROW: Final = operator.attrgetter(*(f.name for f in dataclasses.fields(AuditRecord)))
"""An ``AuditRecord`` as the row of ``_AUDIT_COLUMNS``: ``dataclasses.astuple`` deep-copies
every field, half of what a command cost at the scan boundary (65 → 34 µs)."""


class AuditStore:
    """Append audit rows and read the audit trail and the alarm history of one state file;
    ``state``: the run's store, whose writer commits the rows with the scan's state."""

    def __init__(self, path: Path | str, *, state: StateStore | None = None) -> None:
        self.path = Path(path)
        self.state = state
        self._lock = threading.Lock()
        self._db = sqlite3.connect(
            self.path, check_same_thread=False, isolation_level=None, timeout=5.0
        )
        self._db.execute("PRAGMA journal_mode=WAL")
        self._db.execute("PRAGMA synchronous=FULL")  # as the state store: durable commits
        with self._lock:
            _migrate(self._db)
            self._last_id = _last_id(self._db)

    def close(self) -> None:
        with self._lock:
            self._db.close()

    def record(self, t_ns: int, facts: Facts) -> AuditRecord:
        """Append one row and return it: queued to commit with the next scan's state while
        the run's writer runs, else written now."""
        with self._lock:
            self._last_id += 1
            rec = facts.at(self._last_id, t_ns)
            values = _ROW(rec)
            if self.state is None or not self.state.append("audit", _AUDIT_COLUMNS, values):
                marks = ", ".join("?" * len(values))
                self._db.execute(
                    f"INSERT INTO audit ({', '.join(_AUDIT_COLUMNS)}) VALUES ({marks})", values
                )
        return rec

    def last(self, n: int = 50) -> list[AuditRecord]:
        """The last ``n`` audit rows, oldest first."""
        with self._lock:
            rows = _audit_rows(self._db, "ORDER BY id DESC LIMIT ?", (max(n, 0),))
        return rows[::-1]

    def alarm_history(self, n: int = 200) -> list[AlarmRecord]:
        """The last ``n`` message events (came, went, acknowledged), oldest first."""
        with self._lock:
            rows = self._db.execute(
                "SELECT id, t_ns, key, state, text, user FROM alarms ORDER BY id DESC LIMIT ?",
                (max(n, 0),),
            ).fetchall()
        return [
            AlarmRecord(
                int(r[0]), int(r[1] or 0), str(r[2]), str(r[3]), str(r[4] or ""), str(r[5] or "")
            )
            for r in reversed(rows)
        ]


def read_audit(path: Path | str, *, since_ns: int | None = None) -> list[AuditRecord]:
    """The audit rows of a state file (read-only; a file from before reads too)."""
    uri = f"file:{Path(path)}?mode=ro"
    db = sqlite3.connect(uri, uri=True, timeout=5.0)
    try:
        tables = {r[0] for r in db.execute("SELECT name FROM sqlite_master WHERE type='table'")}
        if "audit" not in tables:
            return []
        if since_ns is None:
            return _audit_rows(db, "ORDER BY id", ())
        return _audit_rows(db, "WHERE t_ns >= ? ORDER BY id", (since_ns,))
    finally:
        db.close()


def lines(records: Iterable[AuditRecord]) -> list[str]:
    """Audit rows as text lines (``s7graph audit``)."""
    import time

    out = []
    for r in records:
        when = time.strftime("%Y-%m-%d %H:%M:%S", time.localtime(r.t_ns / 1e9))
        verdict = r.outcome if r.outcome == "applied" else f"refused: {r.reason}"
        args = "" if r.args in ("", "{}") else f" {r.args}"
        fb = f" {r.fb}" if r.fb else ""
        who = f"{r.user} ({r.role})" if r.role else r.user
        origin = f" from {r.origin}" if r.origin else ""
        detail = f" - {r.detail}" if r.detail and r.outcome == "applied" else ""
        out.append(f"{when}  {who}{origin}: {r.op}{fb}{args}: {verdict}{detail}")
    return out
