"""The audit table is bounded by rows and by size: its oldest rows are summed into
``audit_summary`` in the transaction that takes it over, so every count is kept; the alarm
history is bounded the same way. Older state files open and get the new column and tables;
``s7graph audit`` shows counts and ``--summary`` the summary."""

from __future__ import annotations

import sqlite3
from pathlib import Path

import pytest

from s7graph.engine.persistence import StateStore
from s7graph.web.access.audit import (
    UNAUTHENTICATED,
    AuditStore,
    Facts,
    read_audit,
    read_summary,
    row_size,
)
from s7graph.web.access.login import Authenticator
from s7graph.web.bus.gate import Gate
from s7graph.web.bus.protocol import AuditEntry, Command, LoginRequest
from s7graph.web.cli.audit import audit_command
from s7graph.web.view.texts import audit_html

HOUR = 3600 * 10**9
T0 = 1_795_000_000 * 10**9


class Wall:
    def __init__(self) -> None:
        self.t_ns = T0

    def __call__(self) -> int:
        return self.t_ns


def applied(command: Command) -> tuple[bool, str]:
    return True, ""


def total(path: Path) -> int:
    """Every command the file accounts for: rows' counts and the summary's."""
    return sum(r.count for r in read_audit(path)) + sum(s.count for s in read_summary(path))


def test_the_table_rolls_its_oldest_rows_into_the_summary_with_every_count_kept(
    tmp_path: Path,
) -> None:
    path = tmp_path / "s.sqlite"
    wall = Wall()
    gate = Gate(Authenticator(None), AuditStore(path, max_rows=100), wall_ns=wall, flush_s=None)
    token = gate.login(LoginRequest(op="login", user="alice")).token
    sent = 1
    for hour in range(72):  # three days
        wall.t_ns = T0 + hour * HOUR
        for _ in range(20):
            gate.apply(Command(op="init", fb="FILL", user="alice", token=token), applied)
            gate.apply(Command(op="off", fb="FILL", user="eve", token="forged"), applied)
            sent += 2
        gate.flush()
        assert len(read_audit(path)) <= 100
        assert total(path) == sent
    summary = read_summary(path)
    assert {s.day for s in summary} >= {"2026-11-18", "2026-11-19"}
    assert {(s.user, s.op, s.outcome) for s in summary} == {
        ("alice (unverified)", "login", "applied"),
        ("alice (unverified)", "init", "applied"),
        (UNAUTHENTICATED, "off", "refused"),
    }
    first = min(s.first_ns for s in summary)
    assert first == T0 and all(s.first_ns <= s.last_ns for s in summary)


def test_the_table_is_bounded_by_size_too(tmp_path: Path) -> None:
    path = tmp_path / "s.sqlite"
    store = AuditStore(path, max_bytes=50_000)
    big = Facts("olga", "engineer", "shell", "save", "FILL", {"source": "x" * 5000}, True)
    for i in range(200):
        store.record(T0 + i, big)
        assert sum(row_size(r) for r in read_audit(path)) <= 50_000
    assert total(path) == 200 and store.rolled > 150
    store.close()


def test_a_window_still_counting_is_not_rolled_away(tmp_path: Path) -> None:
    path = tmp_path / "s.sqlite"
    wall = Wall()
    gate = Gate(Authenticator(None), AuditStore(path, max_rows=10), wall_ns=wall, flush_s=None)
    token = gate.login(LoginRequest(op="login", user="alice")).token
    gate.apply(Command(op="off", fb="FILL", user="eve", token="forged"), applied)
    for _ in range(50):
        gate.apply(Command(op="init", fb="FILL", user="alice", token=token), applied)
        gate.apply(Command(op="off", fb="FILL", user="eve", token="forged"), applied)
    gate.flush()
    window = [r for r in read_audit(path) if r.op == "off"]
    assert [r.count for r in window] == [51]
    wall.t_ns += 60 * 10**9  # the minute is over: the window closes, its row may go now
    gate.flush()
    for _ in range(10):
        gate.apply(Command(op="init", fb="FILL", user="alice", token=token), applied)
    assert [r for r in read_audit(path) if r.op == "off"] == []
    assert total(path) == 1 + 60 + 51


def test_an_older_state_file_without_the_count_column_opens_and_gets_it(tmp_path: Path) -> None:
    path = tmp_path / "s.sqlite"
    StateStore(path).close()
    db = sqlite3.connect(path)  # as the release before wrote it
    db.executescript(
        """
        DROP TABLE alarm_summary;
        ALTER TABLE audit ADD COLUMN role TEXT NOT NULL DEFAULT '';
        ALTER TABLE audit ADD COLUMN outcome TEXT NOT NULL DEFAULT 'applied';
        ALTER TABLE audit ADD COLUMN reason TEXT NOT NULL DEFAULT '';
        INSERT INTO audit (t_ns, user, action, detail, role, outcome, reason)
            VALUES (7, 'ann', 'ack', 'FB1', 'operator', 'refused', 'role');
        """
    )
    db.close()
    assert [(r.user, r.outcome, r.count) for r in read_audit(path)] == [("ann", "refused", 1)]
    assert read_summary(path) == []  # read-only: nothing added
    store = AuditStore(path, max_rows=2)
    columns = {r[1] for r in store._db.execute("PRAGMA table_info(audit)")}
    assert {"count", "origin", "fb", "args"} <= columns
    for user in ("bob", "carl"):
        store.record(9, Facts(user, "operator", "shell", "mode", "FB1", {}, True))
    assert [(s.user, s.op, s.count) for s in read_summary(path)] == [
        ("ann", "ack", 1),
        ("bob", "mode", 1),
    ]
    assert [(r.user, r.count) for r in read_audit(path)] == [("carl", 1)]
    store.close()
    state = StateStore(path)  # the engine's store adds its own table, once it writes
    state.open_writing()
    state.close()
    db = sqlite3.connect(path)
    assert db.execute("SELECT name FROM sqlite_master WHERE name='alarm_summary'").fetchone()
    db.close()


def test_the_alarm_history_is_bounded_too_its_oldest_events_summed_per_day(
    tmp_path: Path,
) -> None:
    store = StateStore(tmp_path / "s.sqlite")
    store.alarm_limit = 20
    for i in range(100):
        store.log_alarm(T0 + i * HOUR, f"M{i % 3}", "incoming" if i % 2 else "outgoing", "text")
        assert len(store.alarms()) <= 20
    rolled = store._db.execute("SELECT SUM(count), COUNT(DISTINCT day) FROM alarm_summary")
    count, days = rolled.fetchone()
    assert count + len(store.alarms()) == 100 and days >= 3
    assert AuditStore(store.path).alarm_history(5)[-1].t_ns == T0 + 99 * HOUR
    store.close()


def test_s7graph_audit_shows_counts_and_the_summary(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "s.sqlite"
    wall = Wall()
    gate = Gate(Authenticator(None), AuditStore(path, max_rows=3), wall_ns=wall, flush_s=None)
    for _ in range(1234):
        gate.apply(Command(op="off", fb="FILL", user="eve", token="forged"), applied)
    gate.flush()
    assert audit_command(path, None) == 0
    assert (
        '  (unauthenticated) claiming "eve" (unproven): off FILL: refused ×1,234: invalid token'
        in capsys.readouterr().out
    )
    wall.t_ns += 60 * 10**9
    gate.flush()
    for i in range(5):
        gate.login(LoginRequest(op="login", user=f"u{i}"))
    assert audit_command(path, None, summary=True) == 0
    out = capsys.readouterr().out
    assert f"2026-11-18  {UNAUTHENTICATED}: off refused ×1,234 (" in out
    assert audit_command(path, "2h", summary=True) == 2


def test_the_audit_panel_shows_the_count() -> None:
    entry = AuditEntry(id=1, t_ms=0, user="?", op="init", outcome="refused", reason="x", count=1234)
    assert "refused ×1,234: x" in audit_html([entry])
