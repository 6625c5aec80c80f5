"""Retentive state on disk: SQLite (DESIGN.md "Persistence"; SPEC.md §1.4).

Saved: retentive M/T/C and retain DBs (``Memory.snapshot()``), every instance DB
(``InstanceDB.snapshot()``, OBJECT values through ``to_state()``), the diagnostic buffer,
the restart type, and any extra named parts registered with ``add_part`` (the CPU's
message list: the engine does not know its type). ``maybe_save`` writes after each scan that
changed retentive data (or at most every ``interval_ms``); ``save`` on stop; all in one
transaction. A killed process comes back through ``load`` + warm restart with every
retentive value intact. Alarms (every message event, with the acknowledging user) and the
audit log (who acknowledged or downloaded what, when) are append-only tables.
"""

from __future__ import annotations

import json
import sqlite3
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any, Protocol, runtime_checkable

from s7graph.engine.cpu import Cpu
from s7graph.engine.record import DiagEntry

_SCHEMA = """
CREATE TABLE IF NOT EXISTS meta (key TEXT PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS instances (
    number INTEGER PRIMARY KEY, fb TEXT NOT NULL, state TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS diagnostics (
    seq INTEGER PRIMARY KEY, t_ns INTEGER, event_id INTEGER, block TEXT, message TEXT,
    address TEXT);
CREATE TABLE IF NOT EXISTS alarms (
    id INTEGER PRIMARY KEY AUTOINCREMENT, t_ns INTEGER, key TEXT, state TEXT, text TEXT,
    user TEXT NOT NULL DEFAULT '', cpu_ns INTEGER);
CREATE TABLE IF NOT EXISTS parts (name TEXT PRIMARY KEY, state TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS audit (
    id INTEGER PRIMARY KEY AUTOINCREMENT, t_ns INTEGER, user TEXT, action TEXT, detail TEXT);
"""


_ALARM_COLUMNS = ("t_ns", "key", "state", "text", "user", "cpu_ns")


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


class StateStore:
    """One SQLite file holding a CPU's retentive state, alarms and audit log."""

    def __init__(self, path: Path | str, *, interval_ms: float | None = None) -> None:
        self.path = Path(path)
        self.interval_ns = None if interval_ms is None else int(interval_ms * 1_000_000)
        self._db = sqlite3.connect(self.path, check_same_thread=False, isolation_level=None)
        self._db.execute("PRAGMA journal_mode=WAL")
        self._db.execute("PRAGMA synchronous=NORMAL")
        self._db.executescript(_SCHEMA)
        columns = {row[1] for row in self._db.execute("PRAGMA table_info(alarms)")}
        for column, decl in (("user", "TEXT NOT NULL DEFAULT ''"), ("cpu_ns", "INTEGER")):
            if column not in columns:  # a state file from before the column existed
                self._db.execute(f"ALTER TABLE alarms ADD COLUMN {column} {decl}")
        self._parts: dict[str, tuple[Callable[[], object], Callable[[Any], None]]] = {}
        self._parts_cache: tuple[tuple[int, ...], str, object] | None = None
        self._last: tuple[str, str, str] | None = None
        self._last_ns: int | None = None
        self._diag_saved = 0
        self.saves = 0

    def close(self) -> None:
        self._db.close()

    def has_state(self) -> bool:
        row = self._db.execute("SELECT 1 FROM meta WHERE key='memory'").fetchone()
        return row is not None

    def add_part(
        self, name: str, snapshot: Callable[[], object], restore: Callable[[Any], None]
    ) -> None:
        """Persist ``snapshot()`` (JSON-able plain data) under ``name`` with every save, in
        the same transaction; ``load`` hands it back to ``restore``. Register before ``load``.
        A ``snapshot`` returning the very same object as last time is not encoded again."""
        self._parts[name] = (snapshot, restore)

    def _state(self, cpu: Cpu) -> tuple[str, str, str]:
        memory = _dumps(cpu.mem.snapshot())
        inst = _dumps({str(n): [i.fb.label, i.snapshot()] for n, i in cpu.instance_dbs.items()})
        return memory, inst, self._parts_json()

    def _parts_json(self) -> str:
        snaps = [(name, snap()) for name, (snap, _) in self._parts.items()]
        ids = tuple(id(data) for _, data in snaps)
        if self._parts_cache is None or self._parts_cache[0] != ids:
            # the snapshots are kept alive with their ids, so an id cannot be reused
            self._parts_cache = (ids, _dumps(dict(snaps)), snaps)
        return self._parts_cache[1]

    def maybe_save(self, cpu: Cpu) -> bool:
        """Save if retentive data changed since the last save (and the interval has passed)."""
        now = cpu.process_ns()
        if (
            self.interval_ns is not None
            and self._last_ns is not None
            and now - self._last_ns < self.interval_ns
        ):
            return False
        state = self._state(cpu)
        if state == self._last and cpu.diagnostics.total == self._diag_saved:
            return False
        self._write(cpu, state)
        self._last_ns = now
        return True

    def save(self, cpu: Cpu) -> None:
        """Save unconditionally (on stop)."""
        self._write(cpu, self._state(cpu))

    def _write(self, cpu: Cpu, state: tuple[str, str, str]) -> None:
        memory, inst, parts = state
        db = self._db
        rows = json.loads(inst)
        part_rows = [(name, _dumps(data)) for name, data in json.loads(parts).items()]
        new_diag = cpu.diagnostics.since(self._diag_saved)
        first_seq = cpu.diagnostics.total - len(new_diag)
        db.execute("BEGIN")
        try:
            meta = {
                "memory": memory,
                "mode": str(cpu.mode),
                "cycle": str(cpu.cycle),
                "last_restart": str(cpu.last_restart or ""),
            }
            db.executemany("INSERT OR REPLACE INTO meta VALUES (?, ?)", meta.items())
            db.execute("DELETE FROM instances")
            db.executemany(
                "INSERT INTO instances VALUES (?, ?, ?)",
                [(int(n), label, _dumps(snap)) for n, (label, snap) in rows.items()],
            )
            db.executemany("INSERT OR REPLACE INTO parts VALUES (?, ?)", part_rows)
            db.executemany(
                "INSERT OR REPLACE INTO diagnostics VALUES (?, ?, ?, ?, ?, ?)",
                [
                    (first_seq + i, e.t_ns, e.event_id, e.block, e.message, e.address)
                    for i, e in enumerate(new_diag)
                ],
            )
            db.execute("COMMIT")
        except BaseException:
            db.execute("ROLLBACK")
            raise
        self._last = state
        self._diag_saved = cpu.diagnostics.total
        self.saves += 1

    def meta(self, key: str) -> str | None:
        row = self._db.execute("SELECT value FROM meta WHERE key=?", (key,)).fetchone()
        return None if row is None else str(row[0])

    def load(self, cpu: Cpu) -> bool:
        """Restore retentive memory, DBs, instance DBs, diagnostics and the registered parts
        into a STOPped CPU.

        Instance DBs are matched by number and FB label; returns False if the file is empty.
        """
        memory = self.meta("memory")
        if memory is None:
            return False
        cpu.mem.restore(json.loads(memory))
        for number, label, state in self._db.execute("SELECT number, fb, state FROM instances"):
            idb = cpu.instance_dbs.get(int(number))
            if idb is not None and idb.fb.label == label:
                idb.restore(json.loads(state))
        entries = self._db.execute(
            "SELECT t_ns, event_id, block, message, address FROM diagnostics ORDER BY seq"
        ).fetchall()
        for t_ns, event_id, block, message, address in entries[-cpu.diagnostics.capacity :]:
            cpu.diagnostics.add(DiagEntry(t_ns, event_id, block, message, address))
        self._diag_saved = cpu.diagnostics.total
        for name, state in self._db.execute("SELECT name, state FROM parts"):
            part = self._parts.get(str(name))
            if part is not None:
                part[1](json.loads(state))
        return True

    # ---- alarms and audit (hooks for sfb/alarms and the web commands) ---------------------

    def log_alarm(
        self,
        t_ns: int,
        key: str,
        state: str,
        text: str = "",
        user: str = "",
        cpu_ns: int | None = None,
    ) -> None:
        self._db.execute(
            "INSERT INTO alarms (t_ns, key, state, text, user, cpu_ns) VALUES (?, ?, ?, ?, ?, ?)",
            (t_ns, key, state, text, user, cpu_ns),
        )

    def log_alarms(self, events: Iterable[object], wall_ns: int) -> int:
        """Append every message event among ``events`` (a ``ScanRecord.alarms``) at wall time
        ``wall_ns``: kind as state, the acknowledging user, the CPU clock's time. Returns
        how many were logged."""
        rows = [
            (wall_ns, str(e.msg_id), e.kind, e.text, e.user, e.t_ns)
            for e in events
            if isinstance(e, AlarmEvent)
        ]
        if rows:
            self._db.executemany(
                "INSERT INTO alarms (t_ns, key, state, text, user, cpu_ns) "
                "VALUES (?, ?, ?, ?, ?, ?)",
                rows,
            )
        return len(rows)

    def log_audit(self, t_ns: int, user: str, action: str, detail: str = "") -> None:
        self._db.execute(
            "INSERT INTO audit (t_ns, user, action, detail) VALUES (?, ?, ?, ?)",
            (t_ns, user, action, detail),
        )

    def alarms(self) -> list[dict[str, Any]]:
        cur = self._db.execute(f"SELECT {', '.join(_ALARM_COLUMNS)} FROM alarms ORDER BY id")
        return [dict(zip(_ALARM_COLUMNS, r, strict=True)) for r in cur]

    def audit(self) -> list[dict[str, Any]]:
        cur = self._db.execute("SELECT t_ns, user, action, detail FROM audit ORDER BY id")
        return [dict(zip(("t_ns", "user", "action", "detail"), r, strict=True)) for r in cur]
